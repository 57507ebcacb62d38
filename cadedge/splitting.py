"""Graded splitting: every way cadedge adds points to a finished grid, in one place.

A grid here is a pair (params, points). Nothing in this module edits one in place: each function
returns new arrays, and points are only ever added (so a polyline only lengthens and its deficit only
falls). The pieces:

- :func:`insert_points` merges new samples into a grid (sorted by parameter; a repeated parameter
  keeps the old point);
- :func:`points_at_distances` places points on the curve at given distances from a segment end
  (vectorised bisection);
- :func:`split_evenly` cuts segments into equal parameter steps, :func:`split_by_arc` into pieces of
  equal arc length, :func:`cut_by_arc` at given shares of their arc length;
- :func:`limit_growth` (paper section 7) splits until neighbouring segments differ by at most a ratio:
  first along a graded size field (h(s) = min over segments of their length plus (g - 1) times the
  distance, by two sweeps), so sizes grow geometrically away from small segments; then any pair still
  out of bounds is fixed by splitting the longer segment.

- :func:`regrade` re-places target mode's nodes along such a size field (fewer points than splitting
  would add, the target kept), then hands what is left to :func:`limit_growth`; with end sizes, the
  field grades an edge towards its vertices (vertex grading below the golden ratio).

Callers: refine_curve and target mode (``max_growth`` within an edge), :mod:`cadedge.occt.vertexgrowth`
(``max_growth`` across vertices), :mod:`cadedge.mesh.proximity` (segments longer than the mesh size) and
the mesher's other boundary splits (:mod:`cadedge.mesh.widths`, :mod:`cadedge.mesh.grading`).
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .grid import polyline_length, row_norms, unique_sorted
from .placement import equidistribute

Evaluate = Callable[[np.ndarray], np.ndarray]

#: Most re-placements along a graded size field in :func:`regrade`.
GRADING_PASSES = 4
MAX_PASSES = 400
BISECTION_STEPS = 24


def worst_growth(p: np.ndarray) -> float:
    """Largest length ratio of adjacent segments of the polyline through ``p`` (1 for fewer than two)."""
    seg = row_norms(np.diff(p, axis=0))
    if len(seg) < 2:
        return 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(np.max(np.maximum(seg[1:], seg[:-1]) / np.minimum(seg[1:], seg[:-1])))


def insert_points(params: np.ndarray, points: np.ndarray, new_params: np.ndarray,
                  new_points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A new grid: ``params``/``points`` with the new samples merged in by parameter (where a parameter
    repeats, the old sample stays)."""
    u = np.concatenate([params, new_params])
    order = np.argsort(u, kind="stable")
    u, p = u[order], np.concatenate([points, new_points])[order]
    keep = np.concatenate([[True], np.diff(u) > 0])
    return u[keep], p[keep]


def split_evenly(params: np.ndarray, pieces: np.ndarray) -> np.ndarray:
    """Parameters cutting segment ``k`` of ``params`` into ``pieces[k]`` equal parameter steps (the
    interior cuts only, in order)."""
    return np.concatenate([params[k] + (params[k + 1] - params[k]) * np.arange(1, n) / n
                           for k, n in enumerate(pieces) if n > 1] or [np.zeros(0)])


#: Samples per piece along which :func:`split_by_arc` measures a segment's arc.
ARC_SAMPLES = 8
#: :func:`cut_by_arc` leaves whole a segment the curve spans under this share of (its chord is mostly the
#: gap between a vertex and its curve's end).
GAP_SHARE = 0.5


def split_by_arc(params: np.ndarray, points: np.ndarray, pieces: np.ndarray,
                 evaluate: Evaluate) -> tuple[np.ndarray, np.ndarray]:
    """Parameters and points cutting segment ``k`` into ``pieces[k]`` pieces of equal arc length (the
    interior cuts only, in order), the arc measured along :data:`ARC_SAMPLES` samples per piece
    (:func:`cut_by_arc`).

    Equal parameter steps are not equal lengths where the curve's parameter speed varies: on
    mesh_T106_V3's B-spline profile a 2.4 mm segment cut in three gave a 0.2 mm piece, which the next
    proximity pass took as the local size and split its neighbours down to 0.05 mm.
    """
    return cut_by_arc(params, points, equal_shares(pieces), evaluate)


def equal_shares(pieces: np.ndarray) -> dict[int, np.ndarray]:
    """The cuts of :func:`cut_by_arc` that make segment ``k`` ``pieces[k]`` equal pieces (segments of one
    piece left out)."""
    return {k: np.arange(1, n) / n for k, n in enumerate(np.asarray(pieces, dtype=int)) if n > 1}


