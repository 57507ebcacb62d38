"""cadedge.occt.topology and edgecurve: MapShapes order, adjacency, flags, curve types, the adaptor."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge  # noqa: E402
from OCP.Geom import Geom_CylindricalSurface  # noqa: E402
from OCP.Geom2d import Geom2d_Line  # noqa: E402
from OCP.gp import gp, gp_Ax3, gp_Dir2d, gp_Pnt2d  # noqa: E402
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED, TopAbs_VERTEX  # noqa: E402
from OCP.TopExp import TopExp  # noqa: E402
from cadedge.occt.compat import TopoDS, TopTools_IndexedMapOfShape  # noqa: E402

from cadedge.occt.edgecurve import EdgeCurve  # noqa: E402
from cadedge.occt.reader import load_shape  # noqa: E402
from cadedge.occt.topology import CURVE_TYPES, Topology  # noqa: E402
from conftest import CORPUS, FIXTURES, corpus_params, corpus_sources  # noqa: E402

SOURCES = corpus_sources()


def topo(name: str) -> Topology:
    return Topology(load_shape(FIXTURES / name if (FIXTURES / name).exists() else CORPUS / name).shape)


def counts(t: Topology) -> dict:
    n = len(t.edges)
    return dict(degenerate=sum(t.is_degenerate(i) for i in range(n)), seam=sum(t.is_seam(i) for i in range(n)),
                closed=sum(t.is_closed(i) for i in range(n)))


@pytest.mark.parametrize("name", corpus_params(sorted(SOURCES)))
def test_corpus_counts_match_sources_tsv(name):
    row = SOURCES[name]
    t = topo(name)
    assert len(t.edges) == int(row["n_edges"])
    assert len(t.faces) == int(row["n_faces"])
    c = counts(t)
    assert c["degenerate"] == int(row["n_degenerated_edges"])
    assert c["seam"] == int(row["n_seam_edges"])
    types = Counter(t.curve_type(i) for i in range(len(t.edges)) if not t.is_degenerate(i))
    expected = {k: int(v) for k, v in (kv.split(":") for kv in row["curve_types"].split(";"))
                if k != "(degenerated)"}
    assert dict(types) == expected
    assert set(types) <= set(CURVE_TYPES)
    # boundary edges: non-degenerate, non-seam, exactly one face
    boundary = sum(1 for i, f in enumerate(t.edge_faces)
                   if len(f) == 1 and not t.is_degenerate(i) and not t.is_seam(i))
    assert boundary == int(row["n_boundary_edges"])


def test_ids_follow_mapshapes_order():
    t = topo("bracket.step")
    for kind, items in ((TopAbs_EDGE, t.edges), (TopAbs_VERTEX, t.vertices), (TopAbs_FACE, t.faces)):
        m = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(t.shape, kind, m)
        assert m.Extent() == len(items)
        assert all(m.FindKey(i + 1).IsSame(s) for i, s in enumerate(items))
    fmap = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(t.shape, TopAbs_FACE, fmap)
    assert all(1 <= f <= fmap.Extent() for faces in t.edge_faces for f in faces)
    # a closed solid: every edge lies between two faces, except seams (twice in one face)
    assert all(len(f) == (1 if t.is_seam(i) else 2) for i, f in enumerate(t.edge_faces))
    assert sum(t.is_seam(i) for i in range(len(t.edges))) == 3  # the three holes


def test_cylinder_seam_and_full_circles():
    t = topo("cylinder.step")
    assert len(t.edges) == 3 and len(t.vertices) == 2 and len(t.faces) == 3
    seams = [i for i in range(3) if t.is_seam(i)]
    assert len(seams) == 1 and t.curve_type(seams[0]) == "Line" and len(t.edge_faces[seams[0]]) == 1
    circles = [i for i in range(3) if t.curve_type(i) == "Circle"]
    assert len(circles) == 2 and all(t.is_closed(i) and len(t.edge_faces[i]) == 2 for i in circles)
    assert not any(t.is_degenerate(i) for i in range(3))


def test_sphere_degenerate_poles():
    t = topo("sphere.step")
    assert counts(t) == dict(degenerate=2, seam=1, closed=2)
    for i in range(3):
        if t.is_degenerate(i):
            assert t.is_closed(i)


def test_two_solids_open_face_and_loose_wire():
    two = topo("two_solids.step")
    assert len(two.edges) == 15 and len(two.faces) == 9
    face = topo("open_face.step")
    assert len(face.faces) == 1 and all(f == [1] for f in face.edge_faces)
    assert {face.curve_type(i) for i in range(4)} == {"BSplineCurve"}
    wire = topo("helix_wire.step")
    assert len(wire.faces) == 0 and wire.edge_faces == [[] for _ in wire.edges]
    assert wire.curve_type(0) == "BSplineCurve" and not wire.is_closed(0)


def test_edge_vertices_are_first_and_last_in_parameter_direction():
    t = topo("bracket.step")
    for i, e in enumerate(t.edges):
        c = EdgeCurve(e, i + 1)
        ends = c.evaluate(np.array(c.domain))
        v1, v2 = t.edge_vertices[i]
        for end, vid in zip(ends, (v1, v2)):
            p = np.array(BRep_Tool.Pnt_s(t.vertices[vid - 1]).Coord())
            assert np.linalg.norm(end - p) < 1e-6


def test_edgecurve_domain_is_forward_even_for_a_reversed_edge():
    t = topo("spline_prism.step")
    e = t.edges[1]
    rev = TopoDS.Edge_s(e.Oriented(TopAbs_REVERSED))
    a, b = EdgeCurve(e).domain
    assert EdgeCurve(rev).domain == (a, b) and a < b
    u = np.linspace(a, b, 7)
    assert np.array_equal(EdgeCurve(rev).evaluate(u), EdgeCurve(e).evaluate(u))
    assert EdgeCurve(e).evaluate(u).shape == (7, 3)


def test_edge_with_only_a_curve_on_surface():
    radius = 5.0
    surf = Geom_CylindricalSurface(gp_Ax3(gp.XOY_s()), radius)
    edge = BRepBuilderAPI_MakeEdge(Geom2d_Line(gp_Pnt2d(0, 0), gp_Dir2d(1, 1)), surf, 0.0, 6.0).Edge()
    t = Topology(edge)
    assert not t.has_3d_curve(0)
    assert t.curve_type(0) == "OtherCurve"
    c = EdgeCurve(t.edges[0], 1)
    assert c.domain == (0.0, 6.0)
    pts = c.evaluate(np.linspace(0.0, 6.0, 11))
    assert np.allclose(np.hypot(pts[:, 0], pts[:, 1]), radius)
    # a helix on the cylinder: the pcurve's direction (1, 1) / sqrt 2 gives height u / sqrt 2
    assert np.allclose(pts[:, 2], np.linspace(0.0, 6.0, 11) / math.sqrt(2) * 1.0)


def _free_edge_then(shape):
    """A compound of a loose edge followed by ``shape``: MapShapes lists that edge first, the ancestor
    map (faces first) last, so Topology must take the edge order from MapShapes."""
    from OCP.BRep import BRep_Builder
    from OCP.gp import gp_Pnt
    from OCP.TopoDS import TopoDS_Compound

    comp, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(comp)
    builder.Add(comp, BRepBuilderAPI_MakeEdge(gp_Pnt(0, 0, 0), gp_Pnt(1, 2, 3)).Edge())
    builder.Add(comp, shape)
    return comp


@pytest.mark.parametrize("path", sorted(FIXTURES.glob("*.step")) + corpus_params() + ["free edge first"],
                         ids=lambda p: getattr(p, "name", p))
def test_edges_faces_and_ends_as_mapshapes_and_topexp_give_them(path):
    shape = _free_edge_then(load_shape(FIXTURES / "bracket.step").shape) if path == "free edge first" \
        else load_shape(path).shape
    t = Topology(shape)
    maps = {}
    for kind in (TopAbs_EDGE, TopAbs_VERTEX, TopAbs_FACE):
        maps[kind] = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(shape, kind, maps[kind])
    assert maps[TopAbs_EDGE].Extent() == len(t.edges)
    for i, edge in enumerate(t.edges):
        assert maps[TopAbs_EDGE].FindKey(i + 1).IsSame(edge) and edge.Orientation() == 0  # FORWARD
        ends = (maps[TopAbs_VERTEX].FindIndex(TopExp.FirstVertex_s(edge)),
                maps[TopAbs_VERTEX].FindIndex(TopExp.LastVertex_s(edge)))
        assert t.edge_vertices[i] == ends
        for fid in t.edge_faces[i]:
            face = maps[TopAbs_FACE].FindKey(fid)
            edges = TopTools_IndexedMapOfShape()
            TopExp.MapShapes_s(face, TopAbs_EDGE, edges)
            assert edges.Contains(edge)
    if path == "free edge first":
        assert t.edge_faces[0] == [] and all(t.edge_faces[1:])


def test_an_edge_without_vertices_is_a_geometry_error():
    from OCP.BRep import BRep_Builder
    from OCP.Geom import Geom_Line
    from OCP.gp import gp_Dir, gp_Pnt
    from OCP.TopoDS import TopoDS_Edge

    from cadedge.errors import GeometryError

    edge = TopoDS_Edge()
    BRep_Builder().MakeEdge(edge, Geom_Line(gp_Pnt(0, 0, 0), gp_Dir(1, 0, 0)), 1e-7)
    with pytest.raises(GeometryError, match="edge 1 has no vertex at one end"):
        Topology(edge)


def test_an_edge_two_faces_hold_once_on_one_closed_surface_is_no_seam():
    """A cylinder in two halves on one surface: the edge at angle 0 has two curves on that surface, so
    ``BRep_Tool::IsClosed`` is true for both faces, yet each holds it once (gmsh's ellipses.brep: taken
    for seams, a job in two processes expected four triangles on such edges and failed its check)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_Sewing

    surface = Geom_CylindricalSurface(gp_Ax3(), 5.0)
    sew = BRepBuilderAPI_Sewing(1e-6)
    for start in (0.0, math.pi):
        sew.Add(BRepBuilderAPI_MakeFace(surface, start, start + math.pi, 0.0, 10.0, 1e-7).Face())
    sew.Perform()
    topology = Topology(sew.SewedShape())
    shared = [i for i, faces in enumerate(topology.edge_faces) if len(faces) == 2]
    assert any(BRep_Tool.IsClosed_s(topology.edges[i], topology.faces[0]) for i in shared)
    assert not any(topology.is_seam(i) for i in range(len(topology.edges)))
    assert topology.shared_seams() == {}
