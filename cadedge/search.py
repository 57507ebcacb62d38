"""Algorithm 1 of McLaurin & Shontz: the interior point that maximises a segment's two-chord length.

For a segment [ua, ub] with known end points P(ua), P(ub), find u in (ua, ub) maximising
``|P(ua) - P(u)| + |P(u) - P(ub)|`` by golden-section search: derivative-free, no differentiability
needed, one new curve evaluation per iteration (the surviving interior point is reused). Like any
golden-section search it finds *a* local maximum; on a multimodal segment it may miss the global one
(the paper's section 6 admits this).

:func:`golden_search` works on many segments at once (each iteration is one vectorised call of the
evaluator with one parameter per segment); :func:`best_split` is the one-segment convenience.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .errors import InputError

INV_PHI = (math.sqrt(5.0) - 1.0) / 2.0  # 0.618...: the golden ratio's reciprocal

DEFAULT_SEARCH_TOL = 1e-4
"""Final bracket width as a fraction of the segment's parameter width: 21 evaluations per search.
Reproduces all nine cells of the paper's tables (docs/paper.md) at under a fifth of its evaluations."""


def search_evaluations(tol: float) -> int:
    """Evaluations one search makes for relative tolerance ``tol``: the bracket after n evaluations
    is INV_PHI**(n - 1) of the segment's width, and it must reach ``tol``."""
    if not 0.0 < tol < 1.0:
        raise InputError(f"search_tol must be in (0, 1), got {tol!r}")
    return 1 + max(1, math.ceil(math.log(tol) / math.log(INV_PHI) - 1e-12))


def _two_chord(pa: np.ndarray, p: np.ndarray, pb: np.ndarray) -> np.ndarray:
    return np.linalg.norm(p - pa, axis=1) + np.linalg.norm(pb - p, axis=1)


def golden_search(ev: Callable[[np.ndarray], np.ndarray], ua: np.ndarray, ub: np.ndarray,
                  pa: np.ndarray, pb: np.ndarray, tol: float = DEFAULT_SEARCH_TOL
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Golden-section search on m segments at once.

    ``ua``, ``ub``: (m,) parameter ends (ua < ub); ``pa``, ``pb``: (m, 3) their points, already known.
    ``ev(u)`` returns (len(u), 3) points. The search stops when the bracket is at most ``tol`` times
    the segment's parameter width. Returns ``(u, p, two_chord)``: for each segment the best evaluated
    parameter, its point exactly as evaluated, and ``|pa - p| + |p - pb|``. ``u`` lies in [ua, ub]; it
    equals an end only when the segment is too narrow for floating point to hold an interior point.
    """
    ua = np.atleast_1d(np.asarray(ua, dtype=float))
    ub = np.atleast_1d(np.asarray(ub, dtype=float))
    pa = np.atleast_2d(np.asarray(pa, dtype=float))
    pb = np.atleast_2d(np.asarray(pb, dtype=float))
    n = search_evaluations(tol)
    lo, hi = ua.copy(), ub.copy()
    x1 = hi - INV_PHI * (hi - lo)
    x2 = lo + INV_PHI * (hi - lo)
    pts = ev(np.concatenate([x1, x2]))
    m = len(ua)
    p1, p2 = pts[:m], pts[m:]
    f1, f2 = _two_chord(pa, p1, pb), _two_chord(pa, p2, pb)
    first = f1 >= f2
    best_u = np.where(first, x1, x2)
    best_p = np.where(first[:, None], p1, p2)
    best_f = np.where(first, f1, f2)
    for _ in range(n - 2):
        left = f1 >= f2  # the maximum lies in [lo, x2]: x1 becomes the new x2
        hi = np.where(left, x2, hi)
        lo = np.where(left, lo, x1)
        new_u = np.where(left, hi - INV_PHI * (hi - lo), lo + INV_PHI * (hi - lo))
        new_p = ev(new_u)
        new_f = _two_chord(pa, new_p, pb)
        x2, p2, f2, x1, p1, f1 = (np.where(left, x1, new_u), np.where(left[:, None], p1, new_p),
                                  np.where(left, f1, new_f), np.where(left, new_u, x2),
                                  np.where(left[:, None], new_p, p2), np.where(left, new_f, f2))
        better = new_f > best_f
        best_u = np.where(better, new_u, best_u)
        best_p = np.where(better[:, None], new_p, best_p)
        best_f = np.where(better, new_f, best_f)
    return best_u, best_p, best_f


def best_split(ev: Callable[[np.ndarray], np.ndarray], ua: float, ub: float, pa: np.ndarray,
               pb: np.ndarray, tol: float = DEFAULT_SEARCH_TOL) -> tuple[float, np.ndarray, float]:
    """:func:`golden_search` for one segment: ``(u, point, two_chord_length)``."""
    u, p, f = golden_search(ev, np.array([ua]), np.array([ub]), np.asarray(pa, dtype=float)[None, :3],
                            np.asarray(pb, dtype=float)[None, :3], tol)
    return float(u[0]), p[0], float(f[0])
