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
(the face on a tip's other side sees that jump). Where the tips, made equal, are over :data:`JUMP_AIM`
times those pieces (the nut at 1e-3: its cone faces' area target cut the cusps' sides into 0.09 pieces,
70 times the first graded piece; at 1e-2, 22 times), the points the boundary fits added near the
corner are dropped and the tips cut where that jump is :data:`JUMP_AIM`, unless a face across them is
too thin for tips that long (the thin faces' splits put those points there):
in a cusp the width grows as the square of the distance, so longer tips stand beside relatively longer
pieces. What their chords cut off grows as the cube of their length, and each face's area may move by
at most :data:`TIP_AREA_SHARE` of its target in all. A cusp's tips are then made longer still, up to
the first points the edges were refined with, as far as its faces' area allows (:func:`_cusp_length`:
its forced triangle is as wide as its tips are long), and past them where an edge keeps half its slack
below its target without them (:func:`_growth_points`: mostly points the refiner's growth limit put
there). The other points of the edges as refined are kept and edge ends never move, so shared edges stay
conforming and every edge stays within its arc-length deficit target.
A face whose boundary doubles back on itself at a vertex (a slit: nearly 360 degrees inside) looks the
same from its edge grids and is graded too, which costs segments, not triangle quality.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from ..shapegrid import ShapeGrid, end_tolerances, recorded_targets, with_edges
from .grading import cut_on_curve
from .narrow import WEDGE_DEG, Corner, from_vertex, narrow_corners, tip_length, tip_segment
from .proximity import _LazyCurves
from .widths import BUDGET_FACTOR, MIN_BUDGET, WIDTH_RATIO, _segment_distances

#: Tips within this ratio of each other are left as they are.
TIP_RATIO = 1.2
#: Corners sharing edge ends have their tips matched in at most this many rounds.
TIP_ROUNDS = 4
#: A segment is cut into at most this many pieces.
MAX_PIECES = 200
#: A corner is graded only where its tips are at most this many times longer than the pieces beside
#: them: the face on the tip's other side sees the jump too, at a boundary node where its triangles fan
#: from the tip's triangle to the pieces' within about 120 degrees, and 6 triangles of 20 degrees grow at
#: most 1.88-fold each (sin 40 / sin 20): 44-fold in all. On the nut at 1e-3, tips 70 times the pieces
#: beside them left that face triangles of 2.4 degrees (1.8 with gmsh's Delaunay); at 1e-2, 22 times,
#: 20.3 degrees.
MAX_JUMP = 24.0
#: Tips over this jump are lengthened where they can be (see :func:`_lengthen_tips`), to this jump: the
#: longer the tips the wider the triangle on both, and below :data:`MAX_JUMP` a corner is graded.
JUMP_AIM = 20.0
#: ... or at up to this jump where the faces' area allows no longer tips (see :data:`TIP_AREA_SHARE`).
LAST_AIM = 0.95 * MAX_JUMP
#: A cusp's tips are lengthened past that jump, up to the first points the edges were refined with, where
#: its opening over them grows by this factor or more (see :func:`_cusp_length`).
CUSP_GAIN = 1.2
#: A cusp's tips may also drop points the edges were refined with (mostly ones the refiner's growth limit
#: put there, grading the segments from a short edge at the vertex): an edge may give up this share of
#: what its grid has left below its arc-length deficit target (see :func:`_growth_points`).
SLACK_SHARE = 0.5
#: A cusp's tips reach the first points the edges were refined with only as far as leaves the faces across
#: them no triangle under this many degrees (a tip ``L`` beside a strip ``w`` wide: ``atan(2 w / L)``): the
#: Fusion pump's cusp at the circle of a ring 0.05 wide took that circle's first refined point, 2.4 away,
#: and the ring 24 triangles under 5 degrees, none forced.
ACROSS_DEG = 10.0
#: Lengthened tips may move each face's area by at most this share of its target (the surface ALD times
#: its B-rep area), all its corners' together: the chords of the longer tips cut off what the points
#: dropped had followed.
TIP_AREA_SHARE = 0.4
#: Segments up to this share over the bound at their nearer end are left whole: the pieces are graded by
#: the width all along them (see :func:`_graded_cuts`), so they stand up to a sixth over it there.
SLACK = 1.25
#: Points along a segment at which the wedge's width is measured to grade its pieces.
SAMPLES = 16
#: A wedge's sides are cut, and its tips cut or lengthened, into pieces no shorter than their edge's
#: tolerance over this share. The other splits leave an edge whole where its tolerance is over a
#: thousandth of a piece (``proximity.TOLERANCE_SHARE``: on mesh_T106_V3, tolerances up to 0.73 mm,
#: points on the 3-D curve strayed from the faces' boundaries and gmsh built 0.04-degree triangles). In a
#: wedge the segments left whole span it from side to side: OCCT's sample CrankArm.brep has three planar
#: slivers 20-25 long with 1.7-degree corners, each beside a B-spline edge of tolerance 0.004-0.0095,
#: whose 2.1-long segments stood over widths of 0.05-0.5 (0.72% of its triangles under 20 degrees, 11
#: under 5 that nothing forced). Pieces of 20 tolerances or more put a new point off the face's boundary
#: by at most 5% of a piece.
LOOSE_SHARE = 0.05


def grade_wedges(grid: ShapeGrid, *, below: float = WEDGE_DEG, ratio: float = WIDTH_RATIO,
                 keep: ShapeGrid | None = None, areas: np.ndarray | None = None,
                 target: float | None = None, spare: Callable[[], np.ndarray] | None = None) -> ShapeGrid:
    """A copy of ``grid`` whose narrow corners (:func:`narrow_corners`) have tips of equal length and the
    rest of their two sides cut to at most ``ratio`` times the wedge's width (see the module doc). Given
    ``keep`` (the same edges as refined), the faces' B-rep ``areas`` (by face id - 1) and their area
    ``target`` (the surface ALD), points of ``grid`` that ``keep`` does not hold (added since by the
    boundary fits) may be dropped to lengthen tips over :data:`JUMP_AIM` times the first graded piece
    beside them, each face's area moving by at most :data:`TIP_AREA_SHARE` of its target in all (see
    :func:`_lengthen_tips`); a cusp's tips longer still within each face's ``spare()`` area too (by face
    id - 1: what its area fit leaves it in ``grid``, :func:`cadedge.mesh.boundary_fit.plane_room`; asked
    only where there are narrow corners; without it, none)."""
    edges = list(grid.edges)
    corners = narrow_corners(edges, below=below)
    if not corners:
        return grid
    curves = grid.curves if grid.curves is not None else _LazyCurves(grid)
    ends = end_tolerances(grid)
    budget = BUDGET_FACTOR * grid.segments + MIN_BUDGET
    changed = _match_tips(edges, corners, curves, ends)
    if keep is not None and areas is not None and target is not None:  # then lengthened where too short
        room = TIP_AREA_SHARE * target * np.asarray(areas, dtype=float)
        full = room.copy()
        near = _Near.of(edges)  # indices only: the tips' changes below leave it valid
        for c in corners:
            changed |= _lengthen_tips(edges, c, keep.edges, ratio, curves, ends, room, near)
        if spare is not None:  # then cusps' tips longer still, each face's room shared among its corners
            # spare() measures the grid as given: less what the tips above moved
            free = np.minimum(room, np.asarray(spare(), dtype=float) - (full - room))
            count = np.zeros(len(room))
            targets = recorded_targets(grid)
            touches = [_touched(edges, c) for c in corners]
            for touched in touches:
                count[touched] += 1
            for c, touched in zip(corners, touches):
                share = np.full(len(room), np.inf)
                share[touched] = free[touched] / count[touched]
                before = room.copy()
                if _widen_cusp(edges, c, keep.edges, ratio, curves, ends, room, share, targets, near):
                    changed, free = True, free - (before - room)
                count[touched] -= 1
    tip_segments = {(k, tip_segment(edges[k], s)) for c in corners for k, s in c.sides}
    cuts: dict[int, dict[int, np.ndarray]] = {}  # edge index -> segment -> shares of it to cut at
    for c in corners:
        if _jump(*(from_vertex(edges[k], s) for k, s in c.sides), ratio) > MAX_JUMP:
            continue
        for (i, s), (j, t) in (c.sides, c.sides[::-1]):
            for k, shares in _graded_cuts(from_vertex(edges[i], s), from_vertex(edges[j], t), ratio).items():
                seg, shares = (k, shares) if s else (len(edges[i].points) - 2 - k, 1.0 - shares[::-1])
                if (i, seg) in tip_segments:  # a short edge's far end: another narrow corner's tip stays whole
                    continue
                if len(shares) > len(cuts.setdefault(i, {}).get(seg, ())):
                    cuts[i][seg] = shares
    added = 0
    for i, at in cuts.items():
        e = edges[i]
        at = _no_piece_under(at, e.segment_lengths, e.tolerance / LOOSE_SHARE)
        new = sum(len(f) for f in at.values())
        if not new or added + new > budget:
            continue  # nothing to cut, or over the budget
        cut = cut_on_curve(e, curves, at, ends=ends[e.id])
        if cut is not None:
            edges[i], changed, added = cut, True, added + new
    return with_edges(grid, edges) if changed else grid


def _match_tips(edges: list, corners: list[Corner], curves, ends: dict[int, float]) -> bool:
    """Cut the longer tip of each corner at the shorter one's length (in place; True if any was cut).
    Corners at one vertex share edge ends (a faceted part's facets meet at a vertex in several narrow
    corners), so a tip cut for one corner may leave the next one unequal: repeated until none is cut,
    at most :data:`TIP_ROUNDS` times (tips only get shorter)."""
    changed = False
    for _ in range(TIP_ROUNDS):
        cut_any = False
        for c in corners:
            tips = [tip_length(edges[k], s) for k, s in c.sides]
            k, s = c.sides[int(np.argmax(tips))]
            if max(tips) > TIP_RATIO * min(tips) and not edges[k].tolerance > LOOSE_SHARE * min(tips):
                share = min(tips) / max(tips)
                cut = cut_on_curve(edges[k], curves, {tip_segment(edges[k], s): [share if s else 1 - share]},
                                   ends=ends[edges[k].id])
                if cut is not None:
                    edges[k], cut_any = cut, True
        changed |= cut_any
        if not cut_any:
            break
    return changed


def _no_piece_under(cuts: dict[int, np.ndarray], lengths: np.ndarray, least: float) -> dict[int, np.ndarray]:
    """``cuts`` (segment -> shares of its length to cut at, see :func:`_graded_cuts`) with fewer pieces where
    one would be shorter than ``least``, graded as before (the shares interpolated); a segment that cannot
    be cut into two such pieces is left whole.

    >>> _no_piece_under({0: np.array([0.1, 0.3, 0.6]), 1: np.array([0.5])}, np.array([1.0, 0.1]), 0.2)
    {0: array([0.3])}
    """
    out = {}
    for k, shares in cuts.items():
        bounds = np.concatenate([[0.0], shares, [1.0]])
        n = min(len(shares) + 1, int(lengths[k] / least)) if least > 0 else len(shares) + 1
        while n > 1:
            fewer = np.interp(np.linspace(0.0, 1.0, n + 1), np.linspace(0.0, 1.0, len(bounds)), bounds)
            if np.min(np.diff(fewer)) * lengths[k] >= least:
                out[k] = fewer[1:-1]
                break
            n -= 1
    return out


def _lengthen_tips(edges: list, c: Corner, kept: list, ratio: float, curves, ends: dict[int, float],
                   room: np.ndarray, near: _Near) -> bool:
    """Drop the points near corner ``c`` that ``kept`` (the edges as refined) does not hold and cut both
    tips at the length where they are :data:`JUMP_AIM` times the first graded piece beside them (up to
    :data:`LAST_AIM` where the faces' area allows no more); True if ``edges`` changed. A corner whose tips
    (made equal) are that long already, cannot get that long without dropping a kept point, or whose
    chords would move a face's area by more than its ``room`` (by face id - 1; what is used is taken from
    it), or whose tips would span a face across them (``near``: the edges at each vertex and on each face)
    over ``ratio`` times as long as it is wide there (:func:`_across_room`) is left alone (``ends``: edge
    id -> how far a grid may end from its curve, see :func:`~cadedge.mesh.grading.cut_on_curve`). The
    thin faces' splits put those points there: an Ultimaker 2 feeder part's plane narrows to two cusps on
    a B-spline whose cylinder band across is 0.001 wide, and its tips, lengthened to 0.17, left the band
    62 triangles of 0.09-4.8 degrees that nothing forced. In a cusp the wedge's width grows as the square
    of the distance from the vertex, so a longer tip stands beside pieces that are relatively longer, and
    its forced triangle is wider; what the chords cut off grows as the cube of the tips' length."""
    found = _reach(edges, c, kept, ratio)
    if found is None:
        return False
    sides, reach, now = found
    aim = JUMP_AIM
    across = None
    while aim <= LAST_AIM:
        need = max(_length_at(dist, jumps, aim) for dist, _, jumps in reach)
        if need <= now * (1.0 + 1e-9):
            return False  # the tips, made equal, are long enough already
        if across is None:  # measured out to the first aim's length, the longest asked
            across = min(_across_room(edges, c, k, side, dist, need, ratio, near)
                         for (k, _), side, (dist, _, _) in zip(c.sides, sides, reach))
        if need > across:
            return False  # a face across is too thin for tips that long
        tried = _tips_at(edges, c, sides, reach, need, need / aim, room)
        if tried is None:
            return False  # a kept point inside the tips' new length, or too loose an edge
        if tried[2] <= 1.0:
            return _apply(edges, c, tried, reach, curves, ends, room)
        aim *= 1.05 * tried[2] ** (1.0 / 3.0)  # the area cut off goes about as the cube of the tips' length
    return False


@dataclasses.dataclass(frozen=True)
class _Near:
    """Which edges (indices into the grid's edge list) end at each B-rep vertex, as (index, whether it
    starts there), and which bound each face: looked up per corner instead of scanning every edge."""

    ends: dict[int, list[tuple[int, bool]]]
    faces: dict[int, list[int]]

    @classmethod
    def of(cls, edges: list) -> "_Near":
        ends: dict[int, list[tuple[int, bool]]] = {}
        faces: dict[int, list[int]] = {}
        for i, e in enumerate(edges):
            if e.degenerate or len(e.points) < 2:
                continue
            ends.setdefault(e.vertices[0], []).append((i, True))
            ends.setdefault(e.vertices[-1], []).append((i, False))
            for f in e.faces:
                faces.setdefault(f, []).append(i)
        return cls(ends, faces)


def _widen_cusp(edges: list, c: Corner, kept: list, ratio: float, curves, ends: dict[int, float],
                room: np.ndarray, share: np.ndarray, targets: dict[int, float], near: _Near) -> bool:
    """In a cusp (see :func:`_cusp_length`), drop the points near corner ``c`` that ``kept`` does not hold,
    or that the refiner's growth limit put there (:func:`_growth_points`; ``targets``: edge id -> its
    arc-length deficit target; ``near``: the edges at each vertex and on each face), and make its tips as
    long as the first points kept and ``share`` (the area each face may move for this corner, by face id
    - 1) allow; what is used is taken from ``room``. True if ``edges`` changed."""
    found = _reach(edges, c, kept, ratio)
    if found is None:
        return False
    sides, reach, now = found
    reach, longest = _growth_points(edges, c, sides, reach, kept, targets, ratio, near)
    tried = _cusp_length(edges, c, sides, reach, now, share, longest)
    return tried is not None and _apply(edges, c, tried, reach, curves, ends, room)


def _growth_points(edges: list, c: Corner, sides: list, reach: list, kept: list, targets: dict[int, float],
                   ratio: float, near: _Near) -> tuple[list, float]:
    """``reach`` (see :func:`_reach`) with the points of corner ``c``'s sides that the edges were refined
    with marked free too, from the vertex on, up to the first one that is not: one as far from it as the
    tips may be long, or one whose drop with all before it would use more than :data:`SLACK_SHARE` of
    what the edge's grid has left below its target (``targets``, by edge id; its true length from
    ``kept``, the edges as refined, and their deficit estimates); and how long the tips may be: up to
    the first points kept before (as far as the faces across keep triangles of :data:`ACROSS_DEG`), and
    past them no more than :data:`JUMP_AIM` times the shortest first segment of the vertex's other edges
    (the faces across the tips see the jump between those and the tips), nor ``ratio`` times the width of
    a face across (:func:`_across_room`, measured only where the jump allows that much); nothing is freed
    where that is under :data:`CUSP_GAIN` times as far as the points kept before reach.

    The refiner's growth limit grades an edge's segments from the shortest one at each of its vertices: a
    fan's shroud, a cylinder whose seam is cut 0.2 above the cusps where its circle touches the square's
    sides, had the circle and the lines cut from 0.4 up, doubling, where the lines need no point and the
    circle one every 29: those tips stayed 0.4, their triangles 0.19 degrees (gmsh's, on its own coarse
    edges, 7.5). The edge's far end always stays, and an edge with no target in the options keeps all."""
    others = [tip_length(edges[i], at_start) for i, at_start in near.ends.get(c.vertex, ())
              if (i, at_start) not in c.sides]
    cap = JUMP_AIM * min(others, default=np.inf)
    before = min(float(dist[1 + np.flatnonzero(~free[1:])[0]]) for dist, free, _ in reach)
    if cap >= CUSP_GAIN * before:  # the faces across measured only where the jump leaves something to gain
        cap = min([cap] + [_across_room(edges, c, k, side, dist, cap, ratio, near)
                           for (k, _), side, (dist, _, _) in zip(c.sides, sides, reach)])
    if cap < CUSP_GAIN * before:  # not much longer than the points kept already reach: up to those, as far
        # as the faces across keep triangles of ACROSS_DEG
        loose = 2.0 / np.tan(np.radians(ACROSS_DEG))
        return reach, min([before] + [_across_room(edges, c, k, side, dist, before, loose, near)
                                      for (k, _), side, (dist, _, _) in zip(c.sides, sides, reach)])
    out = []
    for (k, _), side, (dist, free, jumps) in zip(c.sides, sides, reach):
        e, ref = edges[k], kept[k]
        target = targets.get(e.id, np.inf)
        if not np.isfinite(target):
            out.append((dist, free, jumps))
            continue
        true = ref.length / max(1.0 - ref.ald_estimate, 1e-300)
        spare = SLACK_SHARE * (target * true - (true - e.length))
        walked = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(side, axis=0), axis=1))])
        loss = walked - dist  # what the polyline loses when every point before each one is dropped
        stays = np.flatnonzero(~free)  # the vertex, the points kept so far, the far end
        free = free.copy()
        for m, after in zip(stays[1:-1], stays[2:]):
            if dist[m] >= cap * (1.0 - 1e-9) or dist[after] <= dist[m] or loss[after] > spare:
                break  # a tip may then reach the next point kept: the chord to it must fit the edge's slack
            free[m] = True
        out.append((dist, free, jumps))
    return out, cap


