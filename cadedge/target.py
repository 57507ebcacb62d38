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

from .errors import InputError
from .explore import explore
from .grid import polyline_length, row_norms, unique_sorted
from .splitting import worst_growth
from .placement import chord_length, deficit_measure, equidistribute, fewest_nodes

#: Share of the target deficit that the dense exploration may leave unresolved.
EXPLORE_SHARE = 1.0 / 16.0
#: Share of the target kept in reserve against error in the length estimate itself.
MARGIN = 0.03
#: Share of the target kept in reserve when the curve knows its length (``exact_length(a, b)``, to about
#: 1e-9): only against that error, rounding and the snapping of the ends to B-rep vertices.
EXACT_MARGIN = 1e-3
#: How far (as a share of the target) the exploration's estimate may differ from a curve's own length
#: for that length to be used; past that the estimate and its margins are kept.
AGREEMENT = 0.25
#: Most placements measured while searching for the fewest equidistributed segments.
MAX_TRIALS = 10
#: Samples per max_length that a max_length placement can choose among.
MAX_LENGTH_SAMPLES = 8
#: Most segments ``max_length`` may force on one curve (each takes ``MAX_LENGTH_SAMPLES`` samples): past
#: that the option is refused up front instead of filling memory (1e-7 on a 100 mm edge asked for 8e9).
MAX_LENGTH_SEGMENTS = 200_000
#: Most re-placements along a graded size field for max_growth.
GRADING_PASSES = 4


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
        miss = total - polyline_length(pts)
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


