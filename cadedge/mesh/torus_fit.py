"""How the boundary fit cuts a torus face meshed as a grid (:mod:`cadedge.mesh.gridded`): its tube arc
into rows, its two parallels into as many columns at the same angles.

A torus face round the whole ring between two of its parallels, joined by one arc of its tube (a small
fillet along a circular edge), is laid out as a grid whose columns run across the tube and whose rows
run round the ring. Its area deficit is about that of the rows' polygon on the tube arc
(:func:`torus_rows`), and the columns must leave node ``i`` of one parallel beside node ``i`` of the
other all the way round (:func:`torus_fit`), or the grid's cells shear.
"""

from __future__ import annotations

import numpy as np

from ..splitting import split_evenly
from .gridded import GridFit, polygon_count, polygon_deficit

#: A torus face's rows (the polygon on its tube's arc, raised for the inner side of the torus: flat cells
#: there lose more than the polygon's share, by up to ``2 r / rho``) take this share of its target at
#: most; the rest is for its columns' polygon round the ring and for rows up to :data:`TALLER` taller
#: than asked.
TORUS_SHARE = 0.99
#: A segment of the tube's arc this much taller than the grid's rows is kept as one row: the arc's own
#: segments, equal to rounding, would otherwise each be cut in two (a whole 0.2 mm torus at 1e-3: its
#: tube circle's 41 segments of 0.0306 mm into 82 rows, 2.4 million triangles where 41 rows take 0.59).
TALLER = 1e-3
#: A torus face is meshed as a grid only if its parallels' radii are within this ratio of each other: its
#: columns are as many on both, so their widths differ by that ratio (a 0.2 mm fillet on a 35 mm edge:
#: 1.006).
RING_SPREAD = 1.1


def torus_rows(target: float, turn: float, minor: float, ring: float) -> int:
    """The fewest rows on a torus face's tube arc of ``turn`` radians (tube radius ``minor``, the ring's
    smallest radius on the face ``ring``) whose grid, with columns as wide as the rows are tall round the
    whole ring, is within ``target``: the rows' polygon deficit, raised by ``2 minor / ring`` for the
    inner side of the torus, within :data:`TORUS_SHARE` of it, the columns' within the rest. Round the
    whole tube (``turn`` 2 pi) the inner side's loss and the outer side's gain cancel: pass ``ring``
    infinite.

    >>> torus_rows(1e-3, np.pi / 2, 0.2, 34.8), torus_rows(1e-2, np.pi / 2, 0.2, 34.8)
    (11, 4)
    >>> torus_rows(1e-3, 2 * np.pi, 0.2, np.inf)
    41
    """
    n = polygon_count(TORUS_SHARE * target, turn)
    while True:
        columns = max(int(np.rint(2.0 * np.pi * min(ring, 1e300) * n / (minor * turn))), 3)
        rows = float(polygon_deficit(n, turn)) * (1.0 + 2.0 * minor / ring)
        if rows <= TORUS_SHARE * target and rows + float(polygon_deficit(columns)) <= target:
            return n
        n += 1


def _pieces(share: np.ndarray, total: int) -> np.ndarray:
    """Whole numbers of pieces, at least one each, summing to ``total`` (or one each if that is fewer),
    their running sums each within half a piece of the running sum of ``share`` (scaled to ``total``
    beside the segments held at one piece): two parallels so cut from the seam round stay within a
    column of each other all the way round. Rounding each segment alone (largest remainders) drifted
    14 columns apart halfway round flange_200's groove.

    >>> _pieces(np.array([2.6, 0.2, 3.2]), 6).tolist(), _pieces(np.array([1.4, 1.4, 1.4, 1.4, 1.4]), 7).tolist()
    ([2, 1, 3], [1, 2, 1, 2, 1])
    """
    one = np.zeros(len(share), dtype=bool)
    while True:  # segments of less than a piece get one; the others share what is left
        free = max(total - int(one.sum()), 0)
        scaled = np.where(one, 1.0, share * free / max(float(share[~one].sum()), 1e-300))
        if not np.any(~one & (scaled < 1.0)) or free == 0:
            break
        one |= scaled < 1.0
    ends = np.rint(np.cumsum(np.maximum(scaled, 1.0)))
    return np.diff(np.concatenate([[0.0], ends])).astype(int).clip(min=1)


