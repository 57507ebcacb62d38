"""The sampled global optimum: the fewest segments whose best polyline reaches a given length.

Used as the yardstick of target mode and of the shape benchmark: sample a curve densely
(:func:`dense_samples`), then find, among polylines whose vertices are a subsequence of the samples with
both ends fixed, the longest with ``k`` segments (:func:`max_length_polyline`) or the fewest segments
reaching a length (:func:`min_segments`). Vertices restricted to samples can only be shorter than
vertices anywhere on the curve, so the sampled optimum is an upper bound on the continuous optimum's
segment count; with dense samples it is close (a vertex off its best place by ``delta`` loses length of
order ``delta**2``).

The dynamic programme and why its pruning is exact
--------------------------------------------------
Let ``s`` be the cumulative length of the sample polyline (total ``S``) and ``def(i, j) = s[j] - s[i] -
|p_j - p_i|`` the deficit of the chord ``i -> j``. A polyline's length is ``S`` minus the sum of its
chords' deficits. ``M_k[j]`` is the longest polyline from sample 0 to sample j with at most k segments:

    M_k[j] = max(M_{k-1}[j], max_{i < j} M_{k-1}[i] + |p_j - p_i|).

Three facts cut the O(k n^2) cost without changing any value:

1. **Budget.** A polyline reaching length ``L*`` has total deficit at most ``D = S - L*``, so every prefix
   of it has deficit ``s[i] - M[i] <= D`` and every chord ``def(i, j) <= D``. States over budget are
   dropped. ``def(i, j)`` grows with ``j`` (triangle inequality), so the chords allowed from ``i`` end at
   a sample ``reach[i]`` found once by bisection, and a layer looks only ``max(reach[i] - i)`` back.
   For :func:`max_length_polyline`, ``D`` comes from a feasible k-segment polyline (greedy under a
   per-chord deficit cap), so the optimum, being at least as long, is within the same budget. The
   dense layer also looks back, per block of rows, only to the first state whose reach gets there.
2. **Only changed states propagate.** If ``M_{k-1}[i] == M_{k-2}[i]``, every candidate from ``i`` was
   already offered to layer k-1 and is at most ``M_{k-1}[j] <= M_k[j]``. On straight runs, states settle
   after one layer and stop costing anything.
3. Layers stop as soon as ``M_k[last] >= L*`` (for the minimum count) or at ``k``.

Each layer is one vectorised numpy pass, either dense over a band of rows and offsets (chord lengths
cached) or, when the band would be mostly empty, over the exact list of (changed state, chord) pairs.
Cost: about ``n * w * k`` candidate chords for ``k`` layers of width ``w``; ``w`` is near ``k**(1/3)``
times the samples per segment on smooth curves, longer on straight runs (where states settle at once).
Measured on the shared 2-core machine: 5000 :func:`dense_samples` of a circle, helix, spiral or
lissajous, 300 segments: :func:`min_segments` 0.3-0.9 s, :func:`max_length_polyline` 0.4-1.0 s.

Exactness: the result is the exact optimum over the samples (checked against brute force and an
unpruned DP in the tests), up to a relative slack of ``RTOL`` on length comparisons. The only
approximation is the sampling itself: the optimum over samples needs at least as many segments as the
continuous one (see :func:`sampled_optimum` for how close it is).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..curves import Evaluator, as_curve
from ..errors import InputError

RTOL = 1e-12  # relative slack on length comparisons: a polyline reaching L* exactly is not lost to rounding
DENSE_LIMIT = 4_000_000  # largest cached chord band (entries) for the dense layer
BLOCK_ROWS = 256  # rows per block of the dense layer
ARC_SHARE, CURVATURE_SHARE, TURNING_SHARE = 0.25, 0.55, 0.2  # the sampling measure (see _measure)
SAMPLES_PER_SEGMENT = 12  # samples per optimal segment when sampled_optimum adapts the count
MAX_SAMPLES = 10000


def _prepare(points: Any) -> tuple[np.ndarray, np.ndarray]:
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3) or len(pts) < 2:
        raise InputError(f"need at least 2 points of 2 or 3 coordinates, got shape {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise InputError("points must be finite")
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    return np.ascontiguousarray(pts.T), arc


def _chord(xyz: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    d = xyz[0, j] - xyz[0, i]
    out = d * d
    for c in range(1, xyz.shape[0]):
        d = xyz[c, j] - xyz[c, i]
        out += d * d
    return np.sqrt(out)


def _reach(xyz: np.ndarray, arc: np.ndarray, i: np.ndarray, budget: np.ndarray) -> np.ndarray:
    """For each start ``i``, the last sample ``j`` with ``def(i, j) <= budget`` (at least ``i + 1``)."""
    n = arc.size
    lo = np.minimum(i + 1, n - 1)  # always allowed: a one-sample chord has zero deficit
    hi = np.full_like(i, n - 1)
    ok = arc[hi] - arc[i] - _chord(xyz, i, hi) <= budget
    lo = np.where(ok, hi, lo)
    while True:  # invariant: lo allowed, hi allowed only when lo == hi
        open_ = hi - lo > 1
        if not open_.any():
            return lo
        mid = (lo + hi) // 2
        good = arc[mid] - arc[i] - _chord(xyz, i, mid) <= budget
        lo = np.where(open_ & good, mid, lo)
        hi = np.where(open_ & ~good, mid, hi)


class _Band:
    """Chord lengths ``|p_j - p_{j-o}|`` by row j, offsets in decreasing order (the last column is o = 1).

    ``rows(w, j0, j1)`` gives rows ``j0..j1-1`` for offsets ``w..1``. The full band is cached while it has
    at most ``DENSE_LIMIT`` entries; wider bands are computed per block of rows on demand.
    """

    def __init__(self, xyz: np.ndarray):
        self.xyz = xyz
        self.width = 0
        self.data = np.empty((xyz.shape[1], 0))

    def _compute(self, width: int, j0: int, j1: int) -> np.ndarray:
        pad = np.concatenate([np.zeros((self.xyz.shape[0], width)), self.xyz], axis=1)
        win = np.lib.stride_tricks.sliding_window_view(pad, width, axis=1)[:, j0:j1]  # column t: width - t
        return np.sqrt(((self.xyz[:, j0:j1, None] - win) ** 2).sum(axis=0))

    def rows(self, width: int, j0: int, j1: int) -> np.ndarray:
        n = self.xyz.shape[1]
        if width <= self.width:
            return self.data[j0:j1, self.width - width:]
        if n * width > DENSE_LIMIT:
            return self._compute(width, j0, j1)
        self.width = min(max(width, 2 * self.width), n - 1, DENSE_LIMIT // n)
        self.data = self._compute(self.width, 0, n)
        return self.data[j0:j1, self.width - width:]


def _layer_dense(m: np.ndarray, changed: np.ndarray, reach: np.ndarray, band: _Band, j0: int, j1: int,
                 width: int) -> tuple[np.ndarray, np.ndarray]:
    """Best candidate and its predecessor for rows ``j0..j1``, by blocks of rows.

    A block looks back only to the first changed state whose reach gets to the block (``reach`` is
    non-decreasing, since ``def(i, j)`` falls as ``i`` grows), so long reaches elsewhere cost it nothing.
    """
    src = np.full(m.size + width, -np.inf)
    src[width + changed] = m[changed]  # only changed states propagate
    win = np.lib.stride_tricks.sliding_window_view(src, width)  # win[j, t] = value of state j + t - width
    best = np.full(j1 + 1 - j0, -np.inf)
    pred = np.zeros(j1 + 1 - j0, dtype=np.int64)
    ends = reach[changed]
    step = max(1, min(BLOCK_ROWS, DENSE_LIMIT // (4 * width)))
    buf = np.empty(step * width)
    for r0 in range(j0, j1 + 1, step):
        r1 = min(r0 + step, j1 + 1)
        pos = np.searchsorted(ends, r0)
        if pos == changed.size or changed[pos] >= r1 - 1:
            continue
        w = min(width, r1 - 1 - int(changed[pos]))
        cand = buf[:(r1 - r0) * w].reshape(r1 - r0, w)
        np.add(win[r0:r1, width - w:], band.rows(w, r0, r1), out=cand)  # column t: offset w - t
        arg = cand.argmax(axis=1)
        best[r0 - j0:r1 - j0] = cand[np.arange(r1 - r0), arg]
        pred[r0 - j0:r1 - j0] = np.arange(r0, r1) - w + arg
    return best, pred


def _layer_sparse(m: np.ndarray, xyz: np.ndarray, changed: np.ndarray,
                  ends: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidates over the exact (changed state, allowed chord) pairs: targets, values, predecessors."""
    counts = ends - changed
    total = int(counts.sum())
    starts = np.repeat(changed, counts)
    first = np.repeat(np.cumsum(counts) - counts, counts)
    stops = starts + 1 + (np.arange(total) - first)
    return stops, m[starts] + _chord(xyz, starts, stops), starts


