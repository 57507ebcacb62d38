"""Stagger the boundary nodes across a thin face, so that its triangles are isosceles rather than right.

The thin faces' splits (:mod:`cadedge.mesh.widths`) cut both sides of a strip of width w into pieces of
about r w. Cut alike, both sides' nodes face each other, and a strip with no room for interior nodes is
filled with right triangles of legs w and r w: atan(1 / r), 26.6 degrees at r = 2 and 14.0 at r = 4 (a
plane of the Koch leader arm holds a strip 5e-5 wide and 2.87 long; the splits' budget cut it at r = 4,
and two thirds of the face's 42 500 triangles were under 20 degrees). With one side's nodes halfway
between the other's, the same nodes make isosceles triangles of base r w and height w: atan(2 / r),
45 degrees at r = 2 and 26.6 at r = 4. :func:`~cadedge.mesh.widths.fit_to_widths` staggers where its
ratio leaves right triangles under 20 degrees (:data:`~cadedge.mesh.widths.STAGGER_RATIO`).

Two edges *face* each other in a face where both were split and the nodes of one find their nearest node of
the face, among edges touching no vertex they touch, on the other within :data:`FACING` times their own
spacing. The edges so paired are coloured in two, component by component from the lowest edge index, and the
second colour's edges are *shifted*: a stretch of new nodes that face one partner (its neighbouring segments
within :data:`UNEVEN` of each other) is replaced by the midpoints between the partner's nodes, projected
onto the edge and placed on its curve. The points the edges were refined with stay (the polyline through
them meets the ALD, and any polyline through more points on the curve is no shorter), as do edge ends; a
stretch is left as it was where the midpoints would make a segment longer than :data:`LONGEST` times the
longest it replaces, shorter than :data:`SHORTEST` times the shortest at its ends or :data:`EVEN` times
between them (the partner is coarser, finer or askew there), or shorter than a loose edge allows
(:class:`~cadedge.mesh.proximity.Looseness`). An odd cycle of paired edges keeps one pair unstaggered.
"""

from __future__ import annotations

import dataclasses
from collections import deque

import numpy as np

from ..grid import row_norms
from ..shapegrid import ShapeGrid, with_edges
from ..splitting import worst_growth
from .proximity import Looseness
from .segments import segment_feet

#: A node faces the nearest node of another edge within this many times its own spacing (the longer of
#: its two segments): node facing node at r w, the partner's is 1 / r spacings away (a half at r = 2,
#: where the right triangles are 26.6 degrees), at most (1 / r^2 + 1 / 4)^0.5 where already offset (0.56
#: at r = 4). Below r = 2 staggering gains little: at 1.5 spacings it paired the sides of the Koch leader
#: arm's planes 0.5 wide, cut into pieces of about 0.5, and left slivers of 0.38 degrees there.
FACING = 0.6
#: The partner's nodes are projected onto a stretch from this many times its longest segment away.
REACH = 1.5
#: A shifted stretch's segments stay within these shares of the segments they replace, and it gains at
#: most two nodes (else it is left as it was): the midpoints of a partner a little coarser (the outer side
#: of a curved strip) lengthen its segments by at most this, where splitting them would double its nodes.
LONGEST = 1.05
#: A stretch's end piece is about half a piece, less where the partner's last node falls short of the
#: stretch's end: 0.395 of a piece at the end of the leader arm's strip, whose partner runs on past it.
SHORTEST = 0.25
#: Between its end pieces a stretch's segments stay at least this share of the shortest they replace (a
#: partner across at an angle projects its nodes unevenly; where the old nodes meet the midpoints the gap
#: is half a spacing or more).
EVEN = 0.5
#: Only a stretch whose neighbouring segments are within this factor of each other (a strip's splits:
#: equal pieces, or halved towards a tiny edge) is staggered: a hole's circle beside a line across a
#: narrow bridge of a wide plane (Koch leader arm) had a node between segments of 0.105 and 0.84, and
#: staggered it made triangles of 9.5 degrees (18.4 as cut).
UNEVEN = 2.0 * (1.0 + 1e-9)
#: Nodes nearer than this share of the partner's spacing are one.
CLOSE = 0.3
#: Nearest nodes asked per node: its own edge's neighbours and those of edges at its vertices come first.
NEIGHBOURS = 12