def _across_room(edges: list, c: Corner, k: int, side: np.ndarray, dist: np.ndarray, cap: float,
                 ratio: float, near: _Near) -> float:
    """How long corner ``c``'s tip on side ``k`` (its points ``side``, ``dist`` from the vertex) may be, up
    to ``cap``, for the faces across it: the farthest of its points (or ``cap``) whose chord from the
    vertex is at most ``ratio`` times the distance from its midpoint to such a face's boundary, on edges
    away from the vertex (as :mod:`cadedge.mesh.widths` splits thin faces). The fan's shroud has a strip
    0.2 tall at its top: a circle's tip grown to 4 there left it 5.6-degree triangles."""
    across = {i for f in set(edges[k].faces) - {c.face} for i in near.faces.get(f, ())}
    others = [edges[i] for i in sorted(across) if c.vertex not in edges[i].vertices]
    upto = int(np.searchsorted(dist, cap, side="right"))
    if not others or upto < 2:
        return cap
    a = np.vstack([e.points[:-1] for e in others])
    b = np.vstack([e.points[1:] for e in others])
    width = _segment_distances(0.5 * (side[0] + side[1:upto]), a, b)
    bad = np.flatnonzero(dist[1:upto] > ratio * width)
    return cap if not len(bad) else float(dist[bad[0]])  # the last point whose chord fits (0: none)