def cut_by_arc(params: np.ndarray, points: np.ndarray, cuts: dict[int, np.ndarray],
               evaluate: Evaluate) -> tuple[np.ndarray, np.ndarray]:
    """Parameters and points cutting segment ``k`` at the shares ``cuts[k]`` (increasing, in (0, 1)) of its
    arc length (the interior cuts only, in order), the arc measured along :data:`ARC_SAMPLES` samples per
    piece. The grid's own end points stand for the samples at the segment's ends (a vertex may lie a
    tolerance off its curve). A segment the curve itself spans under :data:`GAP_SHARE` of is left whole:
    it is mostly the gap between a vertex and a curve ending off it, which no point on the curve divides
    (a Fusion caster part's B-spline ends 0.005 from its vertex, within the vertex's tolerance: cut in
    eight, that last segment's points fell 1e-14 apart at the curve's end, the face-wise grading took that
    for a spacing, and gmsh hung meshing the face beside it at sizes of 3e-14)."""
    split = sorted(k for k, f in cuts.items() if len(f))
    if not split:
        return np.zeros(0), np.zeros((0, points.shape[1]))
    intervals = np.ones(len(params) - 1, dtype=int)
    intervals[split] = [(len(cuts[k]) + 1) * ARC_SAMPLES for k in split]
    inner = split_evenly(params, intervals)  # the dense samples' parameters, segment after segment
    samples = evaluate(inner)
    own = evaluate(np.concatenate([params[split], params[np.asarray(split) + 1]])).reshape(2, len(split), -1)
    new_u, start = [], 0
    for j, k in enumerate(split):
        m = intervals[k] - 1
        u = np.concatenate([[params[k]], inner[start:start + m], [params[k + 1]]])
        between = samples[start:start + m]
        start += m
        arc = np.concatenate([[0.0], np.cumsum(row_norms(np.diff(np.vstack([points[k], between, points[k + 1]]),
                                                                  axis=0)))])
        if polyline_length(np.vstack([own[0, j], between, own[1, j]])) < GAP_SHARE * arc[-1]:
            continue  # mostly a vertex's gap to its curve: left whole
        new_u.append(np.interp(arc[-1] * np.asarray(cuts[k], dtype=float), arc, u))
    u = np.concatenate(new_u) if new_u else np.zeros(0)
    return u, (evaluate(u) if len(u) else np.zeros((0, points.shape[1])))


def fits_curve(params: np.ndarray, points: np.ndarray, evaluate: Evaluate, tolerance: float) -> bool:
    """Whether the curve (``evaluate``) puts a grid's end parameters at its end points, within 10 times
    the edge's ``tolerance`` or 1e-7 of the grid's extent: a grid whose parameters are not this curve's
    must not be split through it (its new points would land elsewhere on the curve)."""
    off = row_norms(evaluate(params[[0, -1]]) - points[[0, -1]])
    return float(np.max(off)) <= max(10 * tolerance, 1e-7 * (1 + float(np.abs(points).max())))


#: How :func:`split_segments` spaces its cuts.
SPACINGS = ("arc", "parameter")


def split_segments(params: np.ndarray, points: np.ndarray, pieces: np.ndarray, evaluate: Evaluate, *,
                   spacing: str = "arc") -> tuple[np.ndarray, np.ndarray]:
    """A new grid: segment ``k`` cut into ``pieces[k]`` pieces, the new points on the curve
    (``evaluate(u) -> (n, 3)``); the old samples stay as they are.

    ``spacing``: ``"arc"`` (pieces of equal arc length, :func:`split_by_arc`) or ``"parameter"`` (equal
    parameter steps, :func:`split_evenly`: finer where the curve's parameter slows, which on curves that
    run into a pole or a pointed tip is where the face's curvature grows)."""
    if spacing == "arc":
        new_u, new_p = split_by_arc(params, points, pieces, evaluate)
    elif spacing == "parameter":
        new_u = split_evenly(params, np.asarray(pieces, dtype=int))
        new_p = evaluate(new_u)
    else:
        raise ValueError(f"spacing must be one of {SPACINGS}, got {spacing!r}")
    return insert_points(params, points, new_u, new_p)


