"""Growth-ratio control (paper section 7): split segments until neighbours differ by at most a ratio.

Only splitting, so the deficit can only fall. First a graded size field along the polyline
(h(s) = min over segments of their length plus (g - 1) times the distance, by two sweeps) says how many
pieces each segment needs and where, so sizes grow geometrically away from small segments; then any
pair still out of bounds is fixed by splitting the longer segment where it halves its chord
(bisection on |P(u) - A| - |P(u) - B|, vectorised over all segments split in one pass).
"""

from __future__ import annotations

import numpy as np

from .grid import row_norms

GRADED_PASSES = 12
MAX_PASSES = 400
BISECTION_STEPS = 24


def worst_growth(p: np.ndarray) -> float:
    """Largest length ratio of adjacent segments of the polyline through ``p`` (1 for fewer than two)."""
    seg = row_norms(np.diff(p, axis=0))
    if len(seg) < 2:
        return 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(np.max(np.maximum(seg[1:], seg[:-1]) / np.minimum(seg[1:], seg[:-1])))


def _points_at_distances(ev, ua, ub, ref, dist, *, from_start=True):
    """Parameters in (ua, ub) whose points lie ``dist`` from ``ref`` (vectorised bisection).

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
    add, pu = _points_at_distances(ev, np.concatenate(ua), np.concatenate(ub), np.concatenate(pa),
                                   np.concatenate(dist))
    allu = np.concatenate([u, add])
    order = np.argsort(allu, kind="stable")
    allu, allp = allu[order], np.concatenate([p, pu])[order]
    keep = np.concatenate([[True], np.diff(allu) > 0])
    return allu[keep], allp[keep]


def limit_growth(ev, params: np.ndarray, points: np.ndarray, max_growth: float, *,
                 min_length: float | None = None) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Split segments until neighbours have a length ratio of at most ``max_growth``.

    Returns (params, points, notes). A piece is never cut shorter than 1/max_growth of the segment
    beside it nor than half the shortest input segment, so the work is bounded; a note says when some ratio could not be brought within the bound that way
    (min_length, or a bound below about 1.33 right next to an abrupt change of size).
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
        um, pm = _points_at_distances(ev, u[k], u[k + 1], ref, x, from_start=~long_is_left)
        fits = np.minimum(row_norms(pm - p[k]), row_norms(p[k + 1] - pm)) >= floor
        if not fits.any():
            break
        u = np.insert(u, k[fits] + 1, um[fits])
        p = np.insert(p, k[fits] + 1, pm[fits], axis=0)
    worst = worst_growth(p)
    notes = [] if worst <= g * (1 + 1e-9) else [
        f"max_growth {g:g} not met everywhere: worst ratio of adjacent segments is {worst:.3g}"]
    return u, p, notes