def _reach(edges: list, c: Corner, kept: list, ratio: float) -> tuple[list, list, float] | None:
    """Corner ``c``'s sides (ordered from the vertex); per side, its points' distances from the vertex,
    which of them ``kept`` (the edges as refined) does not hold (they may be dropped) and the jumps of a
    tip ending at each inner point (:func:`_jumps`); and the tips' length, the shorter one's. None if an
    edge is not the refined one or a side has under 3 points."""
    sides = [from_vertex(edges[k], s) for k, s in c.sides]
    reach = []
    for (k, s), mine, other in zip(c.sides, sides, sides[::-1]):
        e, ref = edges[k], kept[k]
        if e.id != ref.id or len(mine) < 3:
            return None
        free = ~np.isin(e.params, ref.params)
        free = free if s else free[::-1]
        free[[0, -1]] = False
        reach.append((np.linalg.norm(mine - mine[0], axis=1), free, _jumps(mine, other, ratio)))
    return sides, reach, min(dist[1] for dist, _, _ in reach)


def _apply(edges: list, c: Corner, tried: tuple, reach: list, curves, ends: dict[int, float],
           room: np.ndarray) -> bool:
    """Drop the points and cut the tips of corner ``c`` as ``tried`` plans (:func:`_tips_at`), in place,
    taking the area moved from ``room``; False (nothing changed) if a tip cannot be cut on its curve."""
    plans, moved, _, _ = tried
    new = []
    for (k, s), (drop, end), (dist, _, _) in zip(c.sides, plans, reach):
        e = edges[k]
        stay = ~(drop if s else drop[::-1])
        e = dataclasses.replace(e, params=e.params[stay], points=e.points[stay])
        beyond = dist[~drop & (dist > 0)][0]
        if beyond > (1.0 + 1e-3) * end:
            share = end / beyond
            e = cut_on_curve(e, curves, {tip_segment(e, s): [share if s else 1.0 - share]}, ends=ends[e.id])
            if e is None:
                return False
        new.append(e)
    for (k, _), e in zip(c.sides, new):
        edges[k] = e
    room -= moved
    return True