def _graded(ev, ex, corner_idx: np.ndarray, params: np.ndarray, points: np.ndarray, growth: float,
            total: float, limit: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Re-place the grid so neighbouring segments differ by at most ``growth``, keeping the target.

    The size field h(s) = min over segments j of (l_j + alpha * arc distance to j), alpha just under
    growth - 1, is never above the grid's own sizes; nodes at equal steps of the integral of ds / h
    then have sizes that follow h, so neighbours differ by about 1 + alpha. Both running minima are
    prefix minima over the dense samples, so this is linear in their number.
    """
    u, cum = ex.params, ex.cumulative
    alpha = 0.75 * (growth - 1.0)
    s_nodes = np.interp(params, u, cum)
    seg = row_norms(np.diff(points, axis=0))
    seg_of = np.clip(np.searchsorted(s_nodes, cum, side="right") - 1, 0, len(seg) - 1)
    h = seg[seg_of].copy()
    # forward: segments ending at or before s; backward: segments starting at or after s
    ends, starts = s_nodes[1:], s_nodes[:-1]
    fwd_key = np.minimum.accumulate(seg - alpha * ends)
    k = np.searchsorted(ends, cum, side="right") - 1
    has = k >= 0
    h[has] = np.minimum(h[has], fwd_key[k[has]] + alpha * cum[has])
    bwd_key = np.minimum.accumulate((seg + alpha * starts)[::-1])[::-1]
    k = np.searchsorted(starts, cum, side="left")
    has = k < len(seg)
    h[has] = np.minimum(h[has], bwd_key[k[has]] - alpha * cum[has])
    h = np.maximum(h, 1e-300)
    inv = 1.0 / h
    measure = np.concatenate([[0.0], np.cumsum(0.5 * (inv[:-1] + inv[1:]) * np.diff(cum))])
    count = max(int(math.ceil(measure[-1] - 1e-9)), len(corner_idx) + 1)
    for _ in range(6):
        new = equidistribute(u, cum, measure, count, corner_idx)
        pts = _evaluate_new(ev, u, new, ex.points)
        if total - polyline_length(pts) <= limit:
            return new, pts
        count = int(math.ceil(count * 1.1)) + 1
    return None


def _densify(ev, ex, spacing: float):
    """The exploration with extra samples wherever two neighbours are more than ``spacing`` apart.

    A straight run is explored with its two ends only; a ``max_length`` placement needs samples
    along it to put nodes on.
    """
    gap = row_norms(np.diff(ex.points, axis=0))
    pieces = np.ceil(gap / spacing).astype(int)
    long_ = np.flatnonzero(pieces > 1)
    if not len(long_):
        return ex
    new = np.concatenate([np.linspace(ex.params[i], ex.params[i + 1], pieces[i] + 1)[1:-1] for i in long_])
    return ex.with_samples(new, ev(new))


def _sharp_nodes(points: np.ndarray, ald: float) -> np.ndarray:
    """Interior node indices whose polyline turns much more sharply than a smooth grid at ``ald`` would.

    A chord missing a share ``ald`` of a circular arc turns by about sqrt(24 ald) at each node;
    features (cusps, corners, narrow bumps) turn far more, and a re-placement must keep them.
    """
    d = np.diff(points, axis=0)
    n = np.linalg.norm(d, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.einsum("ij,ij->i", d[:-1], d[1:]) / (n[:-1] * n[1:])
    turn = np.arccos(np.clip(np.nan_to_num(cos, nan=1.0), -1.0, 1.0))
    return 1 + np.flatnonzero(turn > max(0.5, 3.0 * math.sqrt(24.0 * ald)))


def _grade(ev, ex, corner_idx, params, points, growth, ald, total, limit):
    """Graded re-placement keeping corners and sharp nodes, then bounded splitting for what is left."""
    from .splitting import limit_growth

    keep = _sharp_nodes(points, ald)
    if len(keep):  # make the sharp nodes samples (if they are not) and pin them like corners
        ex = ex.with_samples(params[keep], points[keep])
        corner_idx = unique_sorted(np.concatenate([np.searchsorted(ex.params, ex.corners),
                                               np.searchsorted(ex.params, params[keep])])).astype(int)
    for _ in range(GRADING_PASSES):  # each pass smooths the sizes of the one before
        graded = _graded(ev, ex, corner_idx, params, points, growth, total, limit)
        if graded is None:
            break
        params, points = graded
        if worst_growth(points) <= growth:
            return params, points
    params, points, _ = limit_growth(ev, params, points, growth)
    return params, points


def refine_target(ev, a: float, b: float, *, ald: float, min_length: float | None = None,
                  max_length: float | None = None, max_growth: float | None = None,
                  search_tol: float | None = None) -> tuple[np.ndarray, np.ndarray, float, list[str]]:
    """Refine to ``ald``; returns (params, points, ald_estimate, notes).

    With ``max_growth`` the nodes are re-placed along a graded size field (see :func:`_graded`), never
    coarser than the grid it grades, so the target still holds; a note says if a ratio is left over.
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
    if max_length is not None:
        if total / max_length > MAX_LENGTH_SEGMENTS:
            raise InputError(f"max_length {max_length:g} would split a curve {total:.6g} long into more than "
                             f"{MAX_LENGTH_SEGMENTS:,} segments, the cap per edge; use a larger max_length")
        ex = _densify(ev, ex, max_length / MAX_LENGTH_SAMPLES)
        u, p = ex.params, ex.points
    known = getattr(ev.curve, "exact_length", None)
    exact = known(a, b) if known is not None else None
    if exact is not None and exact > 0.0 and abs(exact - total) <= AGREEMENT * ald * exact:
        # the curve's own length (closed form or integrated), confirmed by the exploration's estimate
        total = float(exact)
        remainder = max(total - float(ex.cumulative[-1]), 0.0)
        limit = ald * (1.0 - EXACT_MARGIN) * total
    else:
        remainder = ex.remainder
        limit = ald * (1.0 - MARGIN) * total
    budget = max(limit - remainder, 0.0)
    corner_idx = np.searchsorted(u, ex.corners) if len(ex.corners) else np.zeros(0, dtype=int)
    nodes = fewest_nodes(p, ex.cumulative, budget, min_length=min_length, max_length=max_length,
                         forced=corner_idx)
    params, points = u[nodes], p[nodes]
    if min_length is None and max_length is None:
        eq = _equidistributed(ev, ex, corner_idx, total, limit, budget, min_segments=len(corner_idx) + 1)
        if eq is not None and (len(eq[0]) < len(params) or (
                len(eq[0]) == len(params) and polyline_length(eq[1]) > chord_length(p, nodes))):
            params, points = eq
    if max_growth is not None and min_length is None and len(params) > 2 and worst_growth(points) > max_growth:
        params, points = _grade(ev, ex, corner_idx, params, points, max_growth, ald, total, limit)
    length = polyline_length(points)
    estimate = max(1.0 - length / total, 0.0)
    if max_growth is not None and worst_growth(points) > max_growth * (1 + 1e-9):
        notes.append(f"max_growth {max_growth:g} not met everywhere: worst ratio of adjacent segments "
                     f"is {worst_growth(points):.3g}")
    if estimate > ald:
        reason = "min_length" if min_length is not None else "the sampling cap"
        notes.append(f"ald target {ald:g} not reached (estimate {estimate:.3g}) because of {reason}")
    return params, points, estimate, notes