def _sweep(xyz: np.ndarray, arc: np.ndarray, budget: float, *, k_max: int,
           target: float | None) -> tuple[int, float, np.ndarray]:
    """Run layers until ``M_k[last] >= target`` (if given) or ``k == k_max``; return k, M_k[last], path."""
    n = arc.size
    last = n - 1
    m = np.full(n, -np.inf)
    m[0] = 0.0
    changed = np.array([0])
    layers: list[tuple[np.ndarray, np.ndarray]] = []  # per layer: improved states and their predecessors
    floor = arc - budget  # a state below this is over budget
    band = _Band(xyz)
    reach = _reach(xyz, arc, np.arange(n), np.full(n, budget))  # no chord beyond: it alone exceeds the budget
    k = 0
    while k < k_max and changed.size:
        if target is not None and m[last] >= target:
            break
        k += 1
        ends = reach[changed]
        width = int((ends - changed).max())
        j0, j1 = int(changed[0]) + 1, int(ends.max())
        pairs = int((ends - changed).sum())
        new = m.copy()
        pred = np.empty(n, dtype=np.int64)
        if width and (j1 - j0 + 1) * width <= 3 * pairs:
            best, arg = _layer_dense(m, changed, reach, band, j0, j1, width)
            rows = np.arange(j0, j1 + 1)
            up = (best > m[rows]) & (best >= floor[rows])
            new[rows[up]] = best[up]
            pred[rows[up]] = arg[up]
        elif pairs:
            stops, cand, starts = _layer_sparse(m, xyz, changed, ends)
            keep = cand >= floor[stops]
            starts, stops, cand = starts[keep], stops[keep], cand[keep]
            np.maximum.at(new, stops, cand)
            best = (cand == new[stops]) & (cand > m[stops])
            pred[stops[best]] = starts[best]
        improved = np.flatnonzero(new > m)
        layers.append((improved.astype(np.int32), pred[improved].astype(np.int32)))  # int32: k x n of them
        m = new
        changed = improved
    path = _path(layers, last) if np.isfinite(m[last]) else np.array([], dtype=np.int64)
    return k, float(m[last]), path


