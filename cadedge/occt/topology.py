"""The B-rep topology of a shape as plain lists, in ``TopExp::MapShapes`` order (id = index + 1).

Works for solids, multi-solid compounds, open shells and loose wires/edges (no faces). ``MapShapes``
lists a seam edge (used twice by one face, once per orientation) once; it is flagged by
:meth:`Topology.is_seam`. Degenerate edges (a cone apex, a sphere pole) are listed and flagged.
"""

from __future__ import annotations

import functools

from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.BRepTools import BRepTools_WireExplorer
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_FORWARD, TopAbs_VERTEX, TopAbs_WIRE
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS_Edge, TopoDS_Face, TopoDS_Shape, TopoDS_Vertex

from ..errors import GeometryError
from .compat import (OCCT_ERRORS, TopoDS, TopTools_IndexedDataMapOfShapeListOfShape,
                     TopTools_IndexedMapOfShape, TopTools_ListOfShape)

#: The curve type names reported for edges, from ``GeomAbs_CurveType`` without the prefix.
CURVE_TYPES = ("Line", "Circle", "Ellipse", "Hyperbola", "Parabola", "BezierCurve", "BSplineCurve",
               "OffsetCurve", "OtherCurve")


def forward(edge: TopoDS_Edge) -> TopoDS_Edge:
    """The edge in FORWARD orientation: parameters run from its first vertex to its last."""
    return TopoDS.Edge_s(edge.Oriented(TopAbs_FORWARD))


@functools.cache
def curve_type_name(kind) -> str:
    """The name in :data:`CURVE_TYPES` of a ``GeomAbs_CurveType`` (cached: ``str`` of an OCP enum
    costs about 14 us)."""
    return str(kind).rsplit(".", 1)[-1].removeprefix("GeomAbs_")


def orientations_in(face: TopoDS_Face, edge: TopoDS_Edge) -> list:
    """The orientations in which ``face`` holds ``edge`` (a seam's two; none if it does not hold it)."""
    found = []
    explorer = TopExp_Explorer(face, TopAbs_EDGE)
    while explorer.More():
        if explorer.Current().IsSame(edge) and explorer.Current().Orientation() not in found:
            found.append(explorer.Current().Orientation())
        explorer.Next()
    return found


def walked_wires(face: TopoDS_Face) -> list[list[TopoDS_Edge]] | None:
    """Each wire of ``face`` as its edges in walking order (``BRepTools_WireExplorer``), oriented as the face
    uses them; None if a walk skips an edge (its loop would not be the wire)."""
    loops = []
    wires = TopExp_Explorer(face, TopAbs_WIRE)
    while wires.More():
        wire = TopoDS.Wire_s(wires.Current())
        wires.Next()
        count, edges = 0, TopExp_Explorer(wire, TopAbs_EDGE)
        while edges.More():
            count += 1
            edges.Next()
        loop, walk = [], BRepTools_WireExplorer(wire, face)
        while walk.More():
            loop.append(walk.Current())
            walk.Next()
        if len(loop) != count:
            return None
        loops.append(loop)
    return loops


def list_items(shapes: TopTools_ListOfShape) -> list[TopoDS_Shape]:
    """The items of an OCCT list. Iterating the list itself from Python costs about 0.1 ms per list
    (measured on 917_fusee: 0.15 s of 0.16 s for the whole topology), so the one or two items of almost
    every edge's face list are taken as its first and last, and a longer list is popped from a copy."""
    size = shapes.Size()
    if size <= 2:
        return [] if size == 0 else [shapes.First()] if size == 1 else [shapes.First(), shapes.Last()]
    rest = TopTools_ListOfShape()
    rest.Assign(shapes)
    out = []
    while not rest.IsEmpty():
        out.append(rest.First())
        rest.RemoveFirst()
    return out


