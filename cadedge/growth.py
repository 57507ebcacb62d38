"""Growth-ratio control (paper section 7): split segments until neighbours differ by at most a ratio.

Only splitting, so the deficit can only fall. A segment is split at the point that halves its chord
(bisection on |P(u) - A| - |P(u) - B|, vectorised over all segments split in one pass), which keeps
halves even on badly parametrised curves.
"""

from __future__ import annotations

import numpy as np

MAX_PASSES = 64
BISECTION_STEPS = 8


def _norms(v: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("ij,ij->i", v, v))


def _halving_points(ev, ua: np.ndarray, ub: np.ndarray, pa: np.ndarray, pb: np.ndarray):
    lo, hi = ua.copy(), ub.copy()
    mid, pm = 0.5 * (lo + hi), None
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        pm = ev(mid)
        closer_to_a = _norms(pm - pa) < _norms(pb - pm)
        lo = np.where(closer_to_a, mid, lo)
        hi = np.where(closer_to_a, hi, mid)
    return mid, pm


def limit_growth(ev, params: np.ndarray, points: np.ndarray, max_growth: float, *,
                 min_length: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Split segments until every pair of neighbours has a length ratio of at most ``max_growth``."""
    u, p = np.asarray(params, dtype=float), np.asarray(points, dtype=float)
    for _ in range(MAX_PASSES):
        seg = _norms(np.diff(p, axis=0))
        if len(seg) < 2:
            break
        left, right = seg[:-1], seg[1:]
        with np.errstate(divide="ignore", invalid="ignore"):
            bad = np.maximum(left, right) > max_growth * np.minimum(left, right)
        if not bad.any():
            break
        k = np.flatnonzero(bad)
        longer = np.unique(np.where(left[k] >= right[k], k, k + 1))
        if min_length is not None:
            longer = longer[seg[longer] >= 2.0 * min_length]
        longer = longer[u[longer + 1] - u[longer] > 1e-12 * (u[-1] - u[0])]
        if not len(longer):
            break
        um, pm = _halving_points(ev, u[longer], u[longer + 1], p[longer], p[longer + 1])
        u = np.insert(u, longer + 1, um)
        p = np.insert(p, longer + 1, pm, axis=0)
    return u, p
