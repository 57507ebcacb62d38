"""Boundary segments graded into a face's narrow corners.

Where two of a face's edges leave a B-rep vertex at a small angle, the face is a thin wedge there: an
M10 nut's 30-degree chamfer cone touches each flat at one point, and each cone face ends in two cusps
(its circle and the flat's hyperbola tangent there: a 0-degree corner). The edge grids keep the segments
the faces' area targets gave them, about as long in the wedge as outside it, so every triangle near the
corner spans its two sides: the nut at 1e-2 had 6 triangles under 20 degrees at each of its 24 cusps
(3.24% of its triangles). Two things are done at every corner narrower than :data:`WEDGE_DEG`:

- the two segments that end at the corner (its *tips*) are made equally long, the longer one cut at the
  shorter one's length. The triangle on both tips is forced (its angle at the vertex is the wedge's
  opening over the tips), and it is widest with the tips as long as they are; corner matching
  (:func:`cadedge.mesh.widths.match_corners`) halves a tip only where its halves stay that long;
- every other segment on the two sides is cut so that its pieces are at most ``WIDTH_RATIO`` times the
  wedge's width (the distance to the other side's grid), graded along the segment by that width, as thin
  faces are fit to theirs (:mod:`cadedge.mesh.widths`): the strip beyond the tips is then filled by
  triangles of about 27 degrees or more. In a cusp the width grows as the square of the distance from
  the vertex, so the pieces do too.

A corner is graded only where its tips are at most :data:`MAX_JUMP` times the first pieces beside them
(the face on a tip's other side sees that jump). Grid points are kept and edge ends never move, so
shared edges stay conforming. A face whose boundary doubles back on itself at a vertex (a slit: nearly
360 degrees inside) looks the same from its edge grids and is graded too, which costs segments, not
triangle quality.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..shapegrid import ShapeGrid, with_edges
from .grading import cut_on_curve
from .proximity import TOLERANCE_SHARE, _LazyCurves
from .widths import BUDGET_FACTOR, MIN_BUDGET, WIDTH_RATIO, _segment_distances

#: Corners of a face narrower than this many degrees (between its two edges' first segments) are graded.
WEDGE_DEG = 20.0
#: Tips within this ratio of each other are left as they are.
TIP_RATIO = 1.2
#: A segment is cut into at most this many pieces.
MAX_PIECES = 200
#: A corner is graded only where its tips are at most this many times longer than the pieces beside
#: them: the face on the tip's other side sees the jump too, at a boundary node where its triangles fan
#: from the tip's triangle to the pieces' within about 120 degrees, and 6 triangles of 20 degrees grow at
#: most 1.88-fold each (sin 40 / sin 20): 44-fold in all. On the nut at 1e-3, tips 70 times the pieces
#: beside them left that face triangles of 2.4 degrees (1.8 with gmsh's Delaunay); at 1e-2, 22 times,
#: 20.3 degrees.
MAX_JUMP = 24.0
#: Segments up to this share over the bound at their nearer end are left whole: the pieces are graded by
#: the width all along them (see :func:`_graded_cuts`), so they stand up to a sixth over it there.
SLACK = 1.25
#: Points along a segment at which the wedge's width is measured to grade its pieces.
SAMPLES = 16


@dataclass(frozen=True)
class Corner:
    """A face's corner at a B-rep vertex: its two sides as (edge index, whether the edge starts there),
    and the angle in degrees between the sides' first segments."""

    face: int
    vertex: int
    sides: tuple[tuple[int, bool], tuple[int, bool]]
    angle: float


def _from_vertex(e, at_start: bool) -> np.ndarray:
    """The edge grid's points, ordered from the corner's vertex."""
    return e.points if at_start else e.points[::-1]


def narrow_corners(edges: list, *, below: float = WEDGE_DEG) -> list[Corner]:
    """Every corner where a face's boundary meets a B-rep vertex with exactly two edge ends (degenerate
    edges and grids of fewer than two points left out) whose first segments are under ``below`` degrees
    apart."""
    ends: dict[tuple[int, int], list[tuple[int, bool]]] = {}
    for i, e in enumerate(edges):
        if e.degenerate or len(e.points) < 2 or len(e.vertices) < 2:
            continue
        for f in e.faces:
            ends.setdefault((f, e.vertices[0]), []).append((i, True))
            ends.setdefault((f, e.vertices[-1]), []).append((i, False))
    out = []
    for (f, v), sides in ends.items():
        if len(sides) != 2:
            continue
        d = [np.diff(_from_vertex(edges[i], s)[:2], axis=0)[0] for i, s in sides]
        norms = np.linalg.norm(d[0]) * np.linalg.norm(d[1])
        if not norms > 0:
            continue
        angle = float(np.degrees(np.arccos(np.clip(np.dot(d[0], d[1]) / norms, -1.0, 1.0))))
        if angle < below:
            out.append(Corner(face=f, vertex=v, sides=(sides[0], sides[1]), angle=angle))
    return out