def _touched(edges: list, c: Corner) -> np.ndarray:
    """The faces (by face id - 1) whose area corner ``c``'s tips move: its own and those across its sides."""
    return np.unique([c.face - 1] + [f - 1 for k, _ in c.sides for f in edges[k].faces])


def _tips_at(edges: list, c: Corner, sides: list, reach: list, need: float, piece: float, room: np.ndarray
             ) -> tuple[list, np.ndarray, float, float] | None:
    """Corner ``c``'s tips ``need`` long, the first graded piece beside them ``piece`` long (``sides``,
    ``reach``: see :func:`_lengthen_tips`): which points each side drops and where its tip ends
    (:func:`_tip_plan`), how much each face's area moves (:func:`_moved`), the largest share of a face's
    ``room`` that is, and ``need``; None if a kept point lies inside ``need`` or the corner's edges are
    too loose for pieces that short."""
    if max(edges[k].tolerance for k, _ in c.sides) > LOOSE_SHARE * piece:
        return None  # pieces this short are not cut on so loose an edge: no longer tips either
    plans = [_tip_plan(dist, free, need, piece) for dist, free, _ in reach]
    if any(p is None for p in plans):
        return None
    moved = _moved(edges, c, sides, [r[0] for r in reach], plans, len(room))
    return plans, moved, float(np.max(moved / np.maximum(room, 1e-300))), need


