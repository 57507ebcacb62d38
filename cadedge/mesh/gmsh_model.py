"""Load a B-rep into gmsh and map gmsh's entity tags to cadedge's vertex, edge and face ids.

The shape travels as an OCCT ``.brep`` file rather than a native pointer: gmsh links its own copy of
OpenCASCADE, and handing a ``TopoDS_Shape`` from OCP's build to gmsh's is not ABI-safe. The BREP text
keeps the topology (shared vertices and edges, seams, degenerate edges, locations) exactly, and gmsh
binds its entities in ``TopExp::MapShapes`` order, which is the order of cadedge's ids. That identity is
verified edge by edge (gmsh's curve evaluated at our parameters must land on our points); edges that
fail it are matched by geometry instead (end points, then every grid point projected onto the curve),
which also handles reversed parametrisations. Edges and vertices that match nothing are listed, never
raised: only the faces around them are meshed differently (on gmsh's own curve mesh).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from dataclasses import dataclass, field
from typing import Iterator

import gmsh
import numpy as np

from ..errors import GeometryError, MeshError
from ..shapegrid import ShapeGrid
from .coincident import point_tags


@contextlib.contextmanager
def gmsh_session() -> Iterator[None]:
    """Initialise gmsh quietly with its logger on; always finalise. gmsh is a process-wide singleton. The
    folds of an earlier session's surfaces (:data:`cadedge.mesh.creases.CREASES`) and its surface target
    (:data:`cadedge.mesh.interior.SIZES`) are forgotten."""
    from .creases import CREASES
    from .interior import SIZES

    if gmsh.isInitialized():
        raise MeshError("gmsh is already initialised in this process; cadedge meshes one model at a time")
    CREASES.clear()
    SIZES.target = None
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.logger.start()
        yield
    finally:
        gmsh.finalize()


#: Import settings tried in turn: none of gmsh's healing first (the B-rep exactly as cadedge refined it),
#: then gmsh's automatic wire fixing (some files only import with it; edges it changes are then matched
#: by geometry or meshed by gmsh itself).
IMPORT_ATTEMPTS = ({"Geometry.OCCAutoFix": 0}, {"Geometry.OCCAutoFix": 1})


def import_brep(path: str, *, attempt: int = 0, partial: bool = False) -> str | None:
    """Put the BREP file at ``path`` into the current gmsh model without healing, sewing or fragmenting.

    ``attempt`` indexes :data:`IMPORT_ATTEMPTS`. Raises :class:`GeometryError` with gmsh's reason; with
    ``partial``, a model gmsh bound only in part (it stops at the first surface whose wire it cannot fix,
    "Could not fix wire in surface N", keeping the entities bound before) is kept when it has surfaces,
    and gmsh's reason is returned (None when the import was clean).
    """
    for opt in ("Geometry.OCCFixDegenerated", "Geometry.OCCFixSmallEdges", "Geometry.OCCFixSmallFaces",
                "Geometry.OCCSewFaces", "Geometry.OCCMakeSolids"):
        gmsh.option.setNumber(opt, 0)
    for opt, value in IMPORT_ATTEMPTS[attempt].items():
        gmsh.option.setNumber(opt, value)
    gmsh.option.setNumber("Geometry.OCCScaling", 1)
    gmsh.option.setNumber("Geometry.OCCImportLabels", 0)
    try:
        gmsh.model.occ.importShapes(path, highestDimOnly=False)
        gmsh.model.occ.synchronize()
    except Exception as exc:  # gmsh raises a bare Exception carrying its last error
        if partial:
            with contextlib.suppress(Exception):  # binds what it can, raising again on the same surface
                gmsh.model.occ.synchronize()
            if gmsh.model.getEntities(2):
                return str(exc)
        raise GeometryError(f"gmsh could not import the shape: {exc}") from exc
    return None


def shape_to_brep(shape: object) -> bytes:
    """The OCCT shape as BREP text (the form in which it crosses to gmsh and to a child process)."""
    from OCP.BRepTools import BRepTools

    with tempfile.TemporaryDirectory(prefix="cadedge-brep-") as tmp:
        path = os.path.join(tmp, "shape.brep")
        if not BRepTools.Write_s(shape, path):
            raise GeometryError("OCCT could not write the shape as BREP for gmsh")
        with open(path, "rb") as f:
            return f.read()


@dataclass
class CurveMatch:
    """gmsh curve ``tag`` for one cadedge edge; ``params`` are gmsh parameters of the edge's grid points."""

    tag: int
    params: np.ndarray
    by_order: bool