def stagger(before: ShapeGrid, fitted: ShapeGrid, *, curves, touches: dict[int, set[int]],
            keep: ShapeGrid | None = None) -> ShapeGrid:
    """``fitted`` (``before`` after the thin faces' splits) with one side of every thin strip staggered
    against the other (module doc). ``curves`` evaluate the edges by id; ``touches`` are the vertices
    each edge touches (:func:`cadedge.mesh.widths.touching_vertices`); ``keep`` (the same edges as
    refined, by default ``before``) holds the points that never move."""
    edges = list(fitted.edges)
    keep = keep if keep is not None else before
    split = [i for i, (a, b) in enumerate(zip(before.edges, edges))
             if not b.degenerate and len(b.points) > len(a.points) and np.all(np.diff(b.params) > 0)]
    if len(split) < 2:
        return fitted
    added = {i: ~np.isin(edges[i].params, keep.edges[i].params) for i in split}
    partner = _partners(edges, split, added, touches)
    colour = _two_colours({i: set(p[p >= 0].tolist()) & set(split) for i, p in partner.items()})
    loose = Looseness(fitted)
    changed, first = False, [j for j, c in colour.items() if c == 0]
    for i in sorted(k for k, c in colour.items() if c == 1):
        faced = np.where(np.isin(partner[i], first), partner[i], -1)
        grid = _shifted(edges[i], added[i], faced, edges, curves[edges[i].id].evaluate, loose)
        if grid is not None:
            edges[i] = dataclasses.replace(edges[i], params=grid[0], points=grid[1])
            changed = True
    return with_edges(fitted, edges) if changed else fitted


def _partners(edges: list, split: list[int], added: dict[int, np.ndarray],
              touches: dict[int, set[int]]) -> dict[int, np.ndarray]:
    """Per split edge index, per node, the index of the edge its node faces (-1: none, or a node the
    splits did not add), over the faces it bounds; one k-d tree of each face's nodes."""
    from scipy.spatial import cKDTree

    def touched(k: int) -> set[int]:
        return touches.get(edges[k].id, set(edges[k].vertices))

    on_face: dict[int, list[int]] = {}
    for k, e in enumerate(edges):
        if not e.degenerate and len(e.points) >= 2:
            for f in set(e.faces):
                on_face.setdefault(f, []).append(k)
    partner = {i: np.full(len(edges[i].points), -1, dtype=np.int64) for i in split}
    best = {i: np.full(len(edges[i].points), np.inf) for i in split}
    wanted = set(split)
    for f in sorted({f for i in split for f in edges[i].faces}):
        idx = on_face.get(f, [])
        mine = [i for i in idx if i in wanted]
        if len(idx) < 2 or not mine:
            continue
        owner = np.repeat(idx, [len(edges[k].points) for k in idx])
        tree = cKDTree(np.vstack([edges[k].points for k in idx]))
        apart = {k: np.array([not touched(k) & touched(j) for j in idx]) for k in mine}
        local = np.full(len(edges), -1, dtype=np.int64)
        local[idx] = np.arange(len(idx))
        for i in mine:
            e = edges[i]
            rows = np.flatnonzero(added[i])
            if not len(rows):
                continue
            seg = row_norms(np.diff(e.points, axis=0))
            spacing = np.maximum(seg[rows - 1], seg[rows])
            dist, near = tree.query(e.points[rows], k=min(NEIGHBOURS, len(owner)))
            who = owner[near]
            ok = apart[i][local[who]] & np.isfinite(dist)
            first = np.argmax(ok, axis=1)
            d = np.where(ok.any(axis=1), dist[np.arange(len(rows)), first], np.inf)
            hit = (d <= FACING * spacing) & (d < best[i][rows])
            partner[i][rows[hit]] = who[np.arange(len(rows)), first][hit]
            best[i][rows[hit]] = d[hit]
    return partner


def _two_colours(arcs: dict[int, set[int]]) -> dict[int, int]:
    """0 or 1 per edge index that faces another (``arcs``, made symmetric here), neighbours apart where
    the pairs allow: breadth first from the lowest index of each component."""
    both: dict[int, set[int]] = {}
    for i, js in arcs.items():
        for j in js:
            both.setdefault(i, set()).add(j)
            both.setdefault(j, set()).add(i)
    colour: dict[int, int] = {}
    for root in sorted(both):
        if root in colour:
            continue
        colour[root], todo = 0, deque([root])
        while todo:
            i = todo.popleft()
            for j in sorted(both[i]):
                if j not in colour:
                    colour[j] = 1 - colour[i]
                    todo.append(j)
    return colour