def _cusp_length(edges: list, c: Corner, sides: list, reach: list, now: float, room: np.ndarray,
                 longest: float = np.inf) -> tuple[list, np.ndarray, float, float] | None:
    """In a cusp, tips as long as the first kept points, ``longest`` and the faces' ``room`` allow (see
    :func:`_tips_at`; ``now``, the tips' length as they are): a corner whose opening over its tips grows
    by :data:`CUSP_GAIN` or more when they are that long, whose forced triangle is that much wider. The
    area fits cut a cusp's sides as finely as its face's target asks, though their chords there cut off
    next to nothing: a hole touching a disk's rim at 1e-2 had tips of 0.96 where the edges as refined had
    1.9, its forced triangles 4.2 degrees, gmsh's 11.6. None if no such tips fit."""
    kept = [1 + int(np.flatnonzero(~free[1:])[0]) for _, free, _ in reach]  # each side's first kept point
    near = [side[:m + 1] for side, m in zip(sides, kept)]  # the sides up to it, moving away from the vertex
    dists = [dist[:m + 1] for (dist, _, _), m in zip(reach, kept)]
    need = min([float(d[-1]) for d in dists] + [longest])
    least = CUSP_GAIN * _opening(near, dists, now)
    while need > now * (1.0 + 1e-9) and _opening(near, dists, need) >= least:
        piece = need / max(max(float(np.interp(need, dist[1:m], jumps[:m - 1]))
                               for (dist, _, jumps), m in zip(reach, kept)), 1.0)
        tried = _tips_at(edges, c, sides, reach, need, piece, room)
        if tried is None:
            return None
        if tried[2] <= 1.0:
            return tried
        need /= 1.05 * tried[2] ** (1.0 / 3.0)
    return None


