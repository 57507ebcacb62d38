"""Split boundary segments that are longer than their face is wide.

A face 40 mm long and 0.02 mm wide (the side of a thin plate, a small chamfer, the walls of a notch) can
only be filled with slivers while its long edges keep the few segments their ALD needs: every triangle
spans the face from one long edge to the other. The size field of :mod:`cadedge.mesh.proximity` does not
see it, since it grows from spacings, not from distances. Here the local width of a face at a boundary
segment is the distance from the segment's midpoint to the face's other boundary segments, leaving out
the segment's own edge and the edges that share a B-rep vertex with it (a face that narrows to a corner
has no width there: the corner's angle forces its triangles, see :mod:`cadedge.mesh.quality`). An edge
that passes a vertex within the vertex's tolerance touches it as if it ended there
(:func:`touching_vertices`): a helical flight fused to a shaft ends on the shaft's seam, 2.3e-6 off it at
vertices of tolerance 5e-6, and measured across that gap the flight's end line and the helix that meets
it were cut to pieces of 1.5e-5 (26 755 on the end line once loose edges could be cut finer). Segments
longer than :data:`WIDTH_RATIO` (or :data:`FINE_RATIO`, where that costs few segments) times that width
are split into pieces of equal arc length on their OCCT curve, pass after pass: near a tiny edge the
splits halve towards it, so the boundary is graded down to the tiny edge's length instead of jumping to
it. Grid points are kept and edge ends never move. A loose edge is cut into no piece shorter than it
allows (:class:`~cadedge.mesh.proximity.Looseness`): left whole, its chords sagged across a thin face
and the width measured from the other side counted the sag.

Then the face corners (:func:`match_corners`): where a face's boundary segments meet at a B-rep vertex,
those longer than :data:`CORNER_RATIO` times the shortest are halved. A 90-degree corner between a
cylinder's 2.55 seam segment and its 1.29 circle segment left 39.5-degree triangles that no node move
undoes (42 once matched; gmsh alone, with near-uniform sizes, gets 40.4).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from ..grid import row_norms
from ..shapegrid import ShapeGrid, with_edges
from ..splitting import split_segments
from .budget import MAX_FACE_TRIANGLES
from .proximity import Looseness, _LazyCurves
from .segments import segment_feet
from .stagger import stagger

#: A segment is split when longer than this many times its face's width at its midpoint: a strip of
#: width w cut into pieces of 2 w is filled by right triangles of 26.6 degrees.
WIDTH_RATIO = 2.0
#: Pieces of at most 1.5 w give 33.7 degrees, and are cut instead where that adds at most
#: :data:`FINE_SHARE` of the model's boundary segments: a filleted sphere-box's neck between two fillets,
#: 0.15-0.5 mm wide (1 855 -> 1 946 segments at 1e-2, 26.9 -> 32.9 degrees; gmsh tuned: 31.8 with six
#: times the triangles). Where thin faces make much of the model (the M6 screw's thread flanks, a thin
#: plate, a thin washer: 25-43% more segments, up to 64% more triangles) the pieces stay at 2 w.
FINE_RATIO = 1.5
FINE_SHARE = 0.1
#: Splitting halves segments towards a tiny edge each pass; 24 passes cover a ratio of 1.6e7.
PASSES = 24
#: The splits may add at most this many times the grid's segments (plus :data:`MIN_BUDGET`), and never
#: more than :data:`MOST_ADDED`: a model with thousands of sliver faces is left with slivers rather than
#: millions of boundary nodes.
BUDGET_FACTOR = 20.0
MIN_BUDGET = 200_000
#: Each boundary node added costs its faces about 8 triangles more (their sizes grow from it at 0.25 per
#: unit length), so the splits add at most an eighth of a face's triangle budget
#: (:data:`~cadedge.mesh.budget.MAX_FACE_TRIANGLES`) in all: a Braille plate of 47 dots, each ringed by a
#: band 0.001 tall (cadquery-contrib's Braille.py), took 253 900 segments and 1.9 million triangles at
#: ALD 1e-2 under the relative budget alone, and 43 of its 108 faces ran out of the 300 s.
MOST_ADDED = MAX_FACE_TRIANGLES // 8
#: Where the splits at :data:`WIDTH_RATIO` do not fit the budget, the ratio is doubled until they do (up to
#: this), so every thin face is cut alike rather than the first ones whole and the rest not at all.
MAX_WIDTH_RATIO = 32.0
#: Pieces of r w cut alike on both sides of a strip face each other, and fill it with right triangles of
#: atan(1 / r): under 20 degrees above this ratio, which only the budget's doubling reaches (14.0 at 4).
#: There the sides are staggered (:mod:`cadedge.mesh.stagger`): atan(2 / r), 26.6 at 4. Below it, the
#: points the edges were refined with (graded towards the vertices) break the stagger into stretches
#: with half pieces at their ends, and the corpus's smallest angles fell (the bracket 36.0 -> 33.7 at
#: 1e-2, the spline prism 42.5 -> 40.3) with more triangles.
STAGGER_RATIO = 1.0 / math.tan(math.radians(20.0))
#: At a face corner the boundary segments ending there are made at most this ratio of the shortest of
#: them (halved, at most :data:`CORNER_PASSES` times).
CORNER_RATIO = 1.5
CORNER_PASSES = 4
#: A narrow corner's tip may be halved where its halves fall this share short of the corner's other tip:
#: an edge split in two at a thin face (the ridge between two overlapping holes) is halved again at
#: the neighbouring edge's end, 0.1876 against 2 x 0.09385, and left whole it was later cut in four.
TIP_SLACK = 0.01
#: Point-to-segment distances are computed exactly in blocks of this many pairs.
_BLOCK = 2_000_000
#: A face whose midpoints and segments make more pairs than this has its widths, where only those within
#: a reach are sought, measured by k-d trees (:func:`_near_distances`), near pairs only: an Open CASCADE
#: 6.8 circuit board (3 379 faces, most of a few hundred segments) took 47 s in the thin faces' splits
#: when only faces over :data:`_BLOCK` pairs were, 17 s at this (the same splits).
TREE_PAIRS = 50_000
#: A numpy call costs about as much as this many point-segment distances: a face's widths are measured in
#: one call, every midpoint against every segment, where that measures fewer extra pairs than the calls
#: per edge it saves cost (cadquery-contrib's tetrakaidecahedron lattice: 10 182 faces of a few edges).
CALL_PAIRS = 200


def _segment_distances(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from each point ``p`` (n, 3) to the nearest of the segments ``a``-``b`` (m, 3)."""
    out = np.full(len(p), np.inf)
    if not len(a):
        return out
    step = max(1, _BLOCK // len(a))
    for s in range(0, len(p), step):
        out[s:s + step] = segment_feet(p[s:s + step, None, :], a[None], b[None])[0].min(axis=1)
    return out


def _near_distances(p: np.ndarray, reach: np.ndarray, a: np.ndarray, b: np.ndarray,
                    keep: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> np.ndarray:
    """Distance from each point ``p`` (n, 3) to the nearest of the segments ``a``-``b`` (m, 3) that
    ``keep(rows, cols)`` admits (boolean per point-segment pair), exact where it is at most the point's
    ``reach`` (n,), ``inf`` or exact beyond. The segments are grouped by length and the points by reach,
    each group within a factor 2, in one k-d tree of segment midpoints or of points per group: a segment
    within ``reach`` of a point has its midpoint within ``reach`` plus its half-length, so only the pairs
    two trees find that close are measured (all pairs, on the ibeam's web: 88 s). The trees' pairs come
    as arrays (``sparse_distance_matrix``): one list per point (``query_ball_point``) made the I-beam's
    widths at 1e-3 8.9 s instead of 2.4."""
    from scipy.spatial import cKDTree

    out = np.full(len(p), np.inf)
    ask = np.flatnonzero(reach > 0)
    if not len(ask) or not len(a):
        return out
    mid, half = 0.5 * (a + b), 0.5 * np.linalg.norm(b - a, axis=1)
    group = np.floor(np.log2(np.maximum(half, 1e-300) / max(float(half.max()), 1e-300))).clip(-64, 0)
    band = np.floor(np.log2(reach[ask] / float(reach[ask].max()))).clip(-64, 0)
    points = [(ask[band == r], cKDTree(p[ask[band == r]])) for r in np.unique(band)]
    for g in np.unique(group):
        cols = np.flatnonzero(group == g)
        segments, longest = cKDTree(mid[cols]), float(half[cols].max())
        for rows_r, tree in points:
            pairs = tree.sparse_distance_matrix(segments, float(reach[rows_r].max()) + longest,
                                                output_type="ndarray")
            if not len(pairs):
                continue
            rows, seg = rows_r[pairs["i"]], cols[pairs["j"]]
            ok = keep(rows, seg)
            rows, seg = rows[ok], seg[ok]
            for s in range(0, len(rows), _BLOCK):
                r, k = rows[s:s + _BLOCK], seg[s:s + _BLOCK]
                np.minimum.at(out, r, segment_feet(p[r], a[k], b[k])[0])
    return out


def _spans(start: np.ndarray, count: np.ndarray) -> np.ndarray:
    """``start[i], start[i] + 1, ... start[i] + count[i] - 1`` for every ``i``, end to end."""
    return np.repeat(start - np.cumsum(count) + count, count) + np.arange(int(count.sum()))


#: An edge whose two vertices are closer than this share of its length (a loop not quite closed) spans
#: an opening its faces do not: the edges at one of its ends touch the vertex at the other.
LOOP_SHARE = 1e-3


def _across_loops(live: list, touches: dict[int, set[int]]) -> None:
    """Add to ``touches`` the vertices across every open loop among the ``live`` edges (:data:`LOOP_SHARE`).

    pythonocc-demos' surf114.igs holds an unsewn spline band: its two long sides (27.4 long) run 1.5-3.9e-5
    apart across the opening, its short sides are loops of 7.7 from one long side's end to the other's.
    Measured across that opening, which is outside the face, one long side was cut into 41 783 pieces
    and gmsh hung on the face."""
    ends = np.array([[e.points[0], e.points[-1]] for e in live])
    length = np.array([e.length for e in live])
    opening = np.linalg.norm(ends[:, 0] - ends[:, 1], axis=1)
    loops = [e for e, o, n in zip(live, opening, length) if e.vertices[0] != e.vertices[-1] and o <= LOOP_SHARE * n]
    if not loops:
        return
    at: dict[tuple[int, int], list[int]] = {}  # (face, vertex) -> the edges of that face at that vertex
    for e in live:
        for f in set(e.faces):
            for v in set(e.vertices):
                at.setdefault((f, v), []).append(e.id)
    for e in loops:
        u, v = e.vertices[0], e.vertices[-1]
        for f in set(e.faces):
            for near, far in ((u, v), (v, u)):
                for other in at.get((f, near), []):
                    touches[other].add(far)


def touching_vertices(grid: ShapeGrid) -> dict[int, set[int]]:
    """Edge id -> the B-rep vertices it touches: its own, and those of its faces' other edges that its grid
    passes within the vertex's tolerance (or its own, the larger), away from its ends: a vertex left on
    an edge by a boolean operation without splitting it. (A vertex that near an edge's end is a tiny
    edge away from its vertex there, and the boundary is graded down to that edge: Solid_56's torus,
    a 0.0103 edge between vertices whose edges carry tolerances up to 0.019.) Candidates are the
    vertices within an edge's bounding sphere (one k-d tree query for all edges), measured against all
    its segments in one call. And across an open loop (:func:`_across_loops`), the vertex at its far end."""
    from scipy.spatial import cKDTree

    touches = {e.id: set(e.vertices) for e in grid.edges}
    live = [e for e in grid.edges if not e.degenerate and len(e.points) >= 2]
    if not live or not grid.vertices:
        return touches
    _across_loops(live, touches)
    row = {v.id: r for r, v in enumerate(grid.vertices)}
    at = np.array([v.point for v in grid.vertices], dtype=float)
    tol = np.array([v.tolerance for v in grid.vertices])
    count = np.array([len(e.points) - 1 for e in live])
    first = np.concatenate([[0], np.cumsum(count)[:-1]])
    a = np.vstack([e.points[:-1] for e in live])
    b = np.vstack([e.points[1:] for e in live])
    lo = np.minimum(np.minimum.reduceat(a, first), np.minimum.reduceat(b, first))
    hi = np.maximum(np.maximum.reduceat(a, first), np.maximum.reduceat(b, first))
    own_tol = np.array([e.tolerance for e in live])
    near = cKDTree(at).query_ball_point(0.5 * (lo + hi), 0.5 * np.linalg.norm(hi - lo, axis=1)
                                        + np.maximum(tol.max(), own_tol))
    edge = np.repeat(np.arange(len(live)), [len(n) for n in near])
    vert = np.fromiter((r for n in near for r in n), dtype=np.int64, count=len(edge))
    # a candidate is a vertex of one of the edge's faces (codes face * V + vertex row), not one of its own
    ends = np.array([[row.get(v, -1) for v in e.vertices] for e in live], dtype=np.int64).reshape(-1, 2)
    edge_faces = [sorted(set(e.faces)) for e in live]
    nf = np.array([len(f) for f in edge_faces])
    face = np.fromiter((f for fs in edge_faces for f in fs), dtype=np.int64, count=int(nf.sum()))
    end_rows = np.repeat(ends, nf, axis=0).ravel()
    on_face = np.unique((np.repeat(face, 2) * len(at) + end_rows)[end_rows >= 0])
    keep = (vert != ends[edge, 0]) & (vert != ends[edge, 1]) & (nf[edge] > 0)
    edge, vert = edge[keep], vert[keep]
    if not len(edge):
        return touches
    hit = np.isin(face[_spans(np.cumsum(nf)[edge] - nf[edge], nf[edge])] * len(at) + vert.repeat(nf[edge]),
                  on_face)
    keep = np.add.reduceat(hit, np.cumsum(nf[edge]) - nf[edge]) > 0
    edge, vert = edge[keep], vert[keep]
    if not len(edge):
        return touches
    per = count[edge]  # each candidate against every segment of its edge
    seg = _spans(first[edge], per)
    d = np.minimum.reduceat(segment_feet(at[vert].repeat(per, axis=0), a[seg], b[seg])[0], np.cumsum(per) - per)
    reach = np.maximum(tol[vert], own_tol[edge])
    ends_at = np.stack([a[first[edge]], b[first[edge] + count[edge] - 1]], axis=1)  # the edge's end points
    inside = np.linalg.norm(ends_at - at[vert][:, None], axis=2).min(axis=1) > reach  # not by one of its ends
    hit = (d <= reach) & inside
    for k, r in zip(edge[hit].tolist(), vert[hit].tolist()):
        touches[live[k].id].add(grid.vertices[r].id)
    return touches


def face_widths(edges: list, *, reach: float | None = None, touches: dict[int, set[int]] | None = None,
                only: list[int] | None = None) -> dict[int, np.ndarray]:
    """Per edge index, the width at each segment's midpoint: the smallest, over the faces the edge
    bounds, of the distance to that face's boundary segments on edges touching no vertex it touches
    (``touches``, by edge id, :func:`touching_vertices`; by default its own two) (``inf`` where no such
    edge exists). With ``reach``, widths are sought only out to ``reach`` times the segment's length:
    beyond that they may be ``inf`` (a split only needs widths under the segment's length over the
    ratio, and large faces are then searched near each segment only). With ``only`` (edge indices),
    just those edges' widths, measured on their faces alone."""

    def touched(e) -> set[int]:
        return touches.get(e.id, set(e.vertices)) if touches is not None else set(e.vertices)

    usable = [i for i, e in enumerate(edges) if not e.degenerate and len(e.points) >= 2]
    by_face: dict[int, list[int]] = {}
    for i in usable:
        for f in edges[i].faces:
            by_face.setdefault(f, []).append(i)
    if only is not None:
        wanted = {f for i in only for f in edges[i].faces}
        by_face = {f: idx for f, idx in by_face.items() if f in wanted}
        keep = set(usable)
        usable = [i for i in only if i in keep]
    width = {i: np.full(len(edges[i].points) - 1, np.inf) for i in usable}
    for idx in by_face.values():
        if len(idx) < 2:
            continue
        count = [len(edges[i].points) - 1 for i in idx]
        n = sum(count)
        large = reach is not None and n * n > TREE_PAIRS  # k-d trees, near pairs only
        few = n * n <= _BLOCK and n * n - sum(c * (n - c) for c in count) < CALL_PAIRS * (len(idx) - 1)
        if large or few:  # the whole face at once; else (below) each edge against the others
            a = np.vstack([edges[i].points[:-1] for i in idx])
            b = np.vstack([edges[i].points[1:] for i in idx])
            owner = np.repeat(np.arange(len(idx)), count)
            if large:
                touching: dict[int, list[int]] = {}  # B-rep vertex -> the face's edges (local numbers) at it
                for k, i in enumerate(idx):
                    for v in touched(edges[i]):
                        touching.setdefault(v, []).append(k)
                near = np.unique([k * len(idx) + j for at in touching.values() for k in at for j in at]
                                 + [k * (len(idx) + 1) for k in range(len(idx))])  # pairs sharing a vertex
                got = _near_distances(0.5 * (a + b), reach * np.linalg.norm(b - a, axis=1), a, b,
                                      lambda rows, cols: ~np.isin(owner[rows] * len(idx) + owner[cols], near))
            else:  # a face of a few short edges: all its midpoints against all its segments in one call
                ends = [touched(edges[i]) for i in idx]
                apart = np.array([[not p & q for q in ends] for p in ends])  # an edge meets itself: not apart
                d = segment_feet(0.5 * (a + b)[:, None], a[None], b[None])[0]
                got = np.where(apart[owner][:, owner], d, np.inf).min(axis=1)
            for i, part in zip(idx, np.split(got, np.cumsum(count)[:-1])):
                if i in width:
                    width[i] = np.minimum(width[i], part)
            continue
        for i in idx:
            if i not in width:
                continue
            e = edges[i]
            others = [edges[j] for j in idx if j != i and not touched(edges[j]) & touched(e)]
            if not others:
                continue
            a = np.vstack([o.points[:-1] for o in others])
            b = np.vstack([o.points[1:] for o in others])
            width[i] = np.minimum(width[i], _segment_distances(0.5 * (e.points[:-1] + e.points[1:]), a, b))
    return width


def fit_to_widths(grid: ShapeGrid, *, ratio: float | None = None, passes: int = PASSES,
                  keep: ShapeGrid | None = None) -> ShapeGrid:
    """A copy of ``grid`` whose boundary segments are at most ``ratio`` times their face's width (by
    default :data:`FINE_RATIO` where that adds at most :data:`FINE_SHARE` of the grid's segments and fits
    the budget, else :data:`WIDTH_RATIO`, doubled while the splits do not fit the budget, up to
    :data:`MAX_WIDTH_RATIO`), above :data:`STAGGER_RATIO` each thin strip's sides staggered
    (:func:`~cadedge.mesh.stagger.stagger`, which may lengthen a segment by
    :data:`~cadedge.mesh.stagger.LONGEST` and moves no point of ``keep``, by default ``grid``), its face
    corners matched (:func:`match_corners`)."""
    curves = grid.curves if grid.curves is not None else _LazyCurves(grid)
    touches = touching_vertices(grid)
    if ratio is not None:
        fitted = _split_to_widths(grid, curves, touches, ratio, passes)[0]
    else:
        fitted, ratio = _fit_ratio(grid, curves, touches, passes)
    if ratio > STAGGER_RATIO:
        fitted = stagger(grid, fitted, curves=curves, touches=touches, keep=keep)
    return match_corners(fitted, curves=curves)


def _fit_ratio(grid: ShapeGrid, curves, touches: dict[int, set[int]], passes: int) -> tuple[ShapeGrid, float]:
    """``grid`` split to the default ratio (:func:`fit_to_widths`), and that ratio."""
    # the widths out to 1 / FINE_RATIO serve every larger ratio's first pass as well
    first = face_widths(list(grid.edges), reach=1.0 / FINE_RATIO, touches=touches)
    fitted, short = _split_to_widths(grid, curves, touches, FINE_RATIO, passes, first)
    if not short and fitted.segments <= (1.0 + FINE_SHARE) * grid.segments:
        return fitted, FINE_RATIO
    ratio = WIDTH_RATIO
    coarse, tight = _split_to_widths(grid, curves, touches, ratio, passes, first)
    while tight and ratio < MAX_WIDTH_RATIO:
        ratio *= 2.0
        coarse, tight = _split_to_widths(grid, curves, touches, ratio, passes, first)
    if short or fitted.segments > (1.0 + FINE_SHARE) * coarse.segments:
        return coarse, ratio
    return fitted, FINE_RATIO


def _split_to_widths(grid: ShapeGrid, curves, touches: dict[int, set[int]], ratio: float,
                     passes: int, first: dict[int, np.ndarray] | None = None) -> tuple[ShapeGrid, bool]:
    """A copy of ``grid`` whose boundary segments are at most ``ratio`` times their face's width (edges
    apart by ``touches``, :func:`face_widths`; ``first``, if given, the grid's widths out to at least
    ``1 / ratio``), and whether the budget (:data:`BUDGET_FACTOR`, :data:`MIN_BUDGET`,
    :data:`MOST_ADDED`) left a split out. A loose edge (:class:`~cadedge.mesh.proximity.Looseness`) is
    cut into no piece shorter than it allows, or, where those cuts do not fit the budget, left whole
    without asking anything of it: its cuts never reach the width, and the flight's end line, measured
    across a 2.3e-6 gap, would take a million.

    After the first pass only the edges of faces a split changed are measured again (the others' widths
    stand, and an edge the budget left whole stays so, the budget only shrinking): the Koch leader arm's
    12 104 edges at 1e-2 were measured whole in every pass."""
    edges = list(grid.edges)
    budget = min(BUDGET_FACTOR * grid.segments + MIN_BUDGET, MOST_ADDED)
    added, short = 0, False
    loose = Looseness(grid)
    on_face: dict[int, list[int]] = {}
    for i, e in enumerate(edges):
        for f in set(e.faces):
            on_face.setdefault(f, []).append(i)
    width = first if first is not None else face_widths(edges, reach=1.0 / ratio, touches=touches)
    for _ in range(passes):
        changed = []
        for i, w in width.items():
            e = edges[i]
            if not np.all(np.diff(e.params) > 0):
                continue
            seg = e.segment_lengths
            with np.errstate(invalid="ignore"):
                pieces = np.where(seg > ratio * w, np.ceil(seg / (ratio * np.maximum(w, 1e-300))), 1)
            pieces = np.nan_to_num(pieces, nan=1.0, posinf=1.0).astype(np.int64)
            wanted = pieces
            pieces = loose.capped(e, wanted)  # a loose edge (see proximity.py): no piece shorter than it allows
            held = not np.array_equal(pieces, wanted)
            new = int(np.sum(pieces - 1))
            if not new or (held and added + new > budget):
                continue  # nothing to split; or a loose edge's cuts, which never reach its width, do not fit
            if added + new > budget:
                short = True
                continue
            params, points = split_segments(e.params, e.points, pieces, curves[e.id].evaluate)
            edges[i] = dataclasses.replace(e, params=params, points=points)
            added += new
            changed.append(i)
        if not changed:
            break
        again = sorted({j for i in changed for f in set(edges[i].faces) for j in on_face[f]})
        width = face_widths(edges, reach=1.0 / ratio, touches=touches, only=again)
    return with_edges(grid, edges), short


def match_corners(grid: ShapeGrid, *, ratio: float = CORNER_RATIO, passes: int = CORNER_PASSES,
                  curves: dict | None = None) -> ShapeGrid:
    """A copy of ``grid`` in which, at every corner of every face (a B-rep vertex), the face's boundary
    segments that end there are within ``ratio`` of the shortest of them: longer ones are halved (in
    parameter, on their OCCT curve), pass after pass; a segment that ends at a narrow corner (one of its
    *tips*, :mod:`cadedge.mesh.wedges`, which makes them equal, as long as the shorter) is halved only
    where its halves are no shorter than the corner's other tip (within :data:`TIP_SLACK`), and a loose
    edge's segment only where its halves are no shorter than the edge allows
    (:meth:`~cadedge.mesh.proximity.Looseness.capped`). Grid points are kept and edge ends never move; an
    edge OCCT cannot evaluate keeps its grid."""
    from ..errors import GeometryError
    from ..occt.compat import OCCT_ERRORS
    from .narrow import narrow_corners, tip_length, tip_segment

    curves = curves if curves is not None else (grid.curves if grid.curves is not None else _LazyCurves(grid))
    edges = list(grid.edges)
    loose = Looseness(grid)
    for _ in range(passes):
        tips: dict[tuple[int, int], float] = {}  # a narrow corner's tip -> the other tip's length there
        for c in narrow_corners(edges):
            for (i, at_start), (j, other) in (c.sides, c.sides[::-1]):
                k = tip_segment(edges[i], at_start)
                tips[i, k] = min(tips.get((i, k), np.inf), tip_length(edges[j], other))
        ends: dict[tuple[int, int], list[tuple[int, int]]] = {}
        for i, e in enumerate(edges):
            if e.degenerate or len(e.points) < 2 or len(e.vertices) < 2 or not np.all(np.diff(e.params) > 0):
                continue
            for f in e.faces:
                ends.setdefault((f, e.vertices[0]), []).append((i, 0))
                ends.setdefault((f, e.vertices[-1]), []).append((i, len(e.points) - 2))
        pieces = {i: np.ones(len(e.points) - 1, dtype=np.int64) for i, e in enumerate(edges) if len(e.points) >= 2}
        corners = [c for c in ends.values() if len(c) >= 2]
        at = [(i, k) for c in corners for i, k in c]  # every corner's end segments, measured in one call
        measured = row_norms(np.array([edges[i].points[k + 1] for i, k in at]).reshape(-1, 3)
                             - np.array([edges[i].points[k] for i, k in at]).reshape(-1, 3))
        for corner, lengths in zip(corners, np.split(measured, np.cumsum([len(c) for c in corners])[:-1])):
            short = lengths.min()
            for (i, k), length in zip(corner, lengths):
                if length > ratio * short and length >= 2.0 * (1.0 - TIP_SLACK) * tips.get((i, k), 0.0):
                    pieces[i][k] = 2
        changed = False
        for i, k in pieces.items():
            e = edges[i]
            k = loose.capped(e, k)  # a loose edge's segments halved only where it allows
            if not np.any(k > 1):
                continue
            try:
                params, points = split_segments(e.params, e.points, k, curves[e.id].evaluate)
            except (GeometryError, *OCCT_ERRORS):  # OCCT cannot evaluate this edge: keep its grid
                continue
            edges[i] = dataclasses.replace(e, params=params, points=points)
            changed = True
        if not changed:
            break
    return with_edges(grid, edges)
