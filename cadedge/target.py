"""Target mode: a guaranteed arc-length deficit with close to the fewest segments.

1. :func:`cadedge.explore.explore` samples the curve densely enough that its Richardson length
   estimate is good to a small share of the target (``EXPLORE_SHARE``), catching features that
   chords miss, and finds the kinks a node must sit on.
2. Two placements compete for the fewest segments within the rest of the budget:
   continuous equidistribution of the deficit measure (:func:`cadedge.placement.equidistribute`,
   its count predicted by the cube law and corrected by measuring), and a choice among the dense
   samples (:func:`cadedge.placement.fewest_nodes`, no further evaluations). This is the paper's
   future-work global optimisation with a fixed point count, solved by equidistribution.
"""

from __future__ import annotations

import math

import numpy as np

from .explore import explore
from .placement import chord_length, deficit_measure, equidistribute, fewest_nodes

#: Share of the target deficit that the dense exploration may leave unresolved.
EXPLORE_SHARE = 1.0 / 16.0
#: Share of the target kept in reserve against error in the length estimate itself.
MARGIN = 0.03
#: Most placements measured while searching for the fewest equidistributed segments.
MAX_TRIALS = 10


def _evaluate_new(ev, u: np.ndarray, params: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points at ``params``, evaluating only those not already among the samples ``u``."""
    idx = np.clip(np.searchsorted(u, params), 0, len(u) - 1)
    known = u[idx] == params
    out = np.empty((len(params), 3))
    out[known] = points[idx[known]]
    if (~known).any():
        out[~known] = ev(params[~known])
    return out


def _equidistributed(ev, ex, corner_idx: np.ndarray, total: float, limit: float, budget: float,
                     min_segments: int) -> tuple[np.ndarray, np.ndarray] | None:
    """Fewest equidistributed segments whose deficit against ``total`` stays within ``limit``."""
    u, p, cum = ex.params, ex.points, ex.cumulative
    measure = deficit_measure(p, cum, corner_idx)
    m_tot = measure[-1]
    n = max(min_segments, math.ceil(math.sqrt(m_tot ** 3 / budget)) if budget > 0 and m_tot > 0 else min_segments)
    fixed = limit - budget  # the deficit no placement can remove (what the samples do not show)
    lo, hi = min_segments - 1, None  # lo: largest count known too few; hi: smallest known enough
    best = None
    for _ in range(MAX_TRIALS):
        params = equidistribute(u, cum, measure, n, corner_idx)
        pts = _evaluate_new(ev, u, params, p)
        miss = total - chord_length(pts, np.arange(len(pts)))
        # the cube law: the removable deficit falls with the square of the count
        predicted = math.ceil(n * math.sqrt(max(miss - fixed, 0.0) / budget)) if budget > 0 else n + 1
        if miss <= limit:
            hi, best = n, (params, pts)
            n = max(lo + 1, min(predicted, n - 1))
        else:
            lo = n
            n = max(n + 1, min(predicted, 2 * n))
            if hi is not None:
                n = min(n, hi - 1)
        if hi is not None and hi - lo <= 1:
            break
    return best


def refine_target(ev, a: float, b: float, *, ald: float, min_length: float | None = None,
                  max_length: float | None = None, search_tol: float | None = None
                  ) -> tuple[np.ndarray, np.ndarray, float, list[str]]:
    """Refine to ``ald``; returns (params, points, ald_estimate, notes).

    ``search_tol`` belongs to paper mode's golden-section search and does not apply here.
    """
    ex = explore(ev, a, b, ald * EXPLORE_SHARE)
    notes = list(ex.notes)
    total = ex.length_estimate
    u, p = ex.params, ex.points
    if not total > 0.0:
        notes.append(f"curve has zero length on [{a!r}, {b!r}] (all {len(u)} samples are one point); "
                     "returning its two ends")
        return np.array([a, b]), p[[0, -1]], 0.0, notes
    limit = ald * (1.0 - MARGIN) * total
    budget = max(limit - ex.remainder, 0.0)
    corner_idx = np.searchsorted(u, ex.corners) if len(ex.corners) else np.zeros(0, dtype=int)
    nodes = fewest_nodes(p, ex.cumulative, budget, min_length=min_length, max_length=max_length,
                         forced=corner_idx)
    params, points = u[nodes], p[nodes]
    if min_length is None and max_length is None:
        eq = _equidistributed(ev, ex, corner_idx, total, limit, budget, min_segments=len(corner_idx) + 1)
        if eq is not None and (len(eq[0]) < len(params) or (
                len(eq[0]) == len(params) and chord_length(eq[1], np.arange(len(eq[1]))) > chord_length(p, nodes))):
            params, points = eq
    length = chord_length(points, np.arange(len(points)))
    estimate = max(1.0 - length / total, 0.0)
    if estimate > ald:
        reason = "min_length" if min_length is not None else "the sampling cap"
        notes.append(f"ald target {ald:g} not reached (estimate {estimate:.3g}) because of {reason}")
    return params, points, estimate, notes