def indexed(shape: TopoDS_Shape, kind) -> TopTools_IndexedMapOfShape:
    """The sub-shapes of ``shape`` of type ``kind`` (a ``TopAbs`` value) in ``MapShapes`` order: the ids
    cadedge gives vertices, edges and faces (1-based)."""
    m = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, kind, m)
    return m


class Topology:
    """Edges, vertices and faces of ``shape`` with edge -> faces and edge -> vertices adjacency.

    ``edges``, ``vertices`` and ``faces`` are lists in ``MapShapes`` order (edges in their FORWARD
    orientation); ``edge_faces[i]`` lists the face ids bounding edge ``i + 1``; ``edge_vertices[i]``
    is (first, last) vertex id in that edge's parameter direction. Methods take 0-based indices.
    """

    def __init__(self, shape: TopoDS_Shape, *, dump: bool = True):
        if shape is None or shape.IsNull():
            raise GeometryError("null shape: nothing to take the topology of")
        self.shape = shape
        self._seam: list[bool] | None = None  # computed on first use: refining does not need it
        #: The shape read in one call (:mod:`cadedge.occt.shapedump`, which needs numpy: ``dump=False`` walks
        #: it through OCP, as for the shapes the dump does not take), or None where it was walked.
        self.dump = None
        if dump:
            from . import shapedump
            self.dump = shapedump.read(shape)
        if self.dump is None:
            self._walk(shape)
            return
        d = self.dump
        self.edges, self.vertices, self.faces = d.edges, d.vertices, d.faces
        self.edge_faces: list[list[int]] = d.edge_faces
        missing = (d.edge_vertices == 0).any(axis=1).nonzero()[0]
        if len(missing):
            raise GeometryError(f"edge {missing[0] + 1} has no vertex at one end; cannot anchor its grid")
        self.edge_vertices: list[tuple[int, int]] = list(map(tuple, d.edge_vertices.tolist()))
        self._degenerate = d.degenerate.tolist()

    def _walk(self, shape: TopoDS_Shape) -> None:
        """The topology through OCP calls (about 10 per edge), for the shapes the dump does not take."""
        vmap, fmap = (indexed(shape, k) for k in (TopAbs_VERTEX, TopAbs_FACE))
        ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
        TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, ancestors)
        # The map holds every edge; with none outside a face its keys come in MapShapes order (both walk
        # the faces depth first), so it serves as the edge map and its lists are found by index.
        if TopExp_Explorer(shape, TopAbs_EDGE, TopAbs_FACE).More():
            emap = indexed(shape, TopAbs_EDGE)
            key, faces_of = emap.FindKey, lambda i, edge: ancestors.FindFromKey(edge)
        else:
            key, faces_of = ancestors.FindKey, lambda i, edge: ancestors.FindFromIndex(i)
        face_id, vertex_id, ends = fmap.FindIndex, vmap.FindIndex, TopExp.Vertices_s
        self.edges: list[TopoDS_Edge] = []
        self.vertices: list[TopoDS_Vertex] = [TopoDS.Vertex_s(vmap.FindKey(i)) for i in range(1, vmap.Extent() + 1)]
        self.faces: list[TopoDS_Face] = [TopoDS.Face_s(fmap.FindKey(i)) for i in range(1, fmap.Extent() + 1)]
        self.edge_faces: list[list[int]] = []
        self.edge_vertices: list[tuple[int, int]] = []
        self._degenerate: list[bool] | None = None
        first, last = TopoDS_Vertex(), TopoDS_Vertex()  # filled by TopExp::Vertices for each edge
        for i in range(1, ancestors.Extent() + 1):
            edge = forward(key(i))
            self.edges.append(edge)
            ids: list[int] = []
            for face in list_items(faces_of(i, edge)):
                fid = face_id(face)
                if fid not in ids:
                    ids.append(fid)
            self.edge_faces.append(ids)
            ends(edge, first, last)
            v1, v2 = vertex_id(first), vertex_id(last)
            if not v1 or not v2:  # a null vertex is in no map
                raise GeometryError(f"edge {i} has no vertex at one end; cannot anchor its grid")
            self.edge_vertices.append((v1, v2))

    def vertex_points(self) -> "np.ndarray":
        """The vertices' points (n, 3), as ``BRep_Tool::Pnt`` gives them."""
        if self.dump is not None:
            return self.dump.vertex_points
        import numpy as np

        return np.array([BRep_Tool.Pnt_s(v).Coord() for v in self.vertices], dtype=float).reshape(-1, 3)

    def tolerances(self) -> tuple[list[float], list[float]]:
        """The edges' and the vertices' tolerances (``BRep_Tool::Tolerance``)."""
        if self.dump is not None:
            return self.dump.edge_tolerance.tolist(), self.dump.vertex_tolerance.tolist()
        return ([BRep_Tool.Tolerance_s(e) for e in self.edges], [BRep_Tool.Tolerance_s(v) for v in self.vertices])

    def curve_type(self, i: int) -> str:
        """OCCT's curve type name of edge ``i`` (0-based), e.g. "Line", "BSplineCurve".

        Edges with only curves on surfaces (no 3-D curve) are typed by the adaptor: "OtherCurve".
        """
        try:
            kind = BRepAdaptor_Curve(self.edges[i]).GetType()
        except OCCT_ERRORS as exc:
            raise GeometryError(f"edge {i + 1}: OCCT cannot adapt its curve: {exc}") from exc
        return curve_type_name(kind)

    def is_degenerate(self, i: int) -> bool:
        """True for an edge collapsed to a point (``BRep_Tool::Degenerated``)."""
        if self._degenerate is not None:
            return self._degenerate[i]
        return bool(BRep_Tool.Degenerated_s(self.edges[i]))

    def non_degenerate(self) -> list[int]:
        """The indices of the edges that are not degenerate, increasing."""
        if self._degenerate is not None:
            return [i for i, flag in enumerate(self._degenerate) if not flag]
        return [i for i in range(len(self.edges)) if not self.is_degenerate(i)]

    def is_closed(self, i: int) -> bool:
        """True when the edge starts and ends at the same vertex (a full circle, a closed spline)."""
        return self.edge_vertices[i][0] == self.edge_vertices[i][1]

    def is_seam(self, i: int) -> bool:
        """True when a face holds the edge twice, once each way (the seam of a periodic surface)."""
        if self._seam is None:
            self._seam = [any(self._holds_twice(k, f) for f in fids) for k, fids in enumerate(self.edge_faces)]
        return self._seam[i]

    def _holds_twice(self, i: int, face: int) -> bool:
        """Whether face ``face`` (1-based id) holds edge ``i`` once each way. ``BRep_Tool::IsClosed`` (two
        curves on the face's surface) alone is also true for two faces on one closed surface that each
        hold the edge once, as a cylinder in two halves (gmsh's ellipses.brep), so the orientations tell."""
        edge, shape = self.edges[i], self.faces[face - 1]
        return BRep_Tool.IsClosed_s(edge, shape) and len(orientations_in(shape, edge)) == 2

    def shared_seams(self) -> dict[int, tuple[int, ...]]:
        """Edge id -> the faces that hold it twice, for the seams of more than one face (a face repeated on
        the same edges)."""
        return {i + 1: tuple(f for f in fids if self._holds_twice(i, f))
                for i, fids in enumerate(self.edge_faces) if len(fids) > 1 and self.is_seam(i)}

    def has_3d_curve(self, i: int) -> bool:
        """True when the edge carries a 3-D curve (not only curves on surfaces)."""
        return bool(BRepAdaptor_Curve(self.edges[i]).Is3DCurve())

    def __repr__(self) -> str:
        return f"Topology(edges={len(self.edges)}, vertices={len(self.vertices)}, faces={len(self.faces)})"