def _path(layers: list[tuple[np.ndarray, np.ndarray]], last: int) -> np.ndarray:
    """Vertex indices of the optimum ending at ``last`` from the per-layer improvements."""
    out = [last]
    j = last
    for improved, pred in reversed(layers):
        if j == 0:
            break
        pos = np.searchsorted(improved, j)
        if pos < improved.size and improved[pos] == j:
            j = int(pred[pos])
            out.append(j)
    return np.array(out[::-1])


def _greedy(xyz: np.ndarray, arc: np.ndarray, cap: float, limit: int) -> np.ndarray | None:
    """Vertices of the greedy polyline whose every chord has deficit at most ``cap`` (farthest reach),
    or ``None`` when it needs more than ``limit`` segments."""
    n = arc.size
    idx = np.arange(n)
    reach = _reach(xyz, arc, idx, np.full(n, cap))
    out = [0]
    while out[-1] < n - 1:
        if len(out) > limit:
            return None
        out.append(int(reach[out[-1]]))
    return np.array(out)


def _length(xyz: np.ndarray, idx: np.ndarray) -> float:
    return float(_chord(xyz, idx[:-1], idx[1:]).sum())


def max_length_polyline(points: Any, k: int) -> tuple[float, np.ndarray]:
    """The longest polyline with at most ``k`` segments through a subsequence of ``points``, ends fixed.

    Returns ``(length, indices)``. Exact over the samples (see the module docstring); with at least
    ``k + 1`` samples the optimum uses exactly ``k`` segments, since splitting a chord never shortens it.
    """
    xyz, arc = _prepare(points)
    n = arc.size
    k = int(k)
    if k < 1:
        raise InputError(f"k must be at least 1, got {k}")
    if k >= n - 1:
        idx = np.arange(n)
        return _length(xyz, idx), idx
    # A feasible k-segment polyline bounds the optimum's deficit: bisect the per-chord cap of the greedy.
    lo, hi = 0.0, float(arc[-1]) + 1.0
    feasible = _greedy(xyz, arc, hi, k)
    for _ in range(60):
        cap = 0.5 * (lo + hi)
        found = _greedy(xyz, arc, cap, k)
        if found is None:
            lo = cap
        else:
            hi, feasible = cap, found
        if hi - lo <= 1e-3 * hi:
            break
    budget = (arc[-1] - _length(xyz, feasible)) * (1 + 1e-9) + RTOL * arc[-1]
    _, length, path = _sweep(xyz, arc, budget, k_max=k, target=None)
    return length, path


