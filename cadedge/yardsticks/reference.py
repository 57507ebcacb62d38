"""High-accuracy reference lengths for black-box curves, for tests and benchmarks (not the refiners).

Dense uniform polylines at n and 2n points, Richardson-extrapolated (the deficit of a smooth polyline
falls fourfold when its segments halve). The dense samples are also what the sampled optimum uses.
"""

from __future__ import annotations

import numpy as np

from ..curves import Evaluator, as_curve
from ..grid import polyline_length
from ..refine import resolve_domain


def reference_length(curve, domain: tuple[float, float] | None = None, n: int = 2 ** 20) -> float:
    """Length of ``curve`` on ``domain`` from ``n + 1`` uniform samples, Richardson-extrapolated.

    >>> from cadedge.yardsticks.analytic import circle
    >>> abs(reference_length(circle()) - 2 * np.pi) < 1e-10
    True
    """
    c = as_curve(curve, domain)
    a, b = resolve_domain(c, domain)
    pts = Evaluator(c)(np.linspace(a, b, n + 1))
    fine = polyline_length(pts)
    coarse = polyline_length(pts[::2])
    return fine + (fine - coarse) / 3.0