def points_at_distances(ev: Evaluate, ua: np.ndarray, ub: np.ndarray, ref: np.ndarray, dist: np.ndarray, *,
                        from_start: np.ndarray | bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Parameters in (ua, ub) whose points lie ``dist`` from ``ref``, with the points (vectorised bisection).

    ``ref`` is the point at ``ua`` (``from_start``) or at ``ub``; ``from_start`` may be an array.
    """
    lo, hi = ua.copy(), ub.copy()
    fwd = np.broadcast_to(np.asarray(from_start), lo.shape)
    mid, pm = 0.5 * (lo + hi), None
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        pm = ev(mid)
        near = row_norms(pm - ref) < dist
        move_lo = near == fwd
        lo = np.where(move_lo, mid, lo)
        hi = np.where(move_lo, hi, mid)
    return mid, pm


def _graded_split(ev, u: np.ndarray, p: np.ndarray, g: float, min_length: float | None):
    """Insert graded points so segment sizes follow the size field of growth ``g``."""
    seg = row_norms(np.diff(p, axis=0))
    alpha = 0.9 * (g - 1.0)
    n = len(seg)
    fwd = np.full(n + 1, np.inf)
    bwd = np.full(n + 1, np.inf)
    for i in range(1, n + 1):
        fwd[i] = min(seg[i - 1], fwd[i - 1] + alpha * seg[i - 1])
    for i in range(n - 1, -1, -1):
        bwd[i] = min(seg[i], bwd[i + 1] + alpha * seg[i])
    h_node = np.minimum(fwd, bwd)
    t = (np.arange(32) + 0.5) / 32.0  # midpoint rule inside each segment
    s = seg[:, None] * t[None, :]
    h = np.minimum.reduce([h_node[:-1, None] + alpha * s, h_node[1:, None] + alpha * (seg[:, None] - s),
                           np.broadcast_to(seg[:, None], s.shape)])
    density = 1.0 / np.maximum(h, 1e-300)
    pieces = np.ceil(density.mean(axis=1) * seg - 1e-9).astype(int)
    if min_length is not None:
        pieces = np.minimum(pieces, np.maximum(np.floor(seg / min_length), 1).astype(int))
    split = np.flatnonzero(pieces > 1)
    if not len(split):
        return u, p
    ua, ub, pa, dist = [], [], [], []
    for k in split:  # boundaries at equal steps of the integral of ds / h
        cum = np.concatenate([[0.0], np.cumsum(density[k])])
        frac = np.interp(np.arange(1, pieces[k]) / pieces[k] * cum[-1], cum, np.linspace(0.0, 1.0, 33))
        ua.append(np.full(len(frac), u[k]))
        ub.append(np.full(len(frac), u[k + 1]))
        pa.append(np.repeat(p[k:k + 1], len(frac), axis=0))
        dist.append(frac * seg[k])
    add, pu = points_at_distances(ev, np.concatenate(ua), np.concatenate(ub), np.concatenate(pa),
                                  np.concatenate(dist))
    return insert_points(u, p, add, pu)


def limit_growth(ev: Evaluate, params: np.ndarray, points: np.ndarray, max_growth: float, *,
                 min_length: float | None = None) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Split segments until neighbours have a length ratio of at most ``max_growth``.

    Returns (params, points, notes), a new grid. A piece is never cut shorter than 1/max_growth of the
    segment beside it nor than half the shortest input segment, so the work is bounded; a note says
    when some ratio could not be brought within the bound that way (min_length, or a bound below about
    1.33 right next to an abrupt change of size).
    """
    u, p = np.asarray(params, dtype=float), np.asarray(points, dtype=float)
    g = max_growth
    start = row_norms(np.diff(p, axis=0))
    start = start[start > 0]
    # No piece is ever accepted below half the shortest input segment: the work stays bounded
    # (at most length / floor segments) whatever the curve does between its points.
    floor = 0.5 * float(start.min()) if len(start) else 0.0
    if len(u) > 2 and worst_growth(p) > g:
        u, p = _graded_split(ev, u, p, g, min_length)
    for _ in range(MAX_PASSES):
        seg = row_norms(np.diff(p, axis=0))
        if len(seg) < 2:
            break
        left, right = seg[:-1], seg[1:]
        pair = np.flatnonzero(np.maximum(left, right) > g * np.minimum(left, right))
        pair = pair[np.maximum(left[pair], right[pair]) > 0]
        if not len(pair):
            break
        # Carve a piece x off the longer segment, next to the shorter neighbour t: x <= g t keeps this
        # pair within bounds, x <= L g / (1 + g) keeps the rest within bounds of x, x >= t / g.
        long_is_left = left[pair] >= right[pair]
        k = np.where(long_is_left, pair, pair + 1)
        t = np.minimum(left[pair], right[pair])
        big = seg[k]
        x = np.minimum(0.98 * g * t, big * g / (1.0 + g))
        # A piece no shorter than the short neighbour where one cut allows it; otherwise halves, when
        # they stay within the bound of that neighbour. Pieces never fall below t / g.
        x = np.where(x >= t, x, 0.5 * big)
        ok = (u[k + 1] - u[k] > 1e-12 * (u[-1] - u[0])) & (x >= t / g) & (x < big)
        if min_length is not None:
            ok &= np.minimum(x, big - x) >= min_length
        k, x, long_is_left, big = k[ok], x[ok], long_is_left[ok], big[ok]
        k, first = np.unique(k, return_index=True)
        if not len(k):
            break
        x, long_is_left, big = x[first], long_is_left[first], big[first]
        # the piece sits at the short neighbour's side of the long segment
        ref = np.where(long_is_left[:, None], p[k + 1], p[k])
        um, pm = points_at_distances(ev, u[k], u[k + 1], ref, x, from_start=~long_is_left)
        fits = np.minimum(row_norms(pm - p[k]), row_norms(p[k + 1] - pm)) >= floor
        if not fits.any():
            break
        u, p = insert_points(u, p, um[fits], pm[fits])
    worst = worst_growth(p)
    notes = [] if worst <= g * (1 + 1e-9) else [
        f"max_growth {g:g} not met everywhere: worst ratio of adjacent segments is {worst:.3g}"]
    return u, p, notes


def evaluate_new(ev, u: np.ndarray, params: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points at ``params``, evaluating only those not already among the samples ``u``."""
    idx = np.clip(np.searchsorted(u, params), 0, len(u) - 1)
    known = u[idx] == params
    out = np.empty((len(params), 3))
    out[known] = points[idx[known]]
    if (~known).any():
        out[~known] = ev(params[~known])
    return out


def _graded(ev, ex, corner_idx: np.ndarray, params: np.ndarray, points: np.ndarray, growth: float,
            total: float, limit: float, end_sizes: tuple[float | None, float | None] = (None, None)
            ) -> tuple[np.ndarray, np.ndarray] | None:
    """Re-place the grid so neighbouring segments differ by at most ``growth``, keeping the target.

    The size field h(s) = min over segments j of (l_j + alpha * arc distance to j), alpha just under
    growth - 1, is never above the grid's own sizes; nodes at equal steps of the integral of ds / h
    then have sizes that follow h, so neighbours differ by about 1 + alpha. Both running minima are
    prefix minima over the dense samples, so this is linear in their number. ``end_sizes`` are sizes the
    field starts from at either end (``None``: the grid's own), for grading towards a shared vertex.
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
    if end_sizes[0] is not None:
        h = np.minimum(h, end_sizes[0] + alpha * cum)
    if end_sizes[1] is not None:
        h = np.minimum(h, end_sizes[1] + alpha * (cum[-1] - cum))
    h = np.maximum(h, 1e-300)
    inv = 1.0 / h
    measure = np.concatenate([[0.0], np.cumsum(0.5 * (inv[:-1] + inv[1:]) * np.diff(cum))])
    count = max(int(math.ceil(measure[-1] - 1e-9)), len(corner_idx) + 1)
    for _ in range(6):
        new = equidistribute(u, cum, measure, count, corner_idx)
        pts = evaluate_new(ev, u, new, ex.points)
        if total - polyline_length(pts) <= limit:
            return new, pts
        count = int(math.ceil(count * 1.1)) + 1
    return None


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


def _ends_within(points: np.ndarray, end_sizes: tuple[float | None, float | None], growth: float) -> bool:
    """Whether the end segments are at most ``sqrt(growth)`` times the given end sizes (the field aims at
    the end sizes; the rounds of :func:`regrade` stop once the ends are that close)."""
    seg = row_norms(np.diff(points[[0, 1, -2, -1]], axis=0))[[0, 2]]
    return all(e is None or s <= e * math.sqrt(growth) for s, e in zip(seg, end_sizes))


def regrade(ev, ex, corner_idx: np.ndarray, params: np.ndarray, points: np.ndarray, growth: float, ald: float,
            total: float, limit: float, *, end_sizes: tuple[float | None, float | None] = (None, None)
            ) -> tuple[np.ndarray, np.ndarray]:
    """A new grid for ``max_growth``: the nodes re-placed along a graded size field (:func:`_graded`,
    starting from the sizes ``end_sizes`` at the grid's ends where given) on the exploration ``ex``, keeping
    its corners (``corner_idx``) and the sharp nodes, its deficit against ``total`` within ``limit``;
    then :func:`limit_growth` for what is left within the grid."""
    keep = _sharp_nodes(points, ald)
    if len(keep):  # make the sharp nodes samples (if they are not) and pin them like corners
        ex = ex.with_samples(params[keep], points[keep])
        corner_idx = unique_sorted(np.concatenate([np.searchsorted(ex.params, ex.corners),
                                               np.searchsorted(ex.params, params[keep])])).astype(int)
    for _ in range(GRADING_PASSES):  # each pass smooths the sizes of the one before
        graded = _graded(ev, ex, corner_idx, params, points, growth, total, limit, end_sizes)
        if graded is None:
            break
        params, points = graded
        if worst_growth(points) <= growth and _ends_within(points, end_sizes, growth):
            return params, points
    params, points, _ = limit_growth(ev, params, points, growth)
    return params, points