def _cut_evenly(params: np.ndarray, columns: int) -> np.ndarray:
    """A parallel's parameters (its grid's, all kept) cut into ``columns`` segments in all, each segment
    into equal parameter steps, as many as its share of the turn (a circle's parameter is its angle;
    :func:`_pieces`).

    >>> (_cut_evenly(np.array([0.0, np.pi, 1.5 * np.pi, 2 * np.pi]), 8) / np.pi * 4).round(6).tolist()
    [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]
    """
    span = np.diff(params)
    pieces = _pieces(columns * span / span.sum(), columns)
    return np.sort(np.concatenate([params, split_evenly(params, pieces)]))


def _aligned(a: np.ndarray, b: np.ndarray, same_way: bool) -> tuple[np.ndarray, np.ndarray] | None:
    """Two parallels cut for a grid (their parameters ``a`` and ``b``, from the seam round; ``same_way``
    if they run the same way round the axis) of which another pass split one further (a grading, a
    proximity split): each node of one without a node of the other within half a segment of it (as
    shares of the turn; the nearest of each other) is copied onto the other at its share, so both carry
    as many nodes at the same angles and the columns stay straight; None if they cannot be.

    >>> x, y = _aligned(np.array([0.0, 1.0, 2.0, 4.0]), np.array([0.0, 1.0, 1.5, 2.0, 4.0]), True)
    >>> x.tolist(), y.tolist()
    ([0.0, 1.0, 1.5, 2.0, 4.0], [0.0, 1.0, 1.5, 2.0, 4.0])
    >>> [c.tolist() for c in _aligned(np.array([0.0, 1.0, 2.0, 4.0]), np.array([0.0, 2.5, 3.0, 4.0]), False)]
    [[0.0, 1.0, 1.5, 2.0, 4.0], [0.0, 2.0, 2.5, 3.0, 4.0]]
    """
    fa = (a - a[0]) / (a[-1] - a[0])
    fb = (b - b[0]) / (b[-1] - b[0])
    if not same_way:
        fb = 1.0 - fb[::-1]
    tol = 0.5 / max(len(a) - 1, len(b) - 1)

    def nearest(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        i = np.clip(np.searchsorted(y, x), 1, len(y) - 1)
        return np.where(np.abs(y[i - 1] - x) <= np.abs(y[i] - x), i - 1, i)

    na, nb = nearest(fa, fb), nearest(fb, fa)
    pair_a = (nb[na] == np.arange(len(fa))) & (np.abs(fb[na] - fa) < tol)
    pair_b = np.zeros(len(fb), dtype=bool)
    pair_b[na[pair_a]] = True
    ja = np.sort(np.concatenate([fa, fb[~pair_b]]))
    jb = np.sort(np.concatenate([fb, fa[~pair_a]]))
    if len(ja) != len(jb) or np.any(np.diff(ja) <= 0) or np.any(np.diff(jb) <= 0):
        return None
    if not same_way:
        jb = 1.0 - jb[::-1]
    ca, cb = a[0] + ja * (a[-1] - a[0]), b[0] + jb * (b[-1] - b[0])
    ca[nearest(a, ca)], cb[nearest(b, cb)] = a, b  # their own nodes exactly as they were
    return ca, cb


def _turn(e) -> float:
    """The angle a circle edge turns through (its parameter is its angle)."""
    return float(abs(e.params[-1] - e.params[0]))


def _radius(e) -> float:
    """The radius of a circle edge from its polygon (:func:`polygon_deficit` of equal chords)."""
    turn = _turn(e)
    return float(e.segment_lengths.sum()) / (turn * (1.0 - float(polygon_deficit(len(e.segment_lengths), turn))))


def torus_fit(edges: list, target: float) -> GridFit | None:
    """The :class:`GridFit` of a torus face bounded by two closed parallels and one arc of its tube (its
    seam) between them, of a torus along an arc (two arcs of parallels, two alike of its tube), or of a
    whole torus (one parallel and one circle of its tube, each its seam), or None: rows no taller than
    the arc's length over :func:`torus_rows` (a torus along an arc: its two tube arcs cut alike), the
    parallels cut evenly into columns about as wide (no fewer than either has), or, cut already, aligned
    where another pass split one further (:func:`_aligned`); only where the parallels' radii, and the
    ring's inside the face, are within :data:`RING_SPREAD` of each other."""
    if len(edges) not in (2, 3, 4) or any(e.curve != "Circle" for e in edges):
        return None
    closed = [bool(np.allclose(e.points[0], e.points[-1])) for e in edges]
    ends = []  # a torus along an arc: its tube's two arcs at the ends, cut alike
    if len(edges) == 3 and sum(closed) == 2:
        seam = edges[closed.index(False)]
        rings = [e for e, c in zip(edges, closed) if c]
        turn = _turn(seam)
    elif len(edges) == 2 and all(closed):  # a whole torus: the smaller circle is its tube's
        seam, ring = sorted(edges, key=_radius)
        rings, turn = [ring], 2.0 * np.pi
    elif len(edges) == 4 and not any(closed):  # the two smaller arcs are its tube's, alike
        by_radius = sorted(edges, key=_radius)
        ends, rings = by_radius[:2], by_radius[2:]
        if not np.isclose(_radius(ends[0]), _radius(ends[1]), rtol=1e-3) or not np.isclose(
                _turn(ends[0]), _turn(ends[1]), rtol=1e-3):
            return None
        seam = max(ends, key=lambda e: len(e.params))
        turn = _turn(seam)
    else:
        return None
    arc = seam.segment_lengths
    if not 0.0 < turn <= 2.0 * np.pi or not arc.sum() > 0.0:
        return None
    minor = float(arc.sum()) / (turn * (1.0 - float(polygon_deficit(len(arc), turn))))
    radius = [_radius(e) for e in rings]
    inner = min(radius) - (2.0 * minor if len(rings) == 1 else 0.0)  # a whole torus's inner side
    if inner <= 0.0 or max(max(radius), inner + 2.0 * minor) > RING_SPREAD * inner:
        return None
    tall = float(arc.sum()) / torus_rows(target, turn, minor, inner if len(rings) == 2 else np.inf)
    # each of the arc's segments in the fewest equal steps no taller than that (TALLER spared)
    pieces = np.maximum(np.ceil(arc / tall / (1.0 + TALLER)), 1).astype(int)
    rows = np.sort(np.concatenate([seam.params, split_evenly(seam.params, pieces)]))
    sides = [(seam.id, rows)] if not ends else [(e.id, _cut_evenly(e.params, len(rows) - 1)) for e in ends]
    tall = float(arc.sum()) / (len(rows) - 1)
    columns = int(np.rint(_turn(rings[0]) * float(np.mean(radius)) / tall))

    def way(e) -> np.ndarray:  # which way round the axis the parallel runs from the seam
        p = e.points[[0, len(e.points) // 3, 2 * len(e.points) // 3]]
        return np.cross(p[1] - p[0], p[2] - p[0])

    counts = [len(e.params) - 1 for e in rings]
    if max(counts) < 0.95 * columns:  # not cut yet: each evenly into the columns, within one of each other
        cuts = [_cut_evenly(e.params, max(columns, *counts)) for e in rings]
    elif len(set(counts)) == 1:  # cut already
        cuts = [e.params for e in rings]
    else:
        cuts = _aligned(rings[0].params, rings[1].params, float(np.dot(way(rings[0]), way(rings[1]))) > 0)
        if cuts is None:
            return None
    return GridFit(tall, (), tuple((e.id, c) for e, c in zip(rings, cuts)) + tuple(sides))