def _shifted(e, added: np.ndarray, faced: np.ndarray, edges: list, evaluate, loose: Looseness):
    """Edge ``e``'s grid with each stretch of added nodes facing one partner (``faced``, per node an
    edge index or -1) staggered against the partner (module doc), or None where no stretch changes."""
    u, p = e.params, e.points
    seg = row_norms(np.diff(p, axis=0))
    keep = np.ones(len(u), dtype=bool)
    new_u: list[np.ndarray] = []
    new_p: list[np.ndarray] = []
    label = np.where(added & (faced >= 0), faced, -1)
    start = np.flatnonzero(np.diff(label, prepend=-2) != 0)  # runs of one label
    for s, t in zip(start, np.append(start[1:], len(u)) - 1):
        old = seg[s - 1:t + 1]
        if label[s] < 0 or not worst_growth(p[s - 1:t + 2]) <= UNEVEN:
            continue
        nodes = _staggered(u, s - 1, t + 1, _projections(u, p, s - 1, t + 1, edges[label[s]].points))
        if nodes is not None:
            at = evaluate(nodes)
            new = row_norms(np.diff(np.vstack([p[s - 1], at, p[t + 1]]), axis=0))
            if (new.max() <= LONGEST * old.max() and new.min() >= SHORTEST * old.min()
                    and (len(new) < 3 or new[1:-1].min() >= EVEN * old.min())
                    and len(nodes) <= len(old) + 1 and not loose.too_loose(e, float(new.min()))):
                keep[s:t + 1] = False
                new_u.append(nodes)
                new_p.append(at)
    if not new_u:
        return None
    params = np.concatenate([u[keep], *new_u])
    order = np.argsort(params, kind="stable")
    points = np.vstack([p[keep], *new_p])[order]
    return params[order], points


def _projections(u: np.ndarray, p: np.ndarray, lo: int, hi: int, other: np.ndarray) -> np.ndarray:
    """Sorted parameters on the grid ``u``/``p`` between nodes ``lo`` and ``hi`` (inclusive) of the
    projections of the points of ``other`` within :data:`REACH` segments of it (linear in parameter along
    each segment; a point beyond an end projects onto that end)."""
    from scipy.spatial import cKDTree

    ends = p[lo:hi + 1]
    reach = REACH * float(row_norms(np.diff(ends, axis=0)).max())
    dist, k = cKDTree(ends).query(other, distance_upper_bound=2.0 * reach)
    near = np.isfinite(dist)
    q, k = other[near], k[near]
    # the foot on the two segments at the nearest node, the nearer of them
    a = np.stack([np.maximum(k - 1, 0), np.minimum(k, len(ends) - 2)], axis=1)
    d, t = segment_feet(q[:, None], ends[a], ends[a + 1])
    side = np.argmin(d, axis=1)
    rows = np.arange(len(q))
    seg, t, d = a[rows, side] + lo, t[rows, side], d[rows, side]
    return np.unique((u[seg] + t * (u[seg + 1] - u[seg]))[d <= reach])


def _staggered(u: np.ndarray, lo: int, hi: int, at: np.ndarray) -> np.ndarray | None:
    """New parameters for the nodes strictly between ``lo`` and ``hi`` of grid ``u``: halfway between
    consecutive projections ``at`` of the partner's nodes (those within :data:`CLOSE` of their spacing
    after the one before them merged into it), the old ones outside the projections' span kept where at
    least half a spacing from the midpoints, any node nearer than :data:`CLOSE` to a node kept before it
    dropped, and a gap longer than :data:`LONGEST` times the old ones' longest halved; None where fewer
    than two projections."""
    if len(at) < 2:
        return None
    spacing = float(np.median(np.diff(at)))
    close = CLOSE * spacing
    at = at[np.concatenate([[True], np.diff(at) >= close])]
    mids = 0.5 * (at[:-1] + at[1:])
    old = u[lo + 1:hi]
    before, after = old[old <= mids[0] - 0.5 * spacing], old[old >= mids[-1] + 0.5 * spacing]
    nodes = np.concatenate([before[before < at[0]], mids, after[after > at[-1]]])
    nodes = nodes[(nodes > u[lo] + close) & (nodes < u[hi] - close)]
    if not len(nodes):
        return None
    nodes = nodes[np.concatenate([[True], np.diff(nodes) >= close])]
    every = np.concatenate([[u[lo]], nodes, [u[hi]]])
    gap = np.diff(every)
    long = gap > LONGEST * float(np.diff(u[lo:hi + 1]).max())
    return np.sort(np.concatenate([nodes, every[:-1][long] + 0.5 * gap[long]]))
