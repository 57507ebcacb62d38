"""Choosing the fewest grid nodes among dense samples for a length budget.

For a chord over a smooth stretch the deficit grows with the cube of its length, so the fewest
segments for a total deficit are those that share it equally. ``greedy`` takes, from each node, the
farthest sample whose chord misses at most ``cap`` of the dense polyline's length (farthest reach is
optimal for a per-segment cap because the deficit only grows as a chord is extended); a bisection on
``cap`` finds the fewest nodes for the total budget. ``polish`` then moves each interior node to the
sample between its neighbours that makes the two chords longest (the paper's Algorithm 1 on samples),
alternating odd and even nodes so every move is vectorised and the length never decreases.
"""

from __future__ import annotations

import numpy as np

from .grid import polyline_length, row_norms


def chord_length(points: np.ndarray, nodes: np.ndarray) -> float:
    """Length of the polyline through ``points[nodes]``."""
    return polyline_length(points[nodes])


#: Largest number of samples for which fewest_nodes tabulates every chord deficit (n**2 floats).
TABLE_SAMPLES = 1000


def _follow(reach: list[int], last: int) -> np.ndarray:
    nodes = [0]
    i = 0
    while i < last:
        i = reach[i]
        nodes.append(i)
    return np.array(nodes)


def _stops(n: int, forced: np.ndarray | None) -> np.ndarray:
    """For each sample but the last, the first forced node (or the last sample) after it."""
    last = n - 1
    stops = np.array([last]) if forced is None else np.unique(np.concatenate([forced, [last]]))
    return stops[np.searchsorted(stops, np.arange(last), side="right")]


def _greedy_reach(points: np.ndarray, cum: np.ndarray, cap: float, forced: np.ndarray | None) -> np.ndarray:
    """:func:`greedy` without length bounds: the farthest reach of every sample in one vectorised bisection.

    The deficit of a chord from sample i grows with its far end (triangle inequality), so the reach of
    every i is found together in about log2(n) numpy passes; the nodes then follow the reach pointers.
    """
    last = len(points) - 1
    idx = np.arange(last)
    lo, hi = idx + 1, _stops(len(points), forced)  # lo always admissible (reach is at least one sample on)
    while True:
        open_ = lo < hi
        if not open_.any():
            break
        i, a, b = idx[open_], lo[open_], hi[open_]
        mid = (a + b + 1) // 2
        ok = (cum[mid] - cum[i]) - row_norms(points[mid] - points[i]) <= cap
        lo[open_] = np.where(ok, mid, a)
        hi[open_] = np.where(ok, b, mid - 1)
    return _follow(lo.tolist(), last)


class _DeficitTable:
    """Every chord deficit between samples, tabulated once so each :func:`greedy` cap costs one pass.

    Row i, column k holds the deficit of the chord from sample i to sample i + 1 + k (inf past a stop),
    so the farthest reach under a cap is the first column over it: exactly :func:`greedy`'s choice.
    """

    def __init__(self, points: np.ndarray, cum: np.ndarray, forced: np.ndarray | None):
        n = len(points)
        self.last = n - 1
        idx = np.arange(self.last)
        j = idx[:, None] + 1 + np.arange(self.last)[None, :]
        stop = _stops(n, forced)
        valid = j <= stop[:, None]
        jc = np.minimum(j, self.last)
        d = (cum[jc] - cum[idx, None]) - np.linalg.norm(points[jc] - points[idx, None], axis=2)
        self.table = np.where(valid, d, np.inf)
        self.idx, self.stop = idx, stop

    def greedy(self, cap: float) -> np.ndarray:
        over = self.table > cap
        first = np.where(over.any(axis=1), over.argmax(axis=1), self.stop - self.idx)  # columns admissible
        reach = self.idx + np.maximum(first, 1)
        return _follow(reach.tolist(), self.last)


