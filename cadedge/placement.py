"""Choosing the fewest grid nodes among dense samples for a length budget.

For a chord over a smooth stretch the deficit grows with the cube of its length, so the fewest
segments for a total deficit are those that share it equally. The greedy cover takes, from each
node, the farthest sample whose chord misses at most ``cap`` of the dense polyline's length (farthest
reach is optimal for a per-segment cap because the deficit only grows as a chord is extended); a
bisection on ``cap`` finds the fewest nodes for the total budget. The polish then moves each interior
node to the sample between its neighbours that makes the two chords longest (the paper's Algorithm 1
on samples), odd nodes then even ones, so the length never decreases.

These are tight scalar loops over samples (a few dozen covers and polishes per edge), compiled with
numba (:mod:`cadedge.compiled`): a profile of the numpy version showed its per-call overhead dominating
whole-model runs. So are the deficit measure and the equidistribution along it, which run once or
twice per edge.
"""

from __future__ import annotations

import math

import numpy as np

from .compiled import distance, jit
from .grid import polyline_length


def chord_length(points: np.ndarray, nodes: np.ndarray) -> float:
    """Length of the polyline through ``points[nodes]``."""
    return polyline_length(points[nodes])


@jit
def _dist(points, i, j):
    return distance(points, i, points, j)


@jit
def _chords(points, nodes):
    """Length of the polyline through ``points[nodes]``."""
    s = 0.0
    for k in range(len(nodes) - 1):
        s += _dist(points, nodes[k], nodes[k + 1])
    return s


@jit
def _cover(points, cum, cap, min_length, max_length, stops, out):
    """Greedy farthest-reach nodes into ``out``; returns their count.

    Each chord misses at most ``cap`` of the samples' length and is at most ``max_length`` long, and
    where the curve allows at least ``min_length`` (0 for none). ``stops`` (sorted, ending with the last
    sample) are always nodes.
    """
    last = len(points) - 1
    out[0] = 0
    count, i, s = 1, 0, 0
    while i < last:
        while stops[s] <= i:
            s += 1
        stop = stops[s]
        reach = stop
        for j in range(i + 1, stop + 1):
            chord = _dist(points, i, j)
            if (cum[j] - cum[i]) - chord > cap or chord > max_length:
                reach = j - 1
                break
        reach = max(reach, i + 1)
        if min_length > 0.0 and reach < stop and _dist(points, i, reach) < min_length:
            far = stop
            for j in range(reach + 1, stop + 1):
                if _dist(points, i, j) >= min_length:
                    far = j
                    break
            reach = far
        out[count] = reach
        count += 1
        i = reach
    if min_length > 0.0 and count > 2 and _dist(points, out[count - 2], out[count - 1]) < min_length:
        out[count - 2] = out[count - 1]
        count -= 1
    return count


@jit
def _polish(points, nodes, sweeps, fixed):
    """Move interior nodes (not on ``fixed`` samples) to the sample between their neighbours that
    maximises the two chords; odd positions then even ones, until nothing moves or ``sweeps`` runs."""
    count = len(nodes)
    for _ in range(sweeps):
        moved = False
        for parity in (1, 0):
            for k in range(1, count - 1):
                if k % 2 != parity or fixed[nodes[k]]:
                    continue
                lo, hi = nodes[k - 1], nodes[k + 1]
                best, arg = -1.0, -1
                for c in range(lo + 1, hi):
                    two = _dist(points, lo, c) + _dist(points, c, hi)
                    if two > best:
                        best, arg = two, c
                if arg < 0:
                    continue
                current = _dist(points, lo, nodes[k]) + _dist(points, nodes[k], hi)
                if best > current * (1.0 + 1e-15):
                    nodes[k] = arg
                    moved = True
        if not moved:
            break