def _opening(sides: list, dists: list, length: float) -> float:
    """The angle (radians) at a corner's vertex between its two sides' points ``length`` from it (along
    each side's points, ``dists`` from the vertex)."""
    ends = [np.array([np.interp(length, dist, side[:, k]) for k in range(3)]) - side[0]
            for side, dist in zip(sides, dists)]
    u, v = (e / max(float(np.linalg.norm(e)), 1e-300) for e in ends)
    return float(np.arccos(np.clip(u @ v, -1.0, 1.0)))


def _length_at(dist: np.ndarray, jumps: np.ndarray, aim: float) -> float:
    """The tip's length at which its jump (``jumps`` with the tip ending at each inner point of a side whose
    points lie ``dist`` from the vertex; falling along it) comes down to ``aim``: 0 if it is there at the
    side's first point already, inf if it never is."""
    ok = np.flatnonzero(jumps <= aim)
    if not len(ok):
        return np.inf
    m = ok[0]  # between points m and m + 1
    return 0.0 if m == 0 else float(np.interp(aim, [jumps[m], jumps[m - 1]], [dist[m + 1], dist[m]]))


def _tip_plan(dist: np.ndarray, free: np.ndarray, need: float, piece: float) -> tuple[np.ndarray, float] | None:
    """Which points of a side (``dist`` from the vertex; ``free`` may be dropped) to drop for a tip ``need``
    long, and where the tip then ends: at ``need``, or at the first point kept if that lies within
    ``piece`` beyond it (no piece shorter than the first graded one beside the tip). None if a kept point
    lies inside ``need``. Only points before the first one kept go: a closed edge's last points lie near
    the vertex too, at its other end (a hole touching a disk's rim: one corner's plan took both ends'
    points and left the other corner's tips 2.4 and 1.9)."""
    first = 1 + int(np.flatnonzero(~free[1:])[0])  # the first point kept (the edge's far end at the latest)
    stop = float(dist[first])
    if stop < need * (1.0 - 1e-9):
        return None
    drop = np.zeros(len(dist), dtype=bool)
    drop[1:first] = dist[1:first] < min(stop, need + piece)
    return drop, (stop if stop < need + piece else need)