def min_segments(points: Any, target_length: float) -> tuple[int, np.ndarray]:
    """The fewest segments whose best polyline through a subsequence of ``points`` (ends fixed) has
    length at least ``target_length`` (up to a relative ``RTOL``). Returns ``(count, indices)``.

    Raises :class:`InputError` when even the polyline through every sample is shorter than the target.
    """
    xyz, arc = _prepare(points)
    total = float(arc[-1])
    slack = RTOL * max(total, abs(float(target_length)))
    target = float(target_length) - slack
    if not target <= total:
        raise InputError(f"target length {target_length!r} exceeds the sampled polyline length {total!r}; "
                         "sample more densely")
    budget = total - target
    k, length, path = _sweep(xyz, arc, budget, k_max=arc.size - 1, target=target)
    return k, path


def _measure(arc: np.ndarray, curv: np.ndarray, turn: np.ndarray) -> np.ndarray:
    """Each piece's share of the samples: a mix of arc length, ``curvature**(2/3)`` arc length (the
    density of optimal vertices, so every segment of an optimum gets about as many samples) and turning
    (a point mass at cusps and corners, so a sample lands on them). Shares sum to 1 unless all are 0."""
    parts = [(ARC_SHARE, arc), (CURVATURE_SHARE, curv), (TURNING_SHARE, turn)]
    live = [(w, x / x.sum()) for w, x in parts if x.sum() > 0]
    if not live:
        return np.zeros_like(arc)
    return sum(w * x for w, x in live) / sum(w for w, _ in live)


