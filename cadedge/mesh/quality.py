"""Triangle quality: angles per triangle and per face, and which small angles the B-rep forces.

A triangle's quality here is its smallest interior angle. Simulation wants none below 5 degrees and
at least 99% at 20 degrees or more. A face corner sharper than 5 degrees (two boundary edges meeting
almost tangentially) forces a small angle on whatever triangle fills it, as do a strip narrower than its
boundary segments and the apex of a cone narrower than about 2.4 degrees: such triangles are named with
that reason instead of counted against the mesher.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from .. import kernels
from .segments import segment_feet

#: Below this many degrees a triangle is a sliver unless the B-rep forces it.
SLIVER_DEG = 5.0
#: The share of triangles at or above this many degrees is the quality figure (target: 99%).
GOOD_DEG = 20.0
#: A triangle under :data:`SLIVER_DEG` in the wedge of a sharper face corner is forced when no triangle on
#: its boundary segment there can get over this many degrees (see :func:`small_angles`): its apex would
#: have to lie beyond the face's other side.
WEDGE_BOUND = 2 * SLIVER_DEG
#: A triangle under :data:`SLIVER_DEG` with a node on an edge that lies off its face's boundary (the
#: edge's pcurve on the face's surface) by ``d`` is forced when it is at most this many times ``d``
#: long: the mesh joins the edge's nodes, where they are, to the face's, on its surface where the
#: boundary runs, and a triangle that small spans the gap (an OCCT offset of a loft, edges 1-2.3 mm
#: off their faces: 165 triangles under 5 degrees beside them).
OFF_REACH = 4.0


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (m, 3) arrays, by components (``np.cross`` spends most of its time
    rearranging axes on the optimiser's many small arrays)."""
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def triangle_angles(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Interior angles (m, 3) in degrees; column ``k`` is the angle at corner ``k``."""
    p = np.asarray(nodes, dtype=float)[np.asarray(triangles, dtype=np.int64).reshape(-1, 3)]
    e = [p[:, 1] - p[:, 0], p[:, 2] - p[:, 1], p[:, 0] - p[:, 2]]  # edge k leaves corner k
    c = cross(e[0], e[1])
    twice_area = np.sqrt(np.einsum("ij,ij->i", c, c))  # the same |a x b| at every corner
    out = np.empty((len(p), 3))
    for k in range(3):
        out[:, k] = np.degrees(np.arctan2(twice_area, -np.einsum("ij,ij->i", e[k], e[k - 1])))
    return out


#: A triangle whose largest angle is within this many radians of 180 degrees is flat: its middle node lies
#: on the opposite edge, to rounding (Frontal-Delaunay left three consecutive seam nodes as one triangle
#: beside a pinch of a cylinder's face). A needle at a cusp is not flat: its small angle is forced.
FLAT_RAD = 1e-8


def flat_triangles(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Which triangles (m,) are flat (:data:`FLAT_RAD`), two of their nodes at one point included.

    >>> flat_triangles(np.array([[0., 0, 0], [1, 0, 0], [2, 0, 0], [1, 1e-3, 0]]), np.array([[0, 1, 2], [0, 2, 3]]))
    array([ True, False])
    """
    p = np.asarray(nodes, dtype=float)[np.asarray(triangles, dtype=np.int64).reshape(-1, 3)]
    e = [p[:, 1] - p[:, 0], p[:, 2] - p[:, 1], p[:, 0] - p[:, 2]]  # edge k leaves corner k
    c = cross(e[0], e[1])
    twice_area = np.sqrt(np.einsum("ij,ij->i", c, c))
    # 180 degrees less the angle at corner k: arctan2(|a x b|, a . b) of the edges along it
    return np.any([np.arctan2(twice_area, np.einsum("ij,ij->i", e[k], e[k - 1])) <= FLAT_RAD
                   for k in range(3)], axis=0)


def min_angles(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The smallest interior angle (m,) of each triangle in degrees: ``triangle_angles(...).min(axis=1)``,
    compiled (``cadedge/_angles.c``); the face optimiser asks it thousands of times per face."""
    return kernels.min_angles(nodes, triangles)


@dataclass
class SmallAngle:
    """A triangle under :data:`SLIVER_DEG`: its face, its angle, and whether (and why) the B-rep forces it."""

    face: int
    angle: float
    forced: bool
    reason: str


#: Point-segment pairs measured in one block by :func:`strip_widths`.
_PAIRS = 2_000_000


def _line_widths(p: np.ndarray, line: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per point ``p`` (n, 3), its distance to the polyline ``line`` and how far it lies from the
    polyline's far side (``inf`` where nothing is): the distance to the nearest of its parts that lie
    farther along it (the short way round if it is closed) from the point's nearest part than twice their
    distance from the point. A straight or gently curved stretch has no far side; the two sides of a thin
    face bounded by one closed edge (an airfoil's end cap) are each other's."""
    near, fold = np.empty(len(p)), np.full(len(p), np.inf)
    seg = np.linalg.norm(np.diff(line, axis=0), axis=1)
    start = np.concatenate([[0.0], np.cumsum(seg)[:-1]])
    length = float(seg.sum())
    closed = np.linalg.norm(line[0] - line[-1]) <= 1e-9 * max(length, 1e-300)
    step = max(1, _PAIRS // max(len(seg), 1))
    for s in range(0, len(p), step):
        dist, t = segment_feet(p[s:s + step, None, :], line[None, :-1], line[None, 1:])
        near[s:s + step] = dist.min(axis=1)
        if len(line) < 3:
            continue
        along = start[None] + t * seg[None]
        apart = np.abs(along - along[np.arange(len(dist)), np.argmin(dist, axis=1)][:, None])
        if closed:
            apart = np.minimum(apart, length - apart)
        fold[s:s + step] = np.where(apart > 2.0 * dist, dist, np.inf).min(axis=1)
    return near, fold


def strip_widths(points: np.ndarray, polylines: Sequence[np.ndarray]) -> np.ndarray:
    """Per group of ``points`` (s, k, 3; a triangle's corners), how wide a face is where they lie, judged
    from its boundary: the smallest ``w`` such that every point of the group is within ``w`` of two
    different ones of the face's boundary ``polylines`` (its edges' grids), or of a polyline and its far
    side (:func:`_line_widths`); ``inf`` if there is no such ``w``. All groups of a face in one pass
    over its polylines: measured one triangle at a time, cadquery-contrib's lattice (43 323 slivers in
    the mesh delivered under the default timeout) spent 44 s of its report here, 15.7 s now."""
    p = np.asarray(points, dtype=float)
    groups, k = p.shape[:2]
    if not len(polylines) or not groups:
        return np.full(groups, np.inf)
    far, fold = [], []
    for line in polylines:
        near, folded = _line_widths(p.reshape(-1, 3), np.asarray(line, dtype=float))
        far.append(near.reshape(groups, k).max(axis=1))
        fold.append(folded.reshape(groups, k).max(axis=1))
    two = np.sort(np.array(far), axis=0)[1] if len(far) >= 2 else np.full(groups, np.inf)
    return np.minimum(two, np.min(fold, axis=0))


def strip_width(points: np.ndarray, polylines: Sequence[np.ndarray]) -> float:
    """:func:`strip_widths` of one group of ``points`` (k, 3)."""
    return float(strip_widths(np.asarray(points, dtype=float).reshape(1, -1, 3), polylines)[0])


def _on_polyline(a: np.ndarray, b: np.ndarray, polylines: Sequence[np.ndarray]) -> bool:
    """Whether the segment ``a``-``b`` is a segment of one of ``polylines`` (an edge grid's)."""
    tol = 1e-9 * (1.0 + max(np.abs(a).max(), np.abs(b).max()))
    for line in polylines:
        line = np.asarray(line, dtype=float)
        i = np.flatnonzero(np.linalg.norm(line - a, axis=1) <= tol)
        j = np.flatnonzero(np.linalg.norm(line - b, axis=1) <= tol)
        if len(i) and len(j) and np.min(np.abs(i[:, None] - j[None, :])) == 1:
            return True
    return False


def _closing(nodes: np.ndarray, tri: np.ndarray, angles: np.ndarray, apex: int, total: float,
             polylines: Sequence[np.ndarray]) -> tuple[bool, str]:
    """Whether (and why) a face closing round a B-rep vertex inside its mesh (node ``apex``, its triangles'
    angles there summing to ``total`` degrees, under three times :data:`SLIVER_DEG`: a narrow cone's
    apex) forces a small angle on triangle ``tri`` (its ``angles``).

    At least three triangles meet there (two would lie on each other), so one of them has at most a
    third of ``total`` there: a triangle with its small angle at the apex is forced. Near the apex the face
    is a thin tube about ``reach * total / pi`` across (``reach`` the distance from the apex: the tube's
    girth is ``reach * total``): a triangle standing on an edge grid's segment (``polylines``, the seam's
    among them) much longer than that is forced too when no triangle on that segment gets much over
    :data:`WEDGE_BOUND` degrees there, ``atan(2 width / length)`` as for a wedge."""
    corner = np.flatnonzero(tri == apex)
    if len(corner) and angles[corner[0]] < SLIVER_DEG:
        return True, (f"the face closes round a B-rep vertex (a cone's apex) in {total:.2g} degrees: at least 3 "
                      f"triangles meet there, so one has at most {total / 3.0:.2g} degrees there")
    p = nodes[tri]
    for k in range(3):  # its sides that are curve segments
        a, b = p[k], p[(k + 1) % 3]
        length = float(np.linalg.norm(a - b))
        reach = float(np.linalg.norm(0.5 * (a + b) - nodes[apex]))
        width = reach * np.radians(total) / np.pi
        bound = float(np.degrees(np.arctan(2.0 * width / length))) if length > 0 else 90.0
        if bound < WEDGE_BOUND and _on_polyline(a, b, polylines):
            return True, (f"the face closes round a B-rep vertex (a cone's apex) in {total:.2g} degrees and the "
                          f"triangle stands on a {length:.2g} curve segment {reach:.2g} from it, where the face "
                          f"is about {width:.2g} across (no triangle on it gets much over {bound:.2g} degrees)")
    return False, "not forced by the B-rep"


def _off_boundary(p: np.ndarray, length: float, offsets: Sequence[tuple[np.ndarray, float]]) -> str | None:
    """Why a triangle (corners ``p``, longest side ``length``) is forced by an edge off its face's
    boundary (``offsets``: each such edge's grid polyline and how far it lies off), or None."""
    for line, off in offsets:
        if off <= 0.0 or length > OFF_REACH * off or len(line) < 2:
            continue
        dist, _ = segment_feet(p[:, None, :], line[None, :-1], line[None, 1:])
        if dist.min() <= 1e-9 * (1.0 + np.abs(line).max()):
            return (f"a node of it is on an edge that lies {off:.2g} off the face's boundary (its curve on the "
                    f"face), and the triangle is {length:.2g} long (no more than {OFF_REACH:g} times that): it "
                    "spans the gap between the edge and the face")
    return None


def _pinch(p: np.ndarray, polylines: Sequence[np.ndarray]) -> str | None:
    """Why a triangle (corners ``p``) standing on a segment of one of its face's edge grids
    (``polylines``) is forced by its third node, a node of those grids too, lying near that segment; or
    None.

    The third node is ``h`` from the segment's line, its foot inside the segment, ``l1`` and ``l2`` from
    its ends. Any triangle on that side of the segment leaves that node out, so its angle at one end is
    under ``atan(h / l)`` there: none gets over ``atan(h / min(l1, l2))``. A boundary that passes within
    ``h`` of itself: a flight's end vertex 2.3e-6 off the shaft's seam, which is not split there."""
    tol = 1e-9 * (1.0 + float(np.abs(p).max()))
    for k in range(3):
        a, b, c = p[k], p[(k + 1) % 3], p[(k + 2) % 3]
        dist, t = (float(x) for x in segment_feet(c, a, b))
        length = float(np.linalg.norm(b - a))
        nearer = min(t, 1.0 - t) * length
        bound = float(np.degrees(np.arctan(dist / nearer))) if nearer > 0.0 else 90.0
        if (bound < WEDGE_BOUND and _on_polyline(a, b, polylines)
                and any(np.linalg.norm(np.asarray(line, dtype=float) - c, axis=1).min() <= tol for line in polylines)):
            return (f"the face's boundary passes {dist:.2g} from itself there: a node of it lies that far from the "
                    f"{length:.2g} boundary segment the triangle stands on, {nearer:.2g} from its nearer end (no "
                    f"triangle on that segment gets much over {bound:.2g} degrees)")
    return None


def corner_angles(tri: np.ndarray, angles: np.ndarray, node: int, sides: set[tuple[int, int]]) -> list[float]:
    """The angles (degrees) of a face's corners at mesh node ``node``: per fan of the face's triangles ``tri``
    round it (their ``angles``), the sum of their angles there; fans part where a boundary segment
    (``sides``, sorted node pairs) leaves the node. A vertex where a hole's outline touches the face's
    outer one (gmsh's PeriodicFaceWithLargeTolerance.brep: a slot's tangent sides meeting the end circle)
    has a cusp between two wider corners, and their sum hid the cusp's 0 degrees."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    rows, cols = np.nonzero(tri == node)
    if not len(rows):
        return [0.0]
    other = np.column_stack([tri[rows, (cols + 1) % 3], tri[rows, (cols + 2) % 3]]).ravel()
    owner = np.repeat(np.arange(len(rows)), 2)
    inner = np.array([(min(node, int(o)), max(node, int(o))) not in sides for o in other.tolist()], dtype=bool)
    other, owner = other[inner], owner[inner]
    order = np.argsort(other, kind="stable")
    other, owner = other[order], owner[order]
    same = other[1:] == other[:-1]  # two triangles round the node sharing an inner edge: one corner
    graph = coo_matrix((np.ones(int(same.sum())), (owner[:-1][same], owner[1:][same])), shape=(len(rows),) * 2)
    _, fan = connected_components(graph, directed=False)
    return np.bincount(fan, weights=angles[rows, cols]).tolist()


def small_angles(nodes: np.ndarray, triangles: np.ndarray, triangle_faces: np.ndarray,
                 vertex_points: np.ndarray, angles: np.ndarray | None = None, *,
                 face_edges: Mapping[int, Sequence[np.ndarray]] | None = None,
                 offsets: Mapping[int, Sequence[tuple[np.ndarray, float]]] | None = None,
                 tangles: Mapping[int, Sequence[tuple[Sequence[float], float]]] | None = None) -> list[SmallAngle]:
    """Every triangle under :data:`SLIVER_DEG`, worst first.

    Forced: its face narrows to a corner sharper than :data:`SLIVER_DEG` at a B-rep vertex (a node at one
    of ``vertex_points`` where the sum of that face's triangle angles is that small), and either the
    triangle stands on the face's boundary only (all three nodes on it: it spans the two sides of the
    wedge, which no node placement inside the face can avoid), or it stands on a boundary segment inside
    that wedge where the face is so narrow that no triangle on that segment gets much over
    :data:`WEDGE_BOUND` degrees (``atan(2 width / length)``, the width over the segment's middle; the
    segments are the edge grids', which stay).

    Also forced: the triangle lies in a strip of its face between two of its boundary edges, or two sides
    of one (``face_edges``: face id -> its edges' grid polylines), so narrow (:func:`strip_widths`) that no
    triangle as long as it gets much over :data:`WEDGE_BOUND` degrees there. Two edges that coincide in
    space make a strip of no width: a shaft's seam line with the end of a helical flight fused onto it.

    Also forced: the triangle stands on a segment of the face's edge grids (``face_edges``), and its third
    node, on those grids too, lies so near that segment (:func:`_pinch`) that no triangle on it gets much over
    :data:`WEDGE_BOUND` degrees.

    Also forced: near a B-rep vertex inside the face's mesh round which its triangles' angles sum to under
    three times :data:`SLIVER_DEG` (a narrow cone's apex; :func:`_closing`), a triangle with its small
    angle there, or standing on a curve segment much longer than the face is across there.

    Also forced: a node of the triangle is on an edge that lies off the face's boundary by ``d``
    (``offsets``: face id -> (the edge's grid polyline, ``d``) for such edges, measured by
    :func:`cadedge.occt.offsets.edge_offsets`), and the triangle is at most :data:`OFF_REACH` times
    ``d`` long.

    Also forced: the triangle lies where its face's boundary crosses itself (``tangles``: face -> balls
    (centre, radius) round such places, :func:`cadedge.mesh.parametric.tangle_zones`): its edges cross
    within their tolerance, and the triangles between them fold or are squeezed.
    """
    tris = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    ang = triangle_angles(nodes, tris) if angles is None else angles
    low = np.flatnonzero(ang.min(axis=1) < SLIVER_DEG)
    if not len(low):
        return []
    faces = np.asarray(triangle_faces, dtype=np.int64)
    nodes = np.asarray(nodes, dtype=float)
    from scipy.spatial import cKDTree

    vpts = np.asarray(vertex_points, dtype=float).reshape(-1, 3)
    wedges: dict[int, tuple[float, set[int], set[tuple[int, int]], np.ndarray | None]] = {}
    apexes: dict[int, tuple[int, float]] = {}  # face -> its narrowest closing vertex's node and total angle
    # each face's triangles, and the B-rep vertices in a k-d tree: a face at a time, every node against every
    # vertex, took 4 minutes of the report on a lattice of 15 000 vertices and 2 000 faces with slivers
    order = np.argsort(faces, kind="stable")
    ordered = faces[order]
    tree = cKDTree(vpts) if len(vpts) else None
    low_order = low[np.argsort(faces[low], kind="stable")]  # the slivers grouped by face
    low_faces = faces[low_order]
    strip = np.full(len(tris), np.inf)  # the strip width at each sliver of a face with grids given
    for f in np.unique(faces[low]).tolist():
        lo, hi = np.searchsorted(ordered, [f, f + 1])
        mine = order[lo:hi]
        lo, hi = np.searchsorted(low_faces, [f, f + 1])
        slivers = low_order[lo:hi]
        if face_edges and f in face_edges:
            strip[slivers] = strip_widths(nodes[tris[slivers]], face_edges[f])
        ftri, fang = tris[mine], ang[mine]
        edges = np.sort(np.concatenate([ftri[:, [0, 1]], ftri[:, [1, 2]], ftri[:, [2, 0]]]), axis=1)
        uniq, counts = np.unique(edges, axis=0, return_counts=True)
        boundary = set(np.unique(uniq[counts == 1]).tolist())
        sides = {(int(a), int(b)) for a, b in uniq[counts == 1]}
        sharpest, corner = 180.0, None
        inner = set(np.unique(tris[slivers]).tolist()) - boundary  # an apex is a slivers' node
        candidates = list(boundary | inner) if tree is not None else []
        at_vertex = (tree.query(nodes[candidates])[0] <= 1e-9 * (1.0 + np.abs(nodes[candidates]).max(axis=1))
                     if candidates else [])
        for node, hit in zip(candidates, at_vertex):
            if hit:
                total = min(corner_angles(ftri, fang, node, sides))
                if node in inner:
                    if total < apexes.get(f, (0, 3.0 * SLIVER_DEG))[1]:
                        apexes[f] = (node, total)
                elif total < sharpest:
                    sharpest, corner = total, nodes[node]
        wedges[f] = (sharpest, boundary, sides, corner)
    out = []
    for t in low[np.argsort(ang[low].min(axis=1))]:
        f = int(faces[t])
        sharpest, boundary, sides, corner = wedges[f]
        forced = sharpest < SLIVER_DEG and all(int(n) in boundary for n in tris[t])
        reason = (f"the face narrows to a {sharpest:.2g}-degree corner at a B-rep vertex and the triangle spans "
                  "its two sides" if forced else "not forced by the B-rep")
        if not forced and sharpest < SLIVER_DEG:
            p = nodes[tris[t]]
            k = int(np.argmax(np.linalg.norm(p - np.roll(p, -1, axis=0), axis=1)))  # longest edge: k -> k+1
            a, b = int(tris[t, k]), int(tris[t, (k + 1) % 3])
            if (min(a, b), max(a, b)) in sides:  # a boundary segment
                length = float(np.linalg.norm(nodes[a] - nodes[b]))
                reach = float(np.linalg.norm(0.5 * (nodes[a] + nodes[b]) - corner))
                width = 2.0 * reach * np.tan(np.radians(sharpest) / 2.0)  # the wedge's width over its middle
                bound = float(np.degrees(np.arctan(2.0 * width / length)))
                if bound < WEDGE_BOUND:
                    forced = True
                    reason = (f"the face narrows to a {sharpest:.2g}-degree corner at a B-rep vertex and the "
                              f"triangle stands on a {length:.2g} boundary segment in its wedge, about "
                              f"{width:.2g} wide there (no triangle on it gets much over {bound:.2g} degrees)")
        if not forced and f in apexes:
            forced, reason = _closing(nodes, tris[t], ang[t], *apexes[f], (face_edges or {}).get(f, ()))
        if not forced and face_edges and f in face_edges:
            p = nodes[tris[t]]
            length = float(np.linalg.norm(p - np.roll(p, -1, axis=0), axis=1).max())
            bound = float(np.degrees(np.arctan(2.0 * strip[t] / length))) if length > 0 else 0.0
            if bound < WEDGE_BOUND:
                forced = True
                reason = (f"the face is about {strip[t]:.2g} wide there, between two sides of its boundary, and "
                          f"the triangle is {length:.2g} long (no triangle that long gets much over "
                          f"{bound:.2g} degrees there)")
        if not forced and face_edges and f in face_edges:
            why = _pinch(nodes[tris[t]], face_edges[f])
            if why is not None:
                forced, reason = True, why
        if not forced and offsets and f in offsets:
            p = nodes[tris[t]]
            why = _off_boundary(p, float(np.linalg.norm(p - np.roll(p, -1, axis=0), axis=1).max()), offsets[f])
            if why is not None:
                forced, reason = True, why
        if not forced and tangles and f in tangles:
            p = nodes[tris[t]]
            if any(np.linalg.norm(p - np.asarray(c, dtype=float), axis=1).max() <= r for c, r in tangles[f]):
                forced, reason = True, ("the face's boundary crosses itself there (its edges cross within their "
                                        "tolerance): the triangles between them fold or are squeezed")
        out.append(SmallAngle(face=f, angle=float(ang[t].min()), forced=forced, reason=reason))
    return out