def _moved(edges: list, c: Corner, sides: list, dists: list, plans: list, faces: int) -> np.ndarray:
    """How much each face's area (by face id - 1) moves when the points of corner ``c``'s sides are dropped
    and its tips end as ``plans`` say (see :func:`_tip_plan`): the area between the new chord and the
    points dropped on a side, for the face across it; one side's less the other's for the wedge itself."""
    moved = np.zeros(faces)
    slivers = []
    for (k, _), mine, dist, (drop, end) in zip(c.sides, sides, dists, plans):
        # the tip ends before the first point not dropped; past it a closed edge's distances fall back to 0
        m = 1 + int(np.flatnonzero(~drop & (dist > 0))[0])
        tip = np.array([np.interp(end, dist[:m], mine[:m, d]) for d in range(3)])
        on = drop & (dist < end)
        on[0] = True  # the vertex (a closed edge's last point is there too, and not part of this sliver)
        slivers.append(_vector_area(np.vstack([mine[on], tip])))
        for f in edges[k].faces:
            moved[f - 1] += 0.0 if f == c.face else float(np.linalg.norm(slivers[-1]))
    moved[c.face - 1] += float(np.linalg.norm(slivers[0] - slivers[1]))
    return moved


def _vector_area(points: np.ndarray) -> np.ndarray:
    """Vector area of the polygon closed by the polyline ``points`` (n, 3) and the chord joining its ends."""
    rel = points - points[0]
    return 0.5 * np.cross(rel[:-1], rel[1:]).sum(axis=0)


def _jumps(one: np.ndarray, two: np.ndarray, ratio: float) -> np.ndarray:
    """For a tip of ``one`` (a corner's side ordered from the vertex; ``two`` the other) ending at each of
    its inner points, how many times longer than the first graded piece after it the tip would be:
    ``ratio`` times the wedge's width there."""
    width = _segment_distances(one[1:-1], two[:-1], two[1:])
    return np.linalg.norm(one[1:-1] - one[0], axis=1) / np.maximum(ratio * width, 1e-300)


def _jump(one: np.ndarray, two: np.ndarray, ratio: float) -> float:
    """The jump of ``one``'s tip as it is (see :func:`_jumps`)."""
    return float(_jumps(one[:3], two, ratio)[0]) if len(one) >= 3 else 0.0


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