@jit
def _plan(points, cum, cap, min_length, max_length, stops, fixed, buf):
    """Greedy cover under ``cap``, polished: (nodes, deficit against the samples' length)."""
    nodes = buf[:_cover(points, cum, cap, min_length, max_length, stops, buf)].copy()
    if len(nodes) > 2:
        _polish(points, nodes, 4, fixed)
    return nodes, cum[-1] - _chords(points, nodes)


@jit
def _fewest(points, cum, budget, min_length, max_length, stops, fixed):
    total = cum[-1]
    buf = np.empty(len(points), dtype=np.int64)
    best, miss = _plan(points, cum, max(budget, 0.0), min_length, max_length, stops, fixed, buf)
    if miss > budget:  # the per-segment cap equal to the whole budget is too loose: bisect it down
        lo, hi, found = 0.0, max(budget, 0.0), False
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            nodes, miss = _plan(points, cum, mid, min_length, max_length, stops, fixed, buf)
            if miss <= budget:
                best, found, lo = nodes, True, mid
            else:
                hi = mid
            if hi - lo <= 1e-3 * hi:
                break
        if not found:
            best, miss = _plan(points, cum, 0.0, min_length, max_length, stops, fixed, buf)
    # The polished grid may leave room for fewer nodes: bisect for a cap that drops one, polish, check.
    while len(best) > 2:
        count = len(best)
        lo, hi, found = 0.0, total, False
        fewer = best
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            c = _cover(points, cum, mid, min_length, max_length, stops, buf)
            if c < count:
                fewer, found, hi = buf[:c].copy(), True, mid
            else:
                lo = mid
            if hi - lo <= 1e-4 * hi:
                break
        if not found:
            break
        if len(fewer) > 2:
            _polish(points, fewer, 8, fixed)
        if total - _chords(points, fewer) > budget:
            break
        best = fewer
    return best


def fewest_nodes(points: np.ndarray, cum: np.ndarray, budget: float, *, min_length: float | None = None,
                 max_length: float | None = None, forced: np.ndarray | None = None) -> np.ndarray:
    """The fewest node indices (greedy + bisection on the cap, then polish) whose chords miss at most
    ``budget`` of ``cum[-1]``, the samples' polyline length.

    Chords stay at most ``max_length`` long and, where the curve allows, at least ``min_length``;
    ``forced`` sample indices (kinks) are always nodes. If even every sample is not enough
    (min_length), the densest admissible grid is returned.
    """
    points = np.ascontiguousarray(points, dtype=float)
    n = len(points)
    forced = np.zeros(0, dtype=np.int64) if forced is None else np.asarray(forced, dtype=np.int64)
    stops = np.unique(np.append(forced, n - 1)) if len(forced) else np.array([n - 1], dtype=np.int64)
    fixed = np.zeros(n, dtype=np.bool_)
    fixed[forced] = True
    return _fewest(points, np.ascontiguousarray(cum, dtype=float), float(budget),
                   0.0 if min_length is None else float(min_length),
                   math.inf if max_length is None else float(max_length), stops, fixed)


@jit
def _deficit_measure(points, cum, corners):
    n = len(points)
    rho = np.zeros(n)
    for i in range(1, n - 1):
        h1, h2 = cum[i] - cum[i - 1], cum[i + 1] - cum[i]
        denom = 3.0 * h1 * h2 * (h1 + h2)
        if denom > 0:
            rho[i] = np.cbrt(max(h1 + h2 - _dist(points, i - 1, i + 1), 0.0) / denom)
    if n >= 3:
        rho[0], rho[-1] = rho[1], rho[-2]
    for c in corners:
        rho[c] = 0.0
    measure = np.empty(n)
    measure[0] = 0.0
    for i in range(n - 1):
        measure[i + 1] = measure[i] + 0.5 * (rho[i] + rho[i + 1]) * (cum[i + 1] - cum[i])
    return measure