@dataclass
class EntityMap:
    """cadedge id -> gmsh tag for vertices, non-degenerate edges and faces (plus the reverse for faces)."""

    vertices: dict[int, int]
    edges: dict[int, CurveMatch]
    faces: dict[int, int]
    #: degenerate edge id -> the gmsh curve (a point) carrying it
    degenerate_curves: dict[int, int] = field(default_factory=dict)
    unmatched_curves: list[int] = field(default_factory=list)
    #: cadedge edges no gmsh curve carries within tolerance: gmsh meshes the curves of their faces itself
    unmatched_edges: list[int] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def face_of_surface(self) -> dict[int, int]:
        return {s: f for f, s in self.faces.items()}


def model_tolerance(grid: ShapeGrid) -> float:
    """Distance under which two points count as the same: relative to the model size and edge tolerances."""
    pts = [e.points for e in grid.edges if len(e.points)] + [np.atleast_2d(v.point) for v in grid.vertices]
    allp = np.vstack(pts) if pts else np.zeros((1, 3))
    diag = float(np.linalg.norm(allp.max(axis=0) - allp.min(axis=0))) or 1.0
    tol = max([e.tolerance for e in grid.edges] + [v.tolerance for v in grid.vertices] + [0.0])
    return max(1e-7 * diag, 2.0 * tol)


def _curve_values(tag: int, params: np.ndarray) -> np.ndarray:
    return np.asarray(gmsh.model.getValue(1, tag, params.tolist()), dtype=float).reshape(-1, 3)


def _within_range(tag: int, params: np.ndarray) -> bool:
    """Whether ``params`` lie in gmsh curve ``tag``'s parameter range. gmsh evaluates a line (or any
    curve it can extend) beyond its range: in gmsh's ellipses.brep, bound in another order, the line that
    was edge 47's id is one piece of edge 47's own line, and edge 47's parameters put its points exactly
    on it; taken for edge 47, it left edge 87 no curve, and two faces were dropped."""
    lo, hi = (float(x[0]) for x in gmsh.model.getParametrizationBounds(1, tag))
    slack = 1e-9 * max(1.0, abs(lo), abs(hi))
    return bool(lo - slack <= np.min(params) and np.max(params) <= hi + slack)


def _match_vertices(grid: ShapeGrid, tol: float, notes: list[str], expected: dict[int, int]) -> dict[int, int]:
    """Vertex id -> gmsh point: the ``expected`` tag where it lies there, else the nearest within ``tol``."""
    from scipy.spatial import cKDTree

    tags = [t for _, t in gmsh.model.getEntities(0)]
    coords = np.array([gmsh.model.getValue(0, t, []) for t in tags], dtype=float).reshape(-1, 3)
    out: dict[int, int] = {}
    tree = cKDTree(coords) if len(coords) else None
    for v in grid.vertices:
        p = np.asarray(v.point, dtype=float)
        k = expected[v.id]
        if k <= len(tags) and np.linalg.norm(coords[k - 1] - p) <= tol:
            out[v.id] = tags[k - 1]
            continue
        d, i = tree.query(p) if tree is not None else (np.inf, 0)
        if d > tol:  # its edges cannot carry imposed nodes: gmsh meshes them itself
            notes.append(f"vertex {v.id} at {p.tolist()} has no gmsh point within {tol:.3g}")
            continue
        out[v.id] = tags[int(i)]
        notes.append(f"vertex {v.id} matched to gmsh point {tags[int(i)]} by position")
    return out


