"""A long cylinder face between two circles meshed as a grid of right triangles, its area deficit that of
the polygon on its columns.

A cylinder face bounded by two circles (or two arcs of them) and the straight lines between them (its
seam, or two of its generators) is a rectangle in its parameters, angle round the axis by height along
it, and unrolls onto a plane rectangle without stretching. Meshed as a grid, rows at the lines' nodes and
columns along generators, each row of triangles is a band of the prism on the polygon of the columns: the
face's mesh area falls short of its B-rep area by exactly the share that polygon's perimeter falls short
of the circle's (:func:`polygon_deficit`). So the columns are the fewest the face's target allows
(:func:`polygon_count`: 41 round a full circle at 1e-3), the boundary fit splits the lines into rows as
tall as the columns are wide (:func:`cadedge.mesh.boundary_fit.fit_grids`), and the triangles are right
triangles of about 45 degrees. gmsh sizes a cylinder for triangles at any slant, 57 to the circle at 1e-3,
and meshes about 20 000 triangles a second: a 1 x 1 000 mm rod asked 2.4 million triangles of it (held to
its 400 000 triangle budget, 2.3e-3 off, 53 s); as a grid it is 1.07 million at 9.8e-4, in 14 s.

Where the circles carry as many nodes as the columns, about as wide as the rows are tall, the columns
run through them. A circle split finer for a neighbour (a rod's flat end: 123 segments, three times the
41 columns) is joined to the grid by a band that gmsh meshes in the plane (:func:`_band`), its sizes
growing from the circle's segments to the columns (:data:`BAND_GROWTH`), the lines' segments beside it
graded alike (:meth:`GridFit.line_params`), and its triangles improved in the plane by the face
optimiser's moves (:func:`cadedge.mesh.optimize.improve_plane`: 38-40 degrees, from gmsh's 31-35). Only
faces whose grid takes :data:`FEWEST_TRIANGLES` or more are meshed so: on smaller ones gmsh is quick and
the face optimiser lifts its triangles to 40 degrees and more.

A torus face round the whole ring between two of its parallels, joined by one arc of its tube (a small
fillet along a circular edge, an O-ring groove's round) is a grid the other way: the parallels are long
and hardly curved along themselves, the tube's arc short and sharply curved. Its rows are cut on the
arc, and both parallels into the same number of columns as wide as the rows are tall, at the same
angles (:mod:`cadedge.mesh.torus_fit`): a 0.2 mm fillet round a 70 mm disk at 1e-3 takes 7 682 columns
by 11 rows, 169 004 triangles at 8.6e-4 and 44.5 degrees, where gmsh's curvature sizes took 322 000 at
3.9e-4 and 27.5 degrees. The parallels carry the columns (no band: a torus does not unroll), so they
must end with as many nodes each.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

#: The strategy's name in reports (:data:`cadedge.mesh.strategies.STRATEGIES`).
NAME = "grid"
#: A face is meshed as a grid only if its cells give right triangles no smaller than this many degrees:
#: gmsh's Frontal-Delaunay gets 38-42 degrees on cylinders, and the grid's triangles are the face's
#: smallest.
MIN_ANGLE = 40.0
#: A grid's cells are at most this many times as tall as wide, or as wide as tall (1.19): right triangles
#: of :data:`MIN_ANGLE` degrees or more.
ASPECT = float(1.0 / np.tan(np.radians(MIN_ANGLE)))
#: A circle with other nodes than the grid's columns (a rod's circle split three times finer for its
#: flat end) is joined to the grid by a band at least this many rows tall (:func:`band_reach`), meshed by
#: gmsh in the plane.
BAND_ROWS = 2
#: A band's sizes grow from its circle's segments by this share of the distance to the circle, to the
#: grid's columns (its lines' segments are cut to match, :meth:`GridFit.line_params`; gmsh meshes it to
#: a size field of the same): 33-35 degrees for circles 3, 6 and 9 times finer than the columns, where
#: 0.5 gave 24-33.
BAND_GROWTH = 0.3
#: How a band is meshed, in turn until one reaches :data:`BAND_GOOD` degrees once improved in the plane
#: (:func:`cadedge.mesh.optimize.improve_plane`, moving nodes near triangles under :data:`MIN_ANGLE`;
#: else the best is kept): gmsh's 2-D algorithm (6 Frontal-Delaunay, 5 Delaunay) and whether its sizes
#: come from a field growing from the circle by :data:`BAND_GROWTH` or from its boundary. As gmsh made
#: them, each alone fell to 26-28 degrees on some of the bands of circles 2-9 times finer than 11, 13 and
#: 41 columns (the best of them 33-38.6 on all).
BAND_VARIANTS = ((6, False), (5, True), (6, True), (5, False))
#: A band this good ends the tries (gmsh alone meshes such cylinders at 35.6-37.8 degrees): the first way
#: reaches it on 11752.stp's 176 bands (33.1-34.8 degrees as gmsh made them, 38.6-40.2 improved), a thin
#: tube's four (31.6-32.3, 38.1-40.2) and a rod's two (34.1, 38.9-39). A try takes about 13 ms of gmsh
#: and 45 ms of improving.
BAND_GOOD = 38.0
#: Triangles of a band (gmsh's, graded from the circle's segments to the grid's) are kept at this many
#: degrees or more, else the face is left to gmsh.
BAND_MIN_ANGLE = 30.0
#: An edge whose polyline is as long as its curve to this share is a line: STEP files carry lines as
#: B-splines (11752.stp's 2 mm rods, 1 239 mm long, have B-spline seams).
STRAIGHT_ALD = 1e-12
#: A face is meshed as a grid only if that takes this many triangles or more: on smaller faces gmsh is
#: quick and the face optimiser lifts its triangles to 40 degrees and more, where a grid with bands gets
#: 38-40 (the cylinder fixture's side at 1e-3 as a grid: 38.8 degrees, against 40.7 as gmsh and the
#: optimiser mesh it; gmsh alone gets 39.9).
FEWEST_TRIANGLES = 50_000
#: A face whose grid would take more triangles is left to gmsh (its lines split by the curvature rule,
#: its sizes held to its triangle budget): a grid costs gmsh nothing, but its nodes are still read back,
#: checked and written (the 1 x 1 000 mm rod at 1e-3: 1.07 million).
MOST_TRIANGLES = 4_000_000


def polygon_deficit(n, turn: float = 2.0 * np.pi):
    """How far ``n`` equal chords fall short of the length of a circle's arc of ``turn`` radians (a number
    or an array): the area deficit of a grid's rows between such arcs.

    >>> round(float(polygon_deficit(41)), 6)
    0.000978
    """
    n = np.asarray(n, dtype=float)
    return 1.0 - 2.0 * n / turn * np.sin(turn / (2.0 * n))


def polygon_count(target: float, turn: float = 2.0 * np.pi) -> int:
    """The fewest equal chords whose :func:`polygon_deficit` on an arc of ``turn`` is within ``target``.

    >>> polygon_count(1e-3), polygon_count(1e-2), polygon_count(1e-3, np.pi / 2)
    (41, 13, 11)
    """
    n = max(int(np.ceil(abs(turn) / np.sqrt(24.0 * target))) - 1, 1)
    while polygon_deficit(n, abs(turn)) > target:
        n += 1
    return n


#: The area target of the faces meshed in this process (set by :func:`aim` for each gmsh job): a grid's
#: columns are at least :func:`polygon_count` of it.
TARGET: float | None = None
#: The gmsh surfaces of the job in this process that the boundary fit made grids of (:func:`grid_face_ids`,
#: set by :func:`aim`): only they are laid out. The caller's OCCT types decide, not gmsh's: gmsh calls a
#: cylinder trimmed to a rectangle of its parameters, as STEP files carry them (11752.stp's 420 rods),
#: "Unknown".
SURFACES: frozenset[int] = frozenset()


#: The surfaces of :data:`SURFACES` that are tori (their parallels carry the columns, their tube's arc the
#: rows).
TORI: frozenset[int] = frozenset()


def aim(target: float | None, surfaces: Iterable[int] = (), tori: Iterable[int] = ()) -> None:
    """Set :data:`TARGET`, :data:`SURFACES` and :data:`TORI` for the gmsh job starting in this process."""
    global TARGET, SURFACES, TORI
    TARGET, SURFACES, TORI = target, frozenset(surfaces), frozenset(tori)


def band_reach(row: float, spacing: float) -> float:
    """How far from a circle whose segments are ``spacing`` long the band joining it to a grid of
    ``row``-wide columns reaches: sizes growing by :data:`BAND_GROWTH` to the columns' width, then one
    row; at least :data:`BAND_ROWS` rows.

    >>> round(band_reach(1.0, 0.25), 6)  # 2.5 rows of graded sizes, then a row
    3.5
    """
    return max(BAND_ROWS * row, max(row - spacing, 0.0) / BAND_GROWTH + row)


@dataclass(frozen=True)
class GridFit:
    """What the boundary fit needs of a face meshed as a grid: the ``width`` of its columns, and each
    circle's end points (2, 3) with its segments' mean length (``ends``); on a torus ``width`` is the
    rows' greatest height on its tube's arc, ``cuts`` its parallels' parameters cut into the grid's
    columns and its tube arc's into its rows ((edge id, parameters) each:
    :func:`cadedge.mesh.torus_fit.torus_fit`)."""

    width: float
    ends: tuple[tuple[np.ndarray, float], ...]
    cuts: tuple[tuple[int, np.ndarray], ...] = field(default=(), compare=False)

    def triangles(self, area: float) -> float:
        """About how many triangles the grid of a face of B-rep ``area`` takes."""
        return 2.0 * area / self.width ** 2

    def cut(self, edge: int, params: np.ndarray) -> np.ndarray | None:
        """Grid torus edge ``edge``'s parameters cut into the grid's columns or rows (:attr:`cuts`), if
        they keep its grid's ``params``; else None.

        >>> fit = GridFit(1.0, (), ((3, np.array([0.0, 0.5, 1.0])),))
        >>> fit.cut(3, np.array([0.0, 1.0])).tolist(), fit.cut(3, np.array([0.0, 0.7, 1.0])), fit.cut(4, [0.0])
        ([0.0, 0.5, 1.0], None, None)
        """
        cut = dict(self.cuts).get(edge)
        return cut if cut is not None and np.all(np.isin(params, cut)) else None

    def line_params(self, params: np.ndarray, points: np.ndarray) -> np.ndarray:
        """The parameters of a line of the face (its grid's ``params`` and ``points``, which all stay) cut
        into rows as tall as the columns are wide, and graded from each end on a circle whose segments
        are finer (by more than :data:`ASPECT`): sizes ``spacing + BAND_GROWTH * distance`` up to the
        columns' width, so that the band joining that circle to the grid (:func:`_band`) grows smoothly.
        Each segment is cut in as many pieces as the sizes ask (at least one), graded within it; new
        parameters are spaced as their distances along the line.

        >>> fit = GridFit(1.0, ((np.zeros((2, 3)), 0.25),))
        >>> line = np.array([[0.0, 0, 0], [0, 0, 10.0]])
        >>> np.round(np.diff(fit.line_params(np.array([0.0, 10.0]), line)), 2).tolist()
        [0.29, 0.4, 0.54, 0.73, 0.96, 1.01, 1.01, 1.01, 1.01, 1.01, 1.01, 1.01]
        >>> np.diff(GridFit(1.0, ()).line_params(np.array([0.0, 10.0]), line)).tolist() == [1.0] * 10
        True
        """
        chord = np.linalg.norm(np.diff(points, axis=0), axis=1)
        along = np.concatenate([[0.0], np.cumsum(chord)])
        total = float(along[-1])
        tol = 1e-9 * max(float(np.ptp(points, axis=0).max()), self.width)
        # (distance from the start of the line where the size is `spacing`, `spacing`, the way it grows)
        graded = [(0.0 if row == 0 else total, spacing, 1.0 if row == 0 else -1.0)
                  for row in (0, -1) for ends, spacing in self.ends
                  if spacing < self.width / ASPECT and np.min(np.linalg.norm(ends - points[row], axis=1)) <= tol]
        d = np.unique(np.concatenate([along] + [
            np.clip(at + way * np.linspace(0.0, band_reach(self.width, spacing), 256), 0.0, total)
            for at, spacing, way in graded]))
        size = np.full(len(d), self.width)
        for at, spacing, _ in graded:
            size = np.minimum(size, spacing + BAND_GROWTH * np.abs(d - at))
        count = np.concatenate([[0.0], np.cumsum(np.diff(d) * 0.5 * (1.0 / size[1:] + 1.0 / size[:-1]))])
        at_nodes = np.interp(along, d, count)
        pieces = np.maximum(np.rint(np.diff(at_nodes)), 1).astype(int)
        first = np.repeat(np.arange(len(pieces)), pieces - 1)  # the segment of each new node, and its rank
        rank = np.arange(len(first)) - np.repeat(np.cumsum(pieces - 1) - (pieces - 1), pieces - 1) + 1
        cut = at_nodes[first] + rank / pieces[first] * (at_nodes[first + 1] - at_nodes[first])
        new = np.interp(np.interp(cut, count, d), along, params)
        return np.sort(np.concatenate([params, new]))


def grid_faces(grid, kinds: list[str], target: float, areas: np.ndarray) -> dict[int, GridFit]:
    """The faces of ``grid`` that may be meshed as a grid, with what the boundary fit needs of them
    (:class:`GridFit`): tori as :func:`cadedge.mesh.torus_fit.torus_fit` says, and cylinders (``kinds``,
    by face id - 1) bounded by two circles and by one seam line (full circles) or two lines (arcs;
    straight B-splines too, :data:`STRAIGHT_ALD`), and nothing else.
    The columns' width is the widest whose polygon is within ``target`` (:func:`polygon_count`), or the
    circles' own segments where they are as many and at most :data:`ASPECT` times finer, or where the
    face is too short for bands between them
    (:data:`BAND_ROWS`): a rod's circles split three times for its flat ends get bands, a hole's split
    twice for the plate round it carry the grid. Only faces of ``areas`` (by face id - 1) whose grid
    takes :data:`FEWEST_TRIANGLES` or more."""
    by_face: dict[int, list] = {}
    for e in grid.edges:
        if not e.degenerate:
            for f in set(e.faces):
                by_face.setdefault(f, []).append(e)
    out = {}
    for f, edges in by_face.items():
        if 1 <= f <= len(kinds) and kinds[f - 1] == "Torus":
            from .torus_fit import torus_fit

            fit = torus_fit(edges, target)
            if fit is not None and fit.triangles(areas[f - 1]) >= FEWEST_TRIANGLES:
                out[f] = fit
            continue
        if not 1 <= f <= len(kinds) or kinds[f - 1] != "Cylinder":
            continue
        circles = [e for e in edges if e.curve == "Circle"]
        lines = [e for e in edges if e.curve == "Line" or e.ald_estimate <= STRAIGHT_ALD]
        if len(circles) != 2 or len(circles) + len(lines) != len(edges):
            continue
        closed = [bool(np.allclose(e.points[0], e.points[-1])) for e in circles]
        if not (all(closed) and len(lines) == 1 or not any(closed) and len(lines) == 2):
            continue
        e = circles[0]
        turn = 2.0 * np.pi if closed[0] else float(abs(e.params[-1] - e.params[0]))
        width = float(e.segment_lengths.sum()) / polygon_count(target, turn)
        spacing = float(np.mean(np.concatenate([c.segment_lengths for c in circles])))
        tall = float(lines[0].segment_lengths.sum())
        # the circles' own segments where they are about as wide, or no band fits between them
        if len(circles[0].points) == len(circles[1].points) and (
                spacing >= width / ASPECT or tall < (2 * BAND_ROWS + 2) * width):
            width = spacing
        fit = GridFit(width, tuple((c.points[[0, -1]], float(c.segment_lengths.mean())) for c in circles))
        if fit.triangles(areas[f - 1]) >= FEWEST_TRIANGLES:
            out[f] = fit
    return out


def grid_face_ids(grid, kinds: list[str], target: float, areas: np.ndarray) -> list[int]:
    """The faces of ``grid`` the mesher lays out as grids (:data:`SURFACES`): those of :func:`grid_faces`
    whose grid takes no more than :data:`MOST_TRIANGLES`."""
    return sorted(f for f, fit in grid_faces(grid, kinds, target, areas).items()
                  if fit.triangles(areas[f - 1]) <= MOST_TRIANGLES)


@dataclass(frozen=True)
class Layout:
    """A grid face's boundary nodes: ``bottom`` and ``top`` (circles, the same way round) and ``left`` and
    ``right`` (lines, bottom to top, as many nodes each; one seam twice), as node tags, their points and
    their surface parameters; ``angle`` the parameter round the axis (0 or 1), ``scale`` the surface's
    length per unit of each parameter; ``columns`` the grid's columns, and which circles carry them
    (``own``: bottom, top); a circle that does not is joined to the grid by a band that gmsh meshes in the
    plane, ``bands`` rows tall (bottom, top; 0 where the circle carries the columns)."""

    tags: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
    xyz: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
    uv: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
    angle: int
    scale: np.ndarray
    columns: int
    own: tuple[bool, bool]
    bands: tuple[int, int]


def _chain(curve: int, surface: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A curve's node tags from its first to its last node, their points and their parameters on
    ``surface``."""
    import gmsh

    from .generate import curve_chain

    chain, t = curve_chain(curve)
    tags, coords, _ = gmsh.model.mesh.getNodes(1, curve, includeBoundary=True)
    where = dict(zip(np.asarray(tags, dtype=np.int64).tolist(), np.asarray(coords, dtype=float).reshape(-1, 3)))
    xyz = np.array([where[k] for k in chain.tolist()])
    uv = np.reshape(gmsh.model.reparametrizeOnSurface(1, curve, t.tolist(), surface), (-1, 2))
    return chain, xyz, uv


def _from(chain: tuple, start: int) -> tuple | None:
    """``chain`` (tags, points, parameters) run from its end ``start``; None if neither end is ``start``."""
    tags = chain[0]
    if tags[0] == start:
        return chain
    if tags[-1] == start:
        return tuple(a[::-1] for a in chain)
    return None


def _roll(chain: tuple, start: int) -> tuple | None:
    """A closed ``chain`` turned to start and end at its node ``start``; None if it has no such node."""
    hit = np.flatnonzero(chain[0][:-1] == start)
    if not len(hit):
        return None
    return tuple(np.concatenate([a[:-1][hit[0]:], a[:-1][:hit[0] + 1]]) for a in chain)


def _angle(surface: int) -> int:
    """Which of a gmsh cylinder's parameters runs round its axis (the surface bends along it; along the
    other it is straight)."""
    import gmsh

    lo, hi = (np.asarray(b, dtype=float) for b in gmsh.model.getParametrizationBounds(2, surface))
    mid, step = 0.5 * (lo + hi), 0.25 * (hi - lo)
    bend = []
    for i in (0, 1):
        uv = np.array([mid - step * (np.arange(2) == i), mid, mid + step * (np.arange(2) == i)])
        p = np.reshape(gmsh.model.getValue(2, surface, uv.ravel().tolist()), (3, 3))
        bend.append(float(np.linalg.norm(p[0] + p[2] - 2.0 * p[1])))
    return int(np.argmax(bend))


def layout(surface: int) -> Layout | str:
    """The grid of gmsh surface ``surface`` from its meshed boundary curves, or why it has none."""
    import gmsh

    from .gmsh_model import surface_curve_uses

    if surface not in SURFACES:
        return "not a long cylinder or torus between two circles (the boundary fit's grid faces)"
    uses = surface_curve_uses(surface)
    if any(len(gmsh.model.mesh.getElementsByType(1, c)[1]) == 0 for c in uses):
        return "a boundary curve carries no nodes"
    chains = {c: _chain(c, surface) for c in uses}
    # a circle keeps its height (gmsh may call an arc a "TrimmedCurve"), a line its angle
    still = {c: np.ptp(ch[2], axis=0) <= 1e-9 * max(float(np.ptp(ch[2], axis=0).max()), 1e-300)
             for c, ch in chains.items()}
    torus = surface in TORI  # its parallels run round with gmsh's (OCCT's) first parameter
    angle = 0 if torus else _angle(surface)
    circles = [c for c in uses if still[c][1 - angle] and not still[c][angle]]
    lines = [c for c in uses if still[c][angle] and not still[c][1 - angle]]
    whole = torus and len(circles) == 1 and uses[circles[0]] == 2  # a whole torus: one parallel, both ends
    if (len(circles) + whole != 2 or len(circles) + len(lines) != len(uses)
            or sum(uses[c] for c in lines) != 2):
        return "not bounded by two circles and the lines between them"
    rings = [chains[c] for c in circles]
    sides = [chains[c] for c in lines]
    if len(lines) == 1:  # full circles and a seam
        seam = sides[0]
        bottom = next((r for r in rings if seam[0][0] in r[0]), None)
        top = bottom if whole else next((r for r in rings if r is not bottom), None)
        if bottom is None or seam[0][-1] not in top[0]:
            return "its seam does not join its circles"
        bottom, top = _roll(bottom, seam[0][0]), _roll(top, seam[0][-1])
        if bottom is None or top is None:
            return "its circles are not closed at the seam"
        left = right = seam
    else:
        bottom = rings[0]
        left = next((c for s in sides if (c := _from(s, bottom[0][0])) is not None), None)
        right = next((c for s in sides if (c := _from(s, bottom[0][-1])) is not None and c[0] is not
                      (left[0] if left is not None else None)), None)
        if left is None or right is None or left[0][0] == right[0][0]:
            return "its lines do not join its circles' ends"
        top = _from(rings[1], left[0][-1])
        if top is None or top[0][-1] != right[0][-1]:
            return "its lines do not join its circles' ends"
    if len(left[0]) != len(right[0]):
        return "its lines do not carry as many nodes as each other"
    if len(lines) == 1:  # the top circle the same way round as the bottom one (both from the seam)
        ahead = bottom[1][1] - bottom[1][0]
        if np.dot(top[1][1] - top[1][0], ahead) < np.dot(top[1][-2] - top[1][-1], ahead):
            top = tuple(a[::-1] for a in top)
    chains = (bottom, top, left, right)
    uv = [np.array(c[2], dtype=float) for c in chains]
    for k in (0, 1):  # the circles' angles unwrapped, the top's turned onto the bottom's
        uv[k][:, angle] = np.unwrap(uv[k][:, angle])
    turn = 2.0 * np.pi
    uv[1][:, angle] += turn * np.round((uv[0][0, angle] - uv[1][0, angle]) / turn)
    if whole:  # the seam round the tube from the parallel back to it: the top is the parallel a turn on
        for k in (2, 3):
            uv[k][:, 1 - angle] = np.unwrap(uv[k][:, 1 - angle])
        uv[0][:, 1 - angle], uv[1][:, 1 - angle] = uv[2][0, 1 - angle], uv[2][-1, 1 - angle]
    steps = [np.diff(uv[k][:, angle]) for k in (0, 1)]
    if (not all(np.all(d > 0) for d in steps) and not all(np.all(d < 0) for d in steps)
            or not np.isclose(uv[0][-1, angle], uv[1][-1, angle])):
        return "its circles do not run the same way round"
    uv[2][:, angle], uv[3][:, angle] = uv[0][0, angle], uv[0][-1, angle]
    height = np.stack([np.linalg.norm(np.diff(s[1], axis=0), axis=1) for s in (left, right)])
    scale = _scale(surface, uv[0][0])
    turn = abs(uv[0][-1, angle] - uv[0][0, angle])
    fewest = 1 if torus else polygon_count(TARGET, turn) if TARGET else min(len(bottom[0]), len(top[0])) - 1
    k = height.shape[1]
    widths = [np.linalg.norm(np.diff(c[1], axis=0), axis=1) for c in (bottom, top)]
    # a band is the lines' segments up to band_reach() (the boundary fit graded them from a finer circle to
    # the grid's rows: GridFit.line_params)
    tall = height.mean(axis=0)
    row = float(np.median(tall))
    reach = [band_reach(row, float(np.mean(w))) * (1.0 - 1e-6) for w in widths]
    band = (int(np.searchsorted(np.cumsum(tall), reach[0])) + 1,
            int(np.searchsorted(np.cumsum(tall[::-1]), reach[1])) + 1)
    # the circles carry the columns, else one does and the other gets a band, else both get bands
    why = "too short for a grid between bands"
    for own in ((True, True),) if torus else ((True, True), (True, False), (False, True), (False, False)):
        lo, hi = (0 if own[i] else band[i] for i in (0, 1))
        rows = height[:, lo:max(k - hi, lo)].ravel()
        if not len(rows) or any(len(widths[i]) < fewest for i in (0, 1) if own[i]):
            continue
        if all(own) and len(widths[0]) != len(widths[1]):
            why = "its parallels carry different numbers of nodes" if torus else why
            continue
        if any(own):
            columns = len(widths[own.index(True)])
            width = np.concatenate([widths[i] for i in (0, 1) if own[i]])
        else:  # evenly spaced, never coarser than the target
            columns = max(int(np.rint(turn * scale[angle] / rows.mean())), fewest)
            width = np.full(1, turn * scale[angle] / columns)
        if np.degrees(np.arctan(min(width.min() / rows.max(), rows.min() / width.max()))) >= MIN_ANGLE:
            break
        why = f"its cells would give triangles under {MIN_ANGLE:g} degrees"
    else:
        return why
    if 2 * columns * k < FEWEST_TRIANGLES:
        return f"under {FEWEST_TRIANGLES} triangles as a grid: gmsh meshes it as well"
    return Layout(tuple(c[0] for c in chains), tuple(c[1] for c in chains), tuple(uv), angle, scale, columns, own,
                  (lo, hi))


def _scale(surface: int, uv: np.ndarray) -> np.ndarray:
    """The length of ``surface`` per unit of each parameter at ``uv`` (a cylinder's radius round it)."""
    import gmsh

    d = np.reshape(gmsh.model.getDerivative(2, surface, np.asarray(uv, dtype=float).tolist()), (2, 3))
    return np.linalg.norm(d, axis=1)


def mesh_grid(surface: int) -> str | None:
    """Mesh (empty) gmsh surface ``surface`` as a grid (:func:`layout`): rows at its lines' nodes, columns
    at its circles' nodes (blended between the two where both carry them) or evenly spaced, each cell cut
    along its shorter diagonal; a circle that does not carry the columns is joined to them by a band
    (:func:`_band`). None if it passed, else why not (nothing is added)."""
    import gmsh

    from .flat import add_triangles
    from .quality import min_angles

    lay = layout(surface)
    if isinstance(lay, str):
        return lay
    (bottom, top, left, right), (bx, tx, lx, rx), (buv, tuv, luv, ruv) = lay.tags, lay.xyz, lay.uv
    a, h = lay.angle, 1 - lay.angle
    lo, hi = lay.bands
    k = len(left) - 1
    rows = np.arange(lo, k - hi + 1)
    m = lay.columns
    span = buv[-1, a] - buv[0, a]
    carrier = buv if lay.own[0] else tuv if lay.own[1] else None  # the circle the columns run through
    sigma = np.linspace(0.0, 1.0, m + 1) if carrier is None else (carrier[:, a] - carrier[0, a]) / span
    tau = (luv[rows, h] - luv[0, h]) / (luv[-1, h] - luv[0, h])
    uv = np.empty((m + 1, len(rows), 2))
    if all(lay.own):  # both circles carry the columns: blended between them
        uv[:, :, a] = (1.0 - tau)[None, :] * buv[:, a][:, None] + tau[None, :] * tuv[:, a][:, None]
    else:
        uv[:, :, a] = (buv[0, a] + sigma * span)[:, None]
    uv[:, :, h] = (1.0 - sigma)[:, None] * luv[rows, h][None, :] + sigma[:, None] * ruv[rows, h][None, :]
    tags = np.full((m + 1, len(rows)), -1, dtype=np.int64)
    xyz = np.empty((m + 1, len(rows), 3))
    sides = [((0, slice(None)), left[rows], lx[rows], luv[rows]),
             ((m, slice(None)), right[rows], rx[rows], ruv[rows])]
    if lay.own[0]:
        sides.append(((slice(None), 0), bottom, bx, buv))
    if lay.own[1]:
        sides.append(((slice(None), len(rows) - 1), top, tx, tuv))
    for (i, j), t, x, p in sides:
        tags[i, j], xyz[i, j], uv[i, j] = t, x, p
    fresh = tags < 0
    if fresh.any():
        xyz[fresh] = np.reshape(gmsh.model.getValue(2, surface, uv[fresh].ravel().tolist()), (-1, 3))
    p = np.arange((m + 1) * len(rows)).reshape(m + 1, len(rows))
    c00, c10, c11, c01 = p[:-1, :-1].ravel(), p[1:, :-1].ravel(), p[1:, 1:].ravel(), p[:-1, 1:].ravel()
    x = xyz.reshape(-1, 3)
    short = np.linalg.norm(x[c00] - x[c11], axis=1) <= np.linalg.norm(x[c10] - x[c01], axis=1)
    tri = [np.where(short[:, None], np.stack([c00, c10, c11], axis=1), np.stack([c00, c10, c01], axis=1)),
           np.where(short[:, None], np.stack([c00, c11, c01], axis=1), np.stack([c10, c11, c01], axis=1))]
    nodes = [(tags.ravel(), x, uv.reshape(-1, 2))]
    count = len(x)
    for end in (0, 1):
        if lay.own[end]:
            continue
        ring = p[:, -1 if end else 0]  # the grid's row next to the band
        got = _band(surface, lay, end, ring, x[ring], uv.reshape(-1, 2)[ring], count)
        if isinstance(got, str):
            return got
        (t_new, x_new, uv_new), band = got
        nodes.append((t_new, x_new, uv_new))
        count += len(t_new)
        tri.append(band)
    tags_all, x_all, uv_all = (np.concatenate([n[i] for n in nodes]) for i in range(3))
    tri_all = np.concatenate(tri)
    smallest = float(min_angles(x_all, tri_all).min())
    if smallest < BAND_MIN_ANGLE or (all(lay.own) and smallest < MIN_ANGLE - 1.0):
        return f"its grid's triangles came out at {smallest:.1f} degrees"
    add_triangles(surface, tags_all, x_all, tri_all, uv_all)
    return None


def _band(surface: int, lay: Layout, end: int, ring: np.ndarray, ring_x: np.ndarray, ring_uv: np.ndarray,
          first: int) -> tuple | str:
    """The band between circle ``end`` (0 bottom, 1 top) and the grid's row next to it (``ring``: its
    nodes' rows in the grid's node list, their points and parameters), along the lines' last
    ``lay.bands[end]`` segments: laid flat (a cylinder unrolls without stretching), meshed by gmsh on
    those boundary nodes (:func:`cadedge.mesh.flat.mesh_plane`) the best of :data:`BAND_VARIANTS` ways,
    rolled back up.
    Returns the nodes it adds (tags, -1 for new ones; points; parameters; rows from ``first`` on) and its
    triangles (rows of the grid's node list and of those), or why not."""
    import gmsh

    from .flat import boundary_sizes, mesh_plane
    from .optimize import improve_plane
    from .quality import min_angles

    (_, _, left, right), (bx, tx, lx, rx), (buv, tuv, luv, ruv) = lay.tags, lay.xyz, lay.uv
    a, h = lay.angle, 1 - lay.angle
    k = len(left) - 1
    inner = np.arange(len(ring) - 2, 0, -1)  # the ring's own nodes, right to left (its ends are the lines')
    if end == 0:  # circle left to right, right line up to the ring, ring right to left, left line down
        up = np.arange(1, lay.bands[0] + 1)
        down = up[::-1]
        parts = [(lay.tags[0], bx, buv), (right[up], rx[up], ruv[up]), None, (left[down], lx[down], luv[down])]
    else:  # left line up from the ring, circle left to right, right line down to the ring, ring right to left
        up = np.arange(k - lay.bands[1], k)
        down = up[::-1]
        parts = [(left[up], lx[up], luv[up]), (lay.tags[1], tx, tuv), (right[down], rx[down], ruv[down]), None]
    grid_part = (np.full(len(inner), -1, dtype=np.int64), ring_x[inner], ring_uv[inner])
    at = [None] * 4
    at[parts.index(None)] = ring[inner]
    parts[parts.index(None)] = grid_part
    loop_tags, loop_x, loop_uv = (np.concatenate([q[i] for q in parts]) for i in range(3))
    grid_row = np.concatenate([g if g is not None else np.full(len(q[0]), -1) for g, q in zip(at, parts)])
    origin = np.array([buv[0, a], luv[0, h]])
    scale = np.array([lay.scale[a], lay.scale[h]]) * np.sign([buv[-1, a] - buv[0, a], luv[-1, h] - luv[0, h]])
    plane = (loop_uv[:, [a, h]] - origin) * scale
    segments = [(i, (i + 1) % len(plane)) for i in range(len(plane))]
    # sizes growing from the circle's segments to the grid's columns, as the lines were graded
    # (GridFit.line_params)
    start = 0 if end == 0 else len(parts[0][0])  # the circle's rows in the loop
    circle = plane[start:start + len(lay.tags[end])]
    spacing = float(np.mean(np.linalg.norm(np.diff(circle, axis=0), axis=1)))
    width = float(np.mean(np.linalg.norm(np.diff(ring_x, axis=0), axis=1)))
    grow = f"Min({width!r}, {spacing!r} + {BAND_GROWTH!r} * Abs(y - {float(np.mean(circle[:, 1]))!r}))"

    def growing() -> None:
        tag = gmsh.model.mesh.field.add("MathEval")
        gmsh.model.mesh.field.setString(tag, "F", grow)
        gmsh.model.mesh.field.setAsBackgroundMesh(tag)

    fixed = {(min(i, j), max(i, j)) for i, j in segments}
    near = boundary_sizes(plane, segments)
    best, got = -1.0, "gmsh made no band"
    for algorithm, field in BAND_VARIANTS:
        options = {"Mesh.MeshSizeFromCurvature": 0}
        if field:  # the field's sizes alone, not the boundary's carried inwards
            options.update({"Mesh.MeshSizeExtendFromBoundary": 0, "Mesh.MeshSizeFromPoints": 0})
        trial = mesh_plane(plane, segments, near, algorithm, growing if field else lambda: None, options)
        if isinstance(trial, str):
            got = got if best >= 0 else trial
            continue
        trial = improve_plane(*trial, np.arange(len(trial[0])) >= len(plane), fixed, below=MIN_ANGLE)
        angle = float(min_angles(np.column_stack([trial[0], np.zeros(len(trial[0]))]), trial[1]).min())
        if angle > best:
            best, got = angle, trial
        if best >= BAND_GOOD:
            break
    if isinstance(got, str):
        return f"its band: {got}"
    points, tri = got
    e1, e2 = points[tri[:, 1]] - points[tri[:, 0]], points[tri[:, 2]] - points[tri[:, 0]]
    turned = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0  # all anticlockwise in the plane, as the grid's
    tri[turned] = tri[turned][:, [0, 2, 1]]
    fresh = points[len(plane):]
    params = np.empty((len(fresh), 2))
    params[:, [a, h]] = origin + fresh / scale
    fresh_x = (np.reshape(gmsh.model.getValue(2, surface, params.ravel().tolist()), (-1, 3)) if len(fresh)
               else np.zeros((0, 3)))
    own = grid_row < 0  # the circle's and lines' nodes join the node list again, under their own tags
    row = np.where(own, first + np.cumsum(own) - 1, grid_row)
    row = np.concatenate([row, first + int(own.sum()) + np.arange(len(fresh))])
    nodes = (np.concatenate([loop_tags[own], np.full(len(fresh), -1, dtype=np.int64)]),
             np.vstack([loop_x[own], fresh_x]), np.vstack([loop_uv[own], params]))
    return nodes, row[tri]