def deficit_measure(points: np.ndarray, cum: np.ndarray, corners: np.ndarray | None = None) -> np.ndarray:
    """Cumulative measure M along the samples such that a chord spanning dM misses about dM**3.

    For a smooth stretch a chord of arc length S misses ``c * S**3`` (c = curvature**2 / 24). At each
    interior sample the two neighbouring intervals (h1, h2) give ``c`` derivative-free from the
    deficit ``d = 3 c h1 h2 (h1 + h2)`` of the chord that skips the sample. Equal steps of M are then
    the segments that share a deficit budget equally: the fewest for that budget. Samples listed in
    ``corners`` (kinks, which a node must sit on) contribute nothing.
    """
    corners = np.zeros(0, dtype=np.int64) if corners is None else np.asarray(corners, dtype=np.int64)
    return _deficit_measure(np.ascontiguousarray(points, dtype=float),
                            np.ascontiguousarray(cum, dtype=float), corners)


@jit
def _interp_sorted(x, xp, fp):
    """``np.interp(x, xp, fp)`` for increasing ``x`` and non-decreasing ``xp``, by one forward sweep
    (the same bracketing and formula, so the same values; far less to compile)."""
    out = np.empty(len(x))
    last = len(xp) - 1
    j = 0
    for k in range(len(x)):
        v = x[k]
        if v >= xp[last]:
            out[k] = fp[last]
            continue
        if v < xp[0]:
            out[k] = fp[0]
            continue
        while xp[j + 1] <= v:
            j += 1
        out[k] = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j]) * (v - xp[j]) + fp[j]
    return out


@jit
def _place(params, cum, measure, cut, alloc):
    """Parameters at equal steps of ``measure`` within each piece between ``cut`` samples (``alloc``
    segments each), interpolated in arc length then in parameter; strictly increasing."""
    total = 1
    for k in alloc:
        total += max(k, 1)
    out = np.empty(total)
    out[0] = params[0]
    w = 1
    for piece in range(len(alloc)):
        i0, i1, k = cut[piece], cut[piece + 1], alloc[piece]
        if k > 1:
            ms, cs, ps = measure[i0:i1 + 1], cum[i0:i1 + 1], params[i0:i1 + 1]
            s = np.empty(k - 1)
            for j in range(1, k):
                if measure[i1] > measure[i0]:
                    s[j - 1] = measure[i0] + (measure[i1] - measure[i0]) * float(j) / k
                else:
                    s[j - 1] = cum[i0] + (cum[i1] - cum[i0]) * float(j) / k
            if measure[i1] > measure[i0]:
                s = _interp_sorted(s, ms, cs)
            for x in _interp_sorted(s, cs, ps):
                if x > out[w - 1]:
                    out[w] = x
                    w += 1
        if params[i1] > out[w - 1]:
            out[w] = params[i1]
            w += 1
    return out[:w].copy()


def equidistribute(params: np.ndarray, cum: np.ndarray, measure: np.ndarray, count: int,
                   corners: np.ndarray | None = None) -> np.ndarray:
    """``count`` segments' worth of parameters at equal steps of ``measure``, with every corner a node.

    Pieces between corners get whole numbers of segments in proportion to their measure (at least
    one each). Positions between samples are interpolated linearly in arc length, then in parameter.
    """
    last = len(params) - 1
    if corners is None or not len(corners):
        cut, alloc = np.array([0, last]), np.array([max(count, 1) if measure[last] > measure[0] else 1])
    else:
        cut = np.unique(np.concatenate([[0], corners, [last]])).astype(np.int64)
        share = np.diff(measure[cut])
        total = share.sum()
        pieces = len(share)
        if total <= 0:
            alloc = np.ones(pieces, dtype=np.int64)
        else:
            raw = share / total * max(count, pieces)
            alloc = np.maximum(np.floor(raw).astype(np.int64), 1)
            short = max(count, pieces) - alloc.sum()
            if short > 0:
                alloc[np.argsort(-(raw - alloc))[:short]] += 1
    return _place(np.ascontiguousarray(params, dtype=float), np.ascontiguousarray(cum, dtype=float),
                  np.ascontiguousarray(measure, dtype=float), cut.astype(np.int64), alloc.astype(np.int64))