def greedy(points: np.ndarray, cum: np.ndarray, cap: float, *, min_length: float | None = None,
           max_length: float | None = None, forced: np.ndarray | None = None) -> np.ndarray:
    """Node indices by farthest reach: each chord misses at most ``cap`` of the samples' length.

    Chords stay at most ``max_length`` long and, where the curve allows, at least ``min_length``.
    ``forced`` sample indices (sharp corners) are always nodes.
    """
    if min_length is None and max_length is None and cap > 0.0:  # cap 0 keeps every sample off a rounding-noise chord
        return _greedy_reach(points, cum, cap, forced)
    n = len(points)
    last = n - 1
    stops = np.array([last]) if forced is None else np.unique(np.concatenate([forced, [last]]))
    nodes = [0]
    i = 0
    window = 16
    while i < last:
        stop = int(stops[np.searchsorted(stops, i, side="right")])
        while True:
            j_hi = min(stop, i + window)
            seg = points[i + 1:j_hi + 1] - points[i]
            chord = row_norms(seg)
            deficit = (cum[i + 1:j_hi + 1] - cum[i]) - chord
            ok = deficit <= cap
            if max_length is not None:
                ok &= chord <= max_length
            bad = np.flatnonzero(~ok)
            if len(bad) or j_hi == stop:
                break
            window *= 2
        reach = i + 1 + (int(bad[0]) - 1 if len(bad) else len(ok) - 1)
        reach = max(reach, i + 1)
        if min_length is not None and reach < stop and np.linalg.norm(points[reach] - points[i]) < min_length:
            far = row_norms(points[reach + 1:stop + 1] - points[i]) >= min_length
            reach = reach + 1 + int(np.argmax(far)) if far.any() else stop
        nodes.append(reach)
        i = reach
    out = np.array(nodes)
    if min_length is not None and len(out) > 2:
        if np.linalg.norm(points[out[-1]] - points[out[-2]]) < min_length:
            out = np.delete(out, -2)
    return out


def polish(points: np.ndarray, nodes: np.ndarray, *, sweeps: int = 4, fixed: np.ndarray | None = None) -> np.ndarray:
    """Move interior nodes to the sample between their neighbours that maximises the two chords."""
    nodes = nodes.copy()
    movable = np.ones(len(nodes), dtype=bool)
    movable[[0, -1]] = False
    if fixed is not None and len(fixed):
        movable &= ~np.isin(nodes, fixed)
    for _ in range(sweeps):
        moved = False
        for parity in (1, 0):
            k = np.flatnonzero(movable & (np.arange(len(nodes)) % 2 == parity))
            if not len(k):
                continue
            lo, hi = nodes[k - 1], nodes[k + 1]
            sizes = hi - lo - 1
            keep = sizes > 0
            k, lo, hi, sizes = k[keep], lo[keep], hi[keep], sizes[keep]
            if not len(k):
                continue
            group = np.repeat(np.arange(len(k)), sizes)
            starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
            cand = lo[group] + 1 + (np.arange(sizes.sum()) - starts[group])
            two = row_norms(points[cand] - points[lo[group]]) + row_norms(points[hi[group]] - points[cand])
            best = np.maximum.reduceat(two, starts)
            current = row_norms(points[nodes[k]] - points[lo]) + row_norms(points[hi] - points[nodes[k]])
            better = best > current * (1 + 1e-15)
            if not better.any():
                continue
            # first candidate reaching the group's maximum
            hit = two >= best[group]
            first = np.full(len(k), -1)
            idx = np.flatnonzero(hit)
            g_hit = group[idx]
            first_pos = idx[np.concatenate([[True], g_hit[1:] != g_hit[:-1]])]
            first[np.unique(g_hit)] = cand[first_pos]
            nodes[k[better]] = first[better]
            moved = True
        if not moved:
            break
    return nodes


def _bisect(test, lo: float, hi: float, *, ok_below: bool, steps: int, rel: float):
    """Bisect a cap on [lo, hi]; ``test(cap)`` gives (ok, value). Returns the value at the ok cap
    closest to the boundary (ok caps lie below it if ``ok_below``, above it otherwise), or None."""
    found = None
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        ok, value = test(mid)
        if ok:
            found = value
        if ok == ok_below:
            lo = mid
        else:
            hi = mid
        if hi - lo <= rel * hi:
            break
    return found


