"""cadedge.occt.shapedump: the topology and edge data read from OCCT's binary stream in one call, set
against the same read one OCP call at a time (``Topology(shape, dump=False)``, ``BRep_Tool``), and the
shapes it refuses (locations, corrupt streams), which go through OCP instead."""

from __future__ import annotations

import io
import sys

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BinTools import BinTools_ShapeSet  # noqa: E402
from OCP.BRep import BRep_Builder, BRep_Tool  # noqa: E402
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder  # noqa: E402
from OCP.gp import gp_Pnt, gp_Trsf, gp_Vec  # noqa: E402
from OCP.TopLoc import TopLoc_Location  # noqa: E402
from OCP.TopoDS import TopoDS_Compound  # noqa: E402

from cadedge.kernels import parse_shapes  # noqa: E402
from cadedge.occt import shapedump  # noqa: E402
from cadedge.occt.reader import load_shape  # noqa: E402
from cadedge.occt.topology import Topology  # noqa: E402
from conftest import FIXTURES, ROOT, corpus_params  # noqa: E402
from test_input_formats import write_iges  # noqa: E402

LOCATED = {"two_solids.step"}  # fixtures whose parts carry locations: the dump refuses them


def same_topology(a: Topology, b: Topology) -> None:
    """The same ids, shapes (orientation included), adjacency and flags."""
    assert (len(a.edges), len(a.vertices), len(a.faces)) == (len(b.edges), len(b.vertices), len(b.faces))
    for xs, ys in ((a.edges, b.edges), (a.vertices, b.vertices), (a.faces, b.faces)):
        assert all(x.IsEqual(y) for x, y in zip(xs, ys))
    assert a.edge_faces == b.edge_faces
    assert a.edge_vertices == b.edge_vertices
    n = len(a.edges)
    for flag in ("is_degenerate", "is_seam", "is_closed"):
        assert [getattr(a, flag)(i) for i in range(n)] == [getattr(b, flag)(i) for i in range(n)], flag


def same_data(topo: Topology) -> None:
    """The dump's tolerances, points, ranges and curve presence as BRep_Tool gives them."""
    d = topo.dump
    for i, edge in enumerate(topo.edges):
        assert d.edge_tolerance[i] == BRep_Tool.Tolerance_s(edge)
        assert bool(d.degenerate[i]) == BRep_Tool.Degenerated_s(edge)
        assert (d.edge_curve[i] > 0) == BRep_Tool.IsGeometric_s(edge) or d.degenerate[i]
        if d.edge_curve[i]:
            assert tuple(d.edge_range[i]) == tuple(BRep_Tool.Range_s(edge))
    for lazy in (d.edges, d.vertices, d.faces):  # the orientation the shape set holds each with
        assert all(d.shape_set.Shape(k).Orientation() == o for k, o in zip(lazy._index, lazy._stored))
    for k, vertex in enumerate(topo.vertices):
        assert d.vertex_tolerance[k] == BRep_Tool.Tolerance_s(vertex)
        assert tuple(d.vertex_points[k]) == BRep_Tool.Pnt_s(vertex).Coord()


@pytest.mark.parametrize("path", sorted(FIXTURES.glob("*.step")) + corpus_params(), ids=lambda p: getattr(p, "name", p))
def test_the_dump_reads_what_ocp_reads(path):
    shape = load_shape(path).shape
    topo = Topology(shape)
    if path.name in LOCATED:
        assert topo.dump is None
    else:
        assert topo.dump is not None
        same_data(topo)
    same_topology(topo, Topology(shape, dump=False))


def _compound(*shapes):
    comp, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(comp)
    for s in shapes:
        builder.Add(comp, s)
    return comp


def test_multi_solid_compounds_shared_and_reversed_parts_and_loose_edges():
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge

    box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 2.0, 3.0, 4.0).Shape()
    cyl = BRepPrimAPI_MakeCylinder(1.0, 5.0).Shape()  # a seam and two circles
    loose = BRepPrimAPI_MakeBox(gp_Pnt(5, 0, 0), 1.0, 1.0, 1.0).Shape()
    edge = BRepBuilderAPI_MakeEdge(gp_Pnt(0, 0, 0), gp_Pnt(1, 2, 3)).Edge()
    shapes = [_compound(box, cyl), _compound(edge, box, box.Reversed(), cyl), _compound(_compound(cyl), loose, edge),
              box.Reversed(), edge]
    for shape in shapes:
        topo = Topology(shape)
        assert topo.dump is not None
        same_data(topo)
        same_topology(topo, Topology(shape, dump=False))


def test_a_located_shape_takes_the_ocp_path():
    box = BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape()
    trsf = gp_Trsf()
    trsf.SetTranslation(gp_Vec(1, 2, 3))
    moved = box.Moved(TopLoc_Location(trsf))
    for shape in (moved, _compound(box, moved)):
        assert shapedump.read(shape) is None
        topo = Topology(shape)
        assert topo.dump is None and len(topo.edges) == 12 * (1 if shape is moved else 2)
        same_topology(topo, Topology(shape, dump=False))