def _at_point(tag: int, point: np.ndarray, tol: float) -> bool:
    """Whether gmsh curve ``tag`` stays within ``tol`` of ``point`` (a degenerate edge's curve). A
    degenerate edge was given the curve of its own id unchecked; where gmsh's order differs from
    MapShapes' it took a real curve: gmsh's benchmark simple_plane.brep (non-manifold edges shared by up
    to six faces) lost 7 of its edges' grids that way, gmsh meshing their curves itself."""
    try:
        lo, hi = (float(x[0]) for x in gmsh.model.getParametrizationBounds(1, tag))
        values = _curve_values(tag, np.linspace(lo, hi, 5))
    except Exception:  # gmsh raises on curves it cannot evaluate
        return False
    return bool(np.max(np.linalg.norm(values - np.asarray(point, dtype=float), axis=1)) <= tol)


def _curve_ends(tags: list[int]) -> dict[int, tuple[float, float, np.ndarray]]:
    """gmsh curve tag -> its parameter range and its two end points (2, 3); curves gmsh cannot evaluate
    are left out."""
    out = {}
    for tag in tags:
        try:
            lo, hi = (float(x[0]) for x in gmsh.model.getParametrizationBounds(1, tag))
            out[tag] = (lo, hi, _curve_values(tag, np.array([lo, hi])))
        except Exception:  # gmsh raises on curves it cannot evaluate
            continue
    return out


def _end_tree(tags: list[int], ends_of: dict[int, tuple[float, float, np.ndarray]]):
    """A k-d tree of the curves' end points, two per curve of ``tags`` in order (None for no curve)."""
    from scipy.spatial import cKDTree

    return cKDTree(np.vstack([ends_of[t][2] for t in tags])) if tags else None


def _match_by_geometry(edge, candidates: list[int], tol: float,
                       ends_of: dict[int, tuple[float, float, np.ndarray]]) -> CurveMatch | None:
    """Find the gmsh curve carrying every grid point of ``edge`` among ``candidates`` (their ranges and end
    points in ``ends_of``, :func:`_curve_ends`); parameters come from projection."""
    p0, p1 = edge.points[0], edge.points[-1]
    for tag in candidates:
        lo, hi, ends = ends_of[tag]
        same = np.linalg.norm(ends[0] - p0) <= tol and np.linalg.norm(ends[1] - p1) <= tol
        flip = np.linalg.norm(ends[0] - p1) <= tol and np.linalg.norm(ends[1] - p0) <= tol
        if not (same or flip):
            continue
        params = np.asarray(gmsh.model.getParametrization(1, tag, edge.points.ravel().tolist()), dtype=float)
        if same and flip:  # a closed curve: the interior points tell the direction
            same = len(params) < 3 or params[1] <= params[-2]
        params[0], params[-1] = (lo, hi) if same else (hi, lo)
        if not (np.all(np.diff(params) > 0) or np.all(np.diff(params) < 0)):
            continue
        if np.max(np.linalg.norm(_curve_values(tag, params) - edge.points, axis=1)) <= tol:
            return CurveMatch(tag=tag, params=params, by_order=False)
    return None