def fewest_nodes(points: np.ndarray, cum: np.ndarray, budget: float, *, min_length: float | None = None,
                 max_length: float | None = None, forced: np.ndarray | None = None) -> np.ndarray:
    """The fewest nodes (by greedy + bisection on the cap, then polish) whose chords miss at most ``budget``.

    ``budget`` is measured against the samples' polyline length ``cum[-1]``. If even every sample is
    not enough (min_length), the densest admissible grid is returned.
    """
    total = cum[-1]
    table = (_DeficitTable(points, cum, forced)
             if min_length is None and max_length is None and len(points) <= TABLE_SAMPLES else None)

    def cover(cap: float) -> np.ndarray:
        if table is not None and cap > 0.0:
            return table.greedy(cap)
        return greedy(points, cum, cap, min_length=min_length, max_length=max_length, forced=forced)

    planned: dict[bytes, tuple[np.ndarray, float]] = {}  # caps of the bisection often give the same nodes

    def plan(cap: float) -> tuple[np.ndarray, float]:
        nodes = cover(cap)
        key = nodes.tobytes()
        if key not in planned:
            if len(nodes) > 2:
                nodes = polish(points, nodes, fixed=forced)
            planned[key] = nodes, total - chord_length(points, nodes)
        return planned[key]

    best, miss = plan(max(budget, 0.0))
    if miss > budget:  # the per-segment cap equal to the whole budget is too loose: bisect down
        best = _bisect(lambda cap: (plan(cap)[1] <= budget, plan(cap)[0]), 0.0, max(budget, 0.0),
                       ok_below=True, steps=60, rel=1e-3)
        if best is None:
            best, _ = plan(0.0)
    # The polished grid may leave room for fewer nodes: try dropping one at a time.
    while len(best) > 2:
        count = len(best)
        fewer = _bisect(lambda cap: (len(cover(cap)) < count, cover(cap)), 0.0, total,
                        ok_below=False, steps=40, rel=1e-4)
        if fewer is None:
            break
        fewer = polish(points, fewer, sweeps=8, fixed=forced) if len(fewer) > 2 else fewer
        if total - chord_length(points, fewer) > budget:
            break
        best = fewer
    return best


def deficit_measure(points: np.ndarray, cum: np.ndarray, corners: np.ndarray | None = None) -> np.ndarray:
    """Cumulative measure M along the samples such that a chord spanning dM misses about dM**3.

    For a smooth stretch a chord of arc length S misses ``c * S**3`` (c = curvature**2 / 24). At each
    interior sample the two neighbouring intervals (h1, h2) give ``c`` derivative-free from the
    deficit ``d = 3 c h1 h2 (h1 + h2)`` of the chord that skips the sample. Equal steps of M are then
    the segments that share a deficit budget equally: the fewest for that budget. Samples listed in
    ``corners`` (kinks, which a node must sit on) contribute nothing.
    """
    h = np.diff(cum)
    n = len(points)
    rho = np.zeros(n)
    if n >= 3:
        skip = row_norms(points[2:] - points[:-2])
        d = np.maximum(h[:-1] + h[1:] - skip, 0.0)
        denom = 3.0 * h[:-1] * h[1:] * (h[:-1] + h[1:])
        with np.errstate(divide="ignore", invalid="ignore"):
            rho[1:-1] = np.where(denom > 0, np.cbrt(d / denom), 0.0)
        rho[0], rho[-1] = rho[1], rho[-2]
    if corners is not None and len(corners):
        rho[corners] = 0.0
    step = 0.5 * (rho[:-1] + rho[1:]) * h
    return np.concatenate([[0.0], np.cumsum(step)])


def equidistribute(params: np.ndarray, cum: np.ndarray, measure: np.ndarray, count: int,
                   corners: np.ndarray | None = None) -> np.ndarray:
    """``count`` segments' worth of parameters at equal steps of ``measure``, with every corner a node.

    Pieces between corners get whole numbers of segments in proportion to their measure (at least
    one each). Positions between samples are interpolated linearly in arc length, then in parameter.
    """
    cut = np.unique(np.concatenate([[0], [] if corners is None else corners, [len(params) - 1]])).astype(int)
    m = measure[cut]
    share = np.diff(m)
    total = share.sum()
    pieces = len(share)
    if total <= 0:
        alloc = np.ones(pieces, dtype=int)
    else:
        raw = share / total * max(count, pieces)
        alloc = np.maximum(np.floor(raw).astype(int), 1)
        short = max(count, pieces) - alloc.sum()
        if short > 0:
            alloc[np.argsort(-(raw - alloc))[:short]] += 1
    out = [params[:1]]
    for (i0, i1), k in zip(zip(cut[:-1], cut[1:]), alloc):
        if k > 1 and measure[i1] > measure[i0]:
            targets = measure[i0] + (measure[i1] - measure[i0]) * np.arange(1, k) / k
            sl = slice(i0, i1 + 1)
            s = np.interp(targets, measure[sl], cum[sl])
            out.append(np.interp(s, cum[sl], params[sl]))
        elif k > 1:
            out.append(np.interp(np.linspace(cum[i0], cum[i1], k + 1)[1:-1], cum[i0:i1 + 1], params[i0:i1 + 1]))
        out.append(params[i1:i1 + 1])
    u = np.concatenate(out)
    keep = np.concatenate([[True], np.diff(u) > 0])
    return u[keep]