def test_an_xde_assembly_with_an_instanced_part_takes_the_ocp_path(tmp_path):
    pytest.importorskip("cadquery")
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        import hard_models
    finally:
        sys.path.remove(str(ROOT / "scripts"))
    path = tmp_path / "assembly.step"
    hard_models.write_xde_assembly(path)
    shape = load_shape(path).shape
    assert shapedump.read(shape) is None
    topo = Topology(shape)
    assert topo.dump is None and len(topo.edges) > 0


def test_iges_input(tmp_path):
    path = write_iges(FIXTURES / "bracket.step", tmp_path / "bracket.igs")
    shape = load_shape(path).shape
    topo = Topology(shape)
    if topo.dump is not None:
        same_data(topo)
    same_topology(topo, Topology(shape, dump=False))


def _stream(shape) -> tuple[bytes, int]:
    shape_set = BinTools_ShapeSet()
    shape_set.SetWithTriangles(False)
    root = shape_set.Add(shape)
    buf = io.BytesIO()
    shape_set.Write(buf)
    return buf.getvalue(), root


def test_a_corrupt_or_foreign_stream_is_refused_never_read_past_its_end():
    data, root = _stream(load_shape(FIXTURES / "bracket.step").shape)
    assert parse_shapes(data, root, 0)
    rng = np.random.default_rng(1)
    for cut in (1, 30, 70, len(data) // 2, len(data) - 1):
        with pytest.raises(ValueError, match="parse_shapes"):
            parse_shapes(data[:cut], root, 0)
    with pytest.raises(ValueError, match="bytes past the last shape"):
        parse_shapes(data + b"\0", root, 0)
    with pytest.raises(ValueError, match="version"):
        parse_shapes(data.replace(b"Topology V4", b"Topology V9", 1), root, 0)
    with pytest.raises(ValueError, match="root"):
        parse_shapes(data, 10**6, 0)
    with pytest.raises(ValueError, match="counts more items"):  # refused before allocating for them
        parse_shapes(data.replace(b"Curves ", b"Curves 999999", 1), root, 0)
    for _ in range(200):  # random bytes flipped: refused or read, never a crash
        noisy = bytearray(data)
        at = rng.integers(0, len(data), 4)
        noisy[at[0]] ^= 0xFF
        noisy[at[1]] = rng.integers(0, 256)
        try:
            parse_shapes(bytes(noisy), root, 0)
        except ValueError:
            pass


@pytest.mark.parametrize("path", sorted(FIXTURES.glob("*.step")) + corpus_params(), ids=lambda p: getattr(p, "name", p))
def test_edge_table_rows_from_the_dump_equal_those_read_through_adaptors(path):
    from cadedge.occt.edgetable import EdgeTable

    topo = Topology(load_shape(path).shape)
    rows = [i for i in range(len(topo.edges)) if not topo.is_degenerate(i)]
    a, b = EdgeTable(topo.edges, rows, topo.dump), EdgeTable(topo.edges, rows)
    assert a.rows == b.rows and a.kinds == b.kinds
    for name in ("kind", "gofs", "ints", "gdata", "domain", "hofs", "hdata", "exact"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name


def _table(name: str):
    from cadedge.occt.edgetable import EdgeTable

    topo = Topology(load_shape(FIXTURES / name).shape)
    table = EdgeTable(topo.edges, [i for i in range(len(topo.edges)) if not topo.is_degenerate(i)], topo.dump)
    assert table.dumped.all()
    return table


def test_a_dump_row_whose_curve_is_not_occts_is_dropped_even_with_its_ends_on_its_vertices():
    from cadedge.occt.edgetable import CONIC

    table = _table("cylinder.step")
    circles = [r for r in range(len(table)) if table.kind[r] == CONIC]
    assert circles
    r = circles[0]
    edge = table.rows[r]
    y = table.gdata[table.gofs[r] + 6:table.gofs[r] + 9]
    y *= -1.0  # the circle run the other way round: the same ends on a full circle, other interior points
    table._check()
    assert edge not in table.rows


def test_a_dump_row_off_its_vertices_gets_the_full_check():
    from cadedge.occt.edgetable import LINE

    table = _table("bracket.step")
    lines = [r for r in range(len(table)) if table.kind[r] == LINE]
    n = len(table)
    got = table.evaluate(np.repeat(np.arange(n), 9), np.linspace(table.domain[:, 0], table.domain[:, 1], 9, axis=1).ravel())
    assert table._ends_on_vertices(got.reshape(n, 9, 3)[:, [0, -1]]).all()
    r = lines[0]
    edge = table.rows[r]
    table.gdata[table.gofs[r]] += 1e-3  # the line moved off its vertices
    got = table.evaluate(np.repeat(np.arange(n), 9), np.linspace(table.domain[:, 0], table.domain[:, 1], 9, axis=1).ravel())
    assert not table._ends_on_vertices(got.reshape(n, 9, 3)[:, [0, -1]])[r]
    table._check()
    assert edge not in table.rows and len(table) == n - 1