def map_entities(grid: ShapeGrid, *, coincident: dict[int, int] | None = None) -> EntityMap:
    """Map every cadedge vertex, edge and face of ``grid`` onto the gmsh model loaded from ``grid.shape``,
    or from it with the ``coincident`` vertices merged (:mod:`cadedge.mesh.coincident`): those map to
    the point of the vertex they were merged into."""
    tol = model_tolerance(grid)
    notes: list[str] = []
    expected = point_tags(grid, coincident or {})
    vertices = _match_vertices(grid, tol, notes, expected)
    curve_tags = [t for _, t in gmsh.model.getEntities(1)]
    by_tag = set(curve_tags)
    edges: dict[int, CurveMatch] = {}
    pending = []
    degenerate_curves: dict[int, int] = {}
    for e in (e for e in grid.edges if e.degenerate):
        if e.id in by_tag and _at_point(e.id, e.points[0], tol):
            degenerate_curves[e.id] = e.id
    for e in grid.edges:
        if e.degenerate:
            continue
        if e.id in by_tag:
            try:
                ok = _within_range(e.id, e.params) and bool(
                    np.max(np.linalg.norm(_curve_values(e.id, e.params) - e.points, axis=1)) <= tol)
            except Exception:  # gmsh raises on a curve it cannot evaluate
                ok = False
            if ok:
                edges[e.id] = CurveMatch(tag=e.id, params=np.asarray(e.params, dtype=float), by_order=True)
                continue
        pending.append(e)
    taken = {m.tag for m in edges.values()} | set(degenerate_curves.values())
    for e in (e for e in grid.edges if e.degenerate and e.id not in degenerate_curves):
        tag = next((t for t in curve_tags if t not in taken and _at_point(t, e.points[0], tol)), None)
        if tag is not None:
            degenerate_curves[e.id] = tag
            taken.add(tag)
            notes.append(f"degenerate edge {e.id} matched to gmsh curve {tag} by geometry")
    unmatched_edges = []
    surfaces_of = {t: {int(s) for s in gmsh.model.getAdjacencies(1, t)[0]} for t in curve_tags} if pending else {}
    # the curves with an end near an edge's first point, found in a k-d tree of every curve's ends: the
    # Koch leader arm (an assembly of 12 104 edges, gmsh's order not MapShapes') sorted every curve for
    # every edge, 23 s in each gmsh process
    ends_of = _curve_ends(curve_tags) if pending else {}
    end_tags = [t for t in curve_tags if t in ends_of]
    order = {t: k for k, t in enumerate(curve_tags)}
    tree = _end_tree(end_tags, ends_of)
    for e in pending:
        faces = set(e.faces)
        near = {end_tags[k // 2] for k in tree.query_ball_point(e.points[0], 1.001 * tol)} if tree else set()
        # coinciding curves (a free curve drawn along a face's edge, unsewn faces): the one bounding the
        # same faces first, then one bounding as many
        candidates = sorted(near - taken, key=lambda t: (surfaces_of[t] != faces,
                                                         len(surfaces_of[t]) != len(faces), order[t]))
        try:
            m = _match_by_geometry(e, candidates, tol, ends_of)
        except Exception:  # gmsh raises on curves it cannot evaluate or project onto
            m = None
        if m is None:
            unmatched_edges.append(e.id)
            continue
        edges[e.id] = m
        taken.add(m.tag)
        notes.append(f"edge {e.id} matched to gmsh curve {m.tag} by geometry")
    unmatched = [t for t in curve_tags if t not in taken]
    if pending or any(tag != expected[v] for v, tag in vertices.items()):  # else gmsh's order held throughout
        _vertices_from_edges(grid, edges, vertices, tol, notes)
    faces = _match_faces(grid, edges)
    return EntityMap(vertices=vertices, edges=edges, faces=faces, degenerate_curves=degenerate_curves,
                     unmatched_curves=unmatched, unmatched_edges=unmatched_edges, notes=notes)


def _vertices_from_edges(grid: ShapeGrid, edges: dict[int, CurveMatch], vertices: dict[int, int], tol: float,
                         notes: list[str]) -> None:
    """Correct ``vertices`` (id -> gmsh point, matched by order or position) by the matched ``edges``: a
    vertex is the gmsh point at the same end of its edge's curve. Coinciding vertices (unsewn faces, a
    free curve ending on a face's corner) are told apart only this way: matched by position, the four
    corners of splinecage's unsewn faces went to one point each and no face's boundary closed. A vertex
    whose edges name different points keeps its match."""
    implied: dict[int, set[int]] = {}
    for e in grid.edges:
        m = edges.get(e.id)
        if m is None or len(m.params) < 2:
            continue
        ends = [abs(t) for _, t in gmsh.model.getBoundary([(1, m.tag)], combined=False, oriented=False)]
        if len(ends) != 2:
            continue  # a closed curve: its one point is found by position
        first, last = (ends[0], ends[1]) if m.params[0] < m.params[-1] else (ends[1], ends[0])
        for v, tag, p in ((e.vertices[0], first, e.points[0]), (e.vertices[1], last, e.points[-1])):
            if np.linalg.norm(np.asarray(gmsh.model.getValue(0, tag, []), dtype=float) - p) <= tol:
                implied.setdefault(v, set()).add(tag)
    for v, tags in sorted(implied.items()):
        if len(tags) == 1 and vertices.get(v) != (tag := next(iter(tags))):
            vertices[v] = tag
            notes.append(f"vertex {v} matched to gmsh point {tag} through its edges")


def _match_faces(grid: ShapeGrid, edges: dict[int, CurveMatch]) -> dict[int, int]:
    """Face ids are MapShapes order like gmsh's surface tags; confirm through edge adjacency, else match on it."""
    surf_tags = [t for _, t in gmsh.model.getEntities(2)]
    ours: dict[int, set[int]] = {}
    for e in grid.edges:
        if e.id in edges:
            for f in e.faces:
                ours.setdefault(f, set()).add(e.id)
    curve_to_edge = {m.tag: eid for eid, m in edges.items()}
    theirs: dict[int, set[int]] = {}
    for s in surf_tags:
        bnd = gmsh.model.getBoundary([(2, s)], combined=False, oriented=False)
        theirs[s] = {curve_to_edge[abs(t)] for _, t in bnd if abs(t) in curve_to_edge}
    n_faces = grid.faces or len(surf_tags)
    if n_faces == len(surf_tags) and all(theirs[s] == ours.get(s, set()) for s in surf_tags):
        return {s: s for s in surf_tags}
    out: dict[int, int] = {}
    free = dict(theirs)
    for f in sorted(ours):
        hits = [s for s, es in free.items() if es == ours[f]]
        if hits:
            out[f] = hits[0]
            del free[hits[0]]
    left = [f for f in range(1, n_faces + 1) if f not in out]
    if left and free:
        out.update(_nearest_surfaces(grid, left, free, ours))
    for f in left:  # nothing to place it by (no edge grid): gmsh's order, if that surface is still free
        if f not in out and f in free and f not in out.values():
            out[f] = f
    return out


def _nearest_surfaces(grid: ShapeGrid, faces: list[int], free: dict[int, set[int]],
                      ours: dict[int, set[int]]) -> dict[int, int]:
    """The ``faces`` whose edges matched no surface's exactly, each given one of the ``free`` surfaces (tag
    -> its matched edges): the one sharing the most of its edges, then the one whose bounding box is
    centred nearest its edge grids' (a face bounded only by degenerate edges shares none). Before, such a
    face kept gmsh's surface of its own id, and lost it when an edge match had given that surface to
    another face: gmsh's benchmark ellipses.brep, 14 edges no gmsh curve carries, had faces 21 and 22
    left with no surface, their triangles labelled as faces 26 and 27 and left out of the ``.msh``."""
    points: dict[int, list[np.ndarray]] = {}
    for e in grid.edges:
        for f in set(e.faces) & set(faces):
            if len(e.points):
                points.setdefault(f, []).append(np.asarray(e.points, dtype=float).reshape(-1, 3))
    centre = {f: 0.5 * (np.vstack(p).min(axis=0) + np.vstack(p).max(axis=0)) for f, p in points.items()}
    boxes = {s: np.asarray(gmsh.model.getBoundingBox(2, s), dtype=float) for s in free}
    pairs = []
    for f in faces:
        for s, edges in free.items():
            middle = 0.5 * (boxes[s][:3] + boxes[s][3:])
            far = float(np.linalg.norm(middle - centre[f])) if f in centre else np.inf
            pairs.append((-len(edges & ours.get(f, set())), far, f, s))
    out: dict[int, int] = {}
    for _, far, f, s in sorted(pairs):
        if f not in out and s not in out.values() and np.isfinite(far):
            out[f] = s
    return out


def boundary_uses(surface: int) -> list[tuple[int, int]]:
    """The curves bounding ``surface`` in gmsh's order, once per use, each with its use's number (0, or 1
    for a seam's second side: gmsh's ``which`` for the curve's parametrisation on the face)."""
    seen: dict[int, int] = {}
    out = []
    for _, t in gmsh.model.getBoundary([(2, surface)], combined=False, oriented=False):
        out.append((abs(t), seen.get(abs(t), 0)))
        seen[abs(t)] = out[-1][1] + 1
    return out


def surface_curve_uses(surface: int) -> dict[int, int]:
    """How many times each curve bounds ``surface`` (a seam bounds its face twice)."""
    uses: dict[int, int] = {}
    for curve, k in boundary_uses(surface):
        uses[curve] = k + 1
    return uses
