"""Points against straight segments: the distance to each and where its foot lies, vectorised.

Shared by the thin-face widths (:mod:`cadedge.mesh.widths`) and the forced-angle reasons
(:mod:`cadedge.mesh.quality`), which both measure boundary polylines against points.
"""

from __future__ import annotations

import numpy as np


def segment_feet(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance from points ``p`` to segments ``a``-``b`` and the foot's parameter ``t`` in [0, 1] along
    each (0 at ``a``); the arrays broadcast against each other over all but their last axis (3).

    >>> d, t = segment_feet(np.array([[1.0, 1.0, 0.0]]), np.zeros((1, 3)), np.array([[4.0, 0.0, 0.0]]))
    >>> float(d[0]), float(t[0])
    (1.0, 0.25)
    """
    ab = b - a
    ap = p - a
    t = np.clip(np.einsum("...k,...k->...", ap, ab) / np.maximum(np.einsum("...k,...k->...", ab, ab), 1e-300),
                0.0, 1.0)
    return np.linalg.norm(ap - t[..., None] * ab, axis=-1), t