def _turning(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle between consecutive chord vectors ``a`` and ``b`` (rows), 0 where either is degenerate."""
    na, nb = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
    ok = (na > 0) & (nb > 0)
    cos = np.ones_like(na)
    cos[ok] = (a[ok] * b[ok]).sum(axis=1) / (na[ok] * nb[ok])
    return np.arccos(np.clip(cos, -1.0, 1.0))


def dense_samples(curve: Any, domain: tuple[float, float] | None = None, n: int = 4000, *,
                  initial: int | None = None, include: Any = None, oversample: int = 3,
                  max_rounds: int = 60) -> tuple[np.ndarray, np.ndarray]:
    """About ``n`` samples of ``curve`` spread for the sampled optimum: ``(params, points)``, points (m, 3).

    Derivative-free. Starting from ``initial`` (default ``n``) uniform parameters, intervals are bisected
    while their share of a measure mixing arc length, ``curvature**(2/3)`` arc length and turning (see
    ``_measure``) exceeds ``1 / (oversample * n)``, or while their midpoint still adds more than ``1e-12``
    of the length (which pins cusps and corners down to rounding level). Uneven speed (by 1e4 or more)
    costs nothing, since every share is measured in space, not in parameter. A feature narrower than the
    initial spacing is found only if some initial sample touches it. The fine set (several times ``n``
    points) is then thinned to about ``n`` samples at equal quantiles of the same measure, ends kept.
    Parameters in ``include`` (e.g. a grid's own vertices) are added after thinning.
    """
    from ..refine import resolve_domain
    c = as_curve(curve, domain)
    a, b = resolve_domain(c, domain)
    n = int(n)
    if n < 3:
        raise InputError(f"n must be at least 3, got {n}")
    ev = Evaluator(c)
    u = np.linspace(a, b, max(n, int(initial or n)))
    p = ev(u)
    um = 0.5 * (u[:-1] + u[1:])
    q = ev(um)
    min_du = 8 * np.finfo(float).eps * max(abs(a), abs(b), b - a)
    for _ in range(max_rounds):
        left = np.linalg.norm(q - p[:-1], axis=1)
        right = np.linalg.norm(p[1:] - q, axis=1)
        h = left + right
        gain = np.maximum(h - np.linalg.norm(p[1:] - p[:-1], axis=1), 0.0)
        # the midpoint adds gain ~ kappa**2 h**3 / 32 over the chord, so kappa**(2/3) h ~ cbrt(32 gain)
        share = _measure(h, np.cbrt(32.0 * gain), _turning(q - p[:-1], p[1:] - q))
        split = (share > 1.0 / (oversample * n)) | (gain > 1e-12 * h.sum())
        split &= np.diff(u) > min_du
        if not split.any():
            break
        idx = np.flatnonzero(split)
        u = np.insert(u, idx + 1, um[idx])
        p = np.insert(p, idx + 1, q[idx], axis=0)
        # midpoints: old ones for unsplit intervals, two new ones for each split interval
        half = np.flatnonzero(np.repeat(split, np.where(split, 2, 1)))
        um_new = 0.5 * (u[:-1] + u[1:])
        todo = np.zeros(len(um_new), dtype=bool)
        todo[half] = True
        q_new = np.empty((len(um_new), 3))
        q_new[~todo] = q[~split]
        q_new[todo] = ev(um_new[todo])
        um, q = um_new, q_new
    fine_u = np.empty(2 * len(u) - 1)
    fine_u[0::2], fine_u[1::2] = u, um
    fine_p = np.empty((len(fine_u), 3))
    fine_p[0::2], fine_p[1::2] = p, q
    u, p = _thin(fine_u, fine_p, n)
    if include is not None:
        extra = np.setdiff1d(np.clip(np.asarray(include, dtype=float).ravel(), a, b), u)
        if extra.size:
            u = np.concatenate([u, extra])
            order = np.argsort(u, kind="stable")
            u, p = u[order], np.concatenate([p, ev(extra)])[order]
    return u, p


def _thin(u: np.ndarray, p: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """About ``n`` of the samples at equal quantiles of the sampling measure, ends kept."""
    if len(u) <= n:
        return u, p
    seg = np.diff(p, axis=0)
    ds = np.linalg.norm(seg, axis=1)
    turn = np.concatenate([[0.0], _turning(seg[:-1], seg[1:]), [0.0]])
    arc_v = 0.5 * (np.concatenate([[0.0], ds]) + np.concatenate([ds, [0.0]]))
    curv_v = np.cbrt(turn ** 2 * arc_v)  # (kappa ds)**(2/3) ds**(1/3) = kappa**(2/3) ds at each vertex
    weight = _measure(arc_v, curv_v, turn)
    if weight.sum() <= 0:
        keep = np.unique(np.linspace(0, len(u) - 1, n).round().astype(int))
        return u[keep], p[keep]
    cum = np.cumsum(weight)
    cum /= cum[-1]
    count = n
    for _ in range(8):  # point masses (cusps) collapse several quantiles onto one sample: ask for more
        q = (np.arange(count) + 0.5) / count
        keep = np.unique(np.concatenate([[0, len(u) - 1], np.minimum(np.searchsorted(cum, q), len(u) - 1)]))
        if keep.size >= n - 1:
            break
        count = int(count * n / keep.size) + 1
    return u[keep], p[keep]


def sampled_optimum(curve: Any, domain: tuple[float, float] | None, target_length: float, *,
                    n: int | None = None, initial: int = 4096, include: Any = None) -> int:
    """The sampled optimum: the fewest segments reaching ``target_length`` through :func:`dense_samples`.

    Passing a grid's own parameters as ``include`` makes the optimum never worse than that grid (its
    polyline is then one of the candidates), so a grid placed better than the samples allow does not
    show a ratio below 1.

    With ``n`` omitted the sample count adapts: a first pass with 1000 samples estimates the count ``m``,
    and a second pass uses ``SAMPLES_PER_SEGMENT * m`` samples (at most ``MAX_SAMPLES``), so the optimum
    is within a fraction of a percent of its converged value while the cost, about ``n**2 m**(1/3)``
    band entries, stays small. Samples are doubled while the sample polyline is shorter than the target.
    """
    size = 1000 if n is None else int(n)
    while True:
        _, pts = dense_samples(curve, domain, size, initial=max(initial, size), include=include)
        try:
            count = min_segments(pts, target_length)[0]
        except InputError:
            if size >= MAX_SAMPLES:
                raise
            size = min(2 * size, MAX_SAMPLES)
            continue
        want = min(SAMPLES_PER_SEGMENT * count, MAX_SAMPLES)
        if n is not None or want <= 1.5 * size:
            return count
        n = size = want