def grade_wedges(grid: ShapeGrid, *, below: float = WEDGE_DEG, ratio: float = WIDTH_RATIO) -> ShapeGrid:
    """A copy of ``grid`` whose narrow corners (:func:`narrow_corners`) have tips of equal length and the
    rest of their two sides cut to at most ``ratio`` times the wedge's width (see the module doc)."""
    edges = list(grid.edges)
    corners = narrow_corners(edges, below=below)
    if not corners:
        return grid
    curves = grid.curves if grid.curves is not None else _LazyCurves(grid)
    budget = BUDGET_FACTOR * grid.segments + MIN_BUDGET
    changed = False
    for c in corners:  # the tips first: the longer one cut at the shorter one's length
        tips = [tip_length(edges[k], s) for k, s in c.sides]
        k, s = c.sides[int(np.argmax(tips))]
        if max(tips) > TIP_RATIO * min(tips) and not edges[k].tolerance > TOLERANCE_SHARE * min(tips):
            share = min(tips) / max(tips)
            cut = cut_on_curve(edges[k], curves, {tip_segment(edges[k], s): [share if s else 1 - share]})
            if cut is not None:
                edges[k], changed = cut, True
    tip_segments = {(k, tip_segment(edges[k], s)) for c in corners for k, s in c.sides}
    cuts: dict[int, dict[int, np.ndarray]] = {}  # edge index -> segment -> shares of it to cut at
    for c in corners:
        if _jump(*(_from_vertex(edges[k], s) for k, s in c.sides), ratio) > MAX_JUMP:
            continue
        for (i, s), (j, t) in (c.sides, c.sides[::-1]):
            for k, shares in _graded_cuts(_from_vertex(edges[i], s), _from_vertex(edges[j], t), ratio).items():
                seg, shares = (k, shares) if s else (len(edges[i].points) - 2 - k, 1.0 - shares[::-1])
                if (i, seg) in tip_segments:  # a short edge's far end: another narrow corner's tip stays whole
                    continue
                if len(shares) > len(cuts.setdefault(i, {}).get(seg, ())):
                    cuts[i][seg] = shares
    added = 0
    for i, at in cuts.items():
        e = edges[i]
        new = sum(len(f) for f in at.values())
        shortest = min(e.segment_lengths[k] / (len(f) + 1) for k, f in at.items())
        if not new or added + new > budget or e.tolerance > TOLERANCE_SHARE * shortest:
            continue  # nothing to cut, over the budget, or a loose edge (see proximity.py)
        cut = cut_on_curve(e, curves, at)
        if cut is not None:
            edges[i], changed, added = cut, True, added + new
    return with_edges(grid, edges) if changed else grid


def _jump(one: np.ndarray, two: np.ndarray, ratio: float) -> float:
    """How many times longer than the first graded piece after it the tip of ``one`` (a corner's side
    ordered from the vertex; ``two`` the other) would be: ``ratio`` times the wedge's width at the tip's end."""
    if len(one) < 3:
        return 0.0
    width = float(_segment_distances(one[1:2], two[:-1], two[1:])[0])
    return float(np.linalg.norm(one[1] - one[0])) / max(ratio * width, 1e-300)


def tip_segment(e, at_start: bool) -> int:
    """Index of the edge grid's segment at its start (``at_start``) or end."""
    return 0 if at_start else len(e.points) - 2


def tip_length(e, at_start: bool) -> float:
    """Length of the edge grid's segment at its start (``at_start``) or end."""
    return float(e.segment_lengths[tip_segment(e, at_start)])


def _graded_cuts(mine: np.ndarray, other: np.ndarray, ratio: float) -> dict[int, np.ndarray]:
    """Where to cut the segments of the polyline ``mine`` (ordered from the corner; its first segment, the
    tip, left whole) so that its pieces are at most ``ratio`` times their distance to the polyline ``other``:
    segment -> shares of its length, the pieces graded along it by the distances at :data:`SAMPLES` points
    (the boundaries at equal steps of the integral of ``ds / (ratio * width)``), at most
    :data:`MAX_PIECES`."""
    if len(mine) < 3:
        return {}
    a, b = other[:-1], other[1:]
    length = np.linalg.norm(np.diff(mine, axis=0), axis=1)
    near = _segment_distances(mine[1:-1], a, b)  # at each segment's end nearer the corner
    todo = 1 + np.flatnonzero(length[1:] > SLACK * ratio * near)
    if not len(todo):
        return {}
    t = (np.arange(SAMPLES) + 0.5) / SAMPLES
    at = mine[todo, None, :] + t[None, :, None] * (mine[todo + 1] - mine[todo])[:, None, :]
    width = _segment_distances(at.reshape(-1, 3), a, b).reshape(len(todo), SAMPLES)
    density = 1.0 / (ratio * np.maximum(width, 1e-300))
    pieces = np.minimum(np.ceil(density.mean(axis=1) * length[todo] - 1e-9), MAX_PIECES).astype(int)
    out = {}
    for k, n, d in zip(todo.tolist(), pieces.tolist(), np.minimum(density, MAX_PIECES / length[todo, None])):
        if n > 1:
            cum = np.concatenate([[0.0], np.cumsum(d)])
            out[k] = np.interp(np.arange(1, n) / n * cum[-1], cum, np.linspace(0.0, 1.0, SAMPLES + 1))
    return out
