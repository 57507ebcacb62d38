"""A face whose boundary crosses itself (its edges cross within their tolerance): the crossing segments found
(cadedge.mesh.tangles), told from crossing chords of curves that do not cross, the layout untangled, and the
face meshed laid flat first instead of hanging gmsh."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cadedge.mesh.tangles import crossings, inward, untangle

LENGTH, BULGE, DIP, TOLERANCE = 45.0, 1.1, 0.28, 0.3


def _brute(plane: np.ndarray, seg: np.ndarray) -> set[tuple[int, int]]:
    """Every properly crossing pair, one segment against each other."""
    from cadedge.mesh.tangles import cross_properly

    found = set()
    for i in range(len(seg)):
        for j in range(i + 1, len(seg)):
            if set(seg[i].tolist()) & set(seg[j].tolist()):
                continue
            if cross_properly(plane[seg[i, 0]], plane[seg[i, 1]], plane[seg[j, 0]], plane[seg[j, 1]]):
                found.add((i, j))
    return found


def test_the_sweep_finds_the_crossings_one_against_each_other_finds():
    rng = np.random.default_rng(7)
    plane = rng.random((120, 2))
    seg = rng.integers(0, 120, size=(90, 2))
    seg = seg[seg[:, 0] != seg[:, 1]]
    got = {tuple(sorted(p)) for p in crossings(plane, seg).tolist()}
    assert got == _brute(plane, seg) and len(got) > 50
    assert crossings(plane, seg, limit=10) is None


def _lens(points: int = 40, dip: float = 0.02) -> tuple[np.ndarray, list[tuple[int, int]], int]:
    """A lens from (0, 0) to (1, 0): a straight side of ``points`` segments below and a curved side above
    (as many segments) that dips ``dip`` below the straight one near both ends, crossing it twice. Returns
    the points, the segments (an outer loop, counter-clockwise) and the row where the curved side begins."""
    x = np.linspace(0.0, 1.0, points + 1)
    top = np.column_stack([x, 0.1 * np.sin(np.pi * x) - dip * np.sin(np.pi * x) ** 0.1 * (np.abs(x - 0.5) > 0.45)])
    plane = np.vstack([np.column_stack([x, np.zeros_like(x)]), top[1:-1][::-1]])
    n = len(plane)
    return plane, [(k, (k + 1) % n) for k in range(n)], points + 1


def test_a_lens_whose_sides_cross_near_its_ends_is_untangled_within_reach():
    plane, segments, _ = _lens()
    before = crossings(plane, segments)
    assert len(before) == 2
    got = untangle(plane, segments, reach=0.1)
    assert not isinstance(got, str)
    moved, places = got
    assert not len(crossings(moved, segments))
    assert len(places) == 2 and {min(plane[rows, 0].max(), 1 - plane[rows, 0].min()) < 0.1 for rows in places} == {True}
    shift = np.linalg.norm(moved - plane, axis=1)
    assert 0 < shift.max() <= 2.5 * 0.02  # across the straight side, no further than the dip was out
    ends = np.abs(plane[shift > 0, 0] - 0.5) >= 0.45 - 1e-9  # nodes of either side, by the crossings only
    assert ends.all() and np.count_nonzero(shift) < 8
    assert isinstance(untangle(plane, segments, reach=1e-3), str)


def test_a_boundary_that_crosses_nothing_is_left_as_it_is():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    hole = 0.4 + 0.2 * square[::-1]  # clockwise
    plane = np.vstack([square, hole])
    segments = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4)]
    same, places = untangle(plane, segments, reach=1.0)
    assert np.array_equal(same, plane) and places == []
    # the region is left of the outer square's sides and of the clockwise hole's
    assert inward(plane, segments).tolist() == [1.0] * 8
    flipped = [(b, a) for a, b in segments]
    assert inward(plane, flipped).tolist() == [-1.0] * 8


def _crossing_lens_face(dip: float):
    """A plane face between a line ``LENGTH`` long and a B-spline edge that bulges ``BULGE`` away from it and
    begins and ends ``dip`` on its other side, 0.1 from its ends (through its vertices within
    :data:`TOLERANCE`), as a valid TopoDS face: the Fusion tyre's face 31 at a hundred times its size."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import (BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeVertex,
                                    BRepBuilderAPI_MakeWire)
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.GeomAPI import GeomAPI_PointsToBSpline
    from OCP.gp import gp_Ax3, gp_Dir, gp_Pln, gp_Pnt
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer

    from cadedge.occt.compat import TColgp_Array1OfPnt, TopoDS

    builder = BRep_Builder()
    ends = [BRepBuilderAPI_MakeVertex(gp_Pnt(x, 0.0, 0.0)).Vertex() for x in (0.0, LENGTH)]
    for v in ends:
        builder.UpdateVertex(v, TOLERANCE)
    x = np.linspace(0.1, LENGTH - 0.1, 41)
    y = -dip + (BULGE + dip) * np.sin(np.pi * (x - 0.1) / (LENGTH - 0.2)) ** 0.7
    points = TColgp_Array1OfPnt(1, len(x))
    for i, (px, py) in enumerate(zip(x, y), start=1):
        points.SetValue(i, gp_Pnt(float(px), float(py), 0.0))
    spline = BRepBuilderAPI_MakeEdge(GeomAPI_PointsToBSpline(points).Curve(), *ends).Edge()
    wire = BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(*ends).Edge(), spline).Wire()
    face = BRepBuilderAPI_MakeFace(gp_Pln(gp_Ax3(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1))), wire, True).Face()
    explorer = TopExp_Explorer(face, TopAbs_EDGE)
    while explorer.More():
        builder.UpdateEdge(TopoDS.Edge_s(explorer.Current()), TOLERANCE)
        explorer.Next()
    assert BRepCheck_Analyzer(face).IsValid()
    return face


def test_a_face_whose_edges_cross_is_laid_flat_first(tmp_path):
    """The lens whose spline crosses its line near both ends: its boundary crosses itself along its curves,
    and the face is laid flat first."""
    gmsh = pytest.importorskip("gmsh")
    from OCP.BRepTools import BRepTools

    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.parametric import crossed
    from cadedge.mesh.strategies import CROSSED_ORDER, STRATEGIES, face_order

    path = tmp_path / "lens.brep"
    BRepTools.Write_s(_crossing_lens_face(DIP), str(path))
    with gmsh_session():
        gmsh.open(str(path))
        (surface,) = [s for _, s in gmsh.model.getEntities(2)]
        line, spline = sorted((c for _, c in gmsh.model.getEntities(1)),
                              key=lambda c: gmsh.model.getType(1, c) != "Line")
        gmsh.model.mesh.setTransfiniteCurve(line, 301)
        gmsh.model.mesh.setTransfiniteCurve(spline, 41)
        gmsh.model.mesh.generate(1)
        assert crossed(surface)
        assert face_order(surface) == CROSSED_ORDER
    assert STRATEGIES[CROSSED_ORDER[0]].unrolled == "parameters"


def test_crossing_chords_of_curves_that_do_not_cross_are_left_to_gmsh():
    """A crescent between two arcs over one chord 10 long, 1.0 and 0.8 high: the outer arc's two segments cut
    across the inner one's twenty, but the arcs meet only at their ends, so gmsh splits those segments
    until they part, as before; the face keeps gmsh's order."""
    gmsh = pytest.importorskip("gmsh")
    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.parametric import crossed, layout, scales
    from cadedge.mesh.strategies import GMSH_ORDER, face_order

    with gmsh_session():
        occ = gmsh.model.occ
        a, b = occ.addPoint(0, 0, 0), occ.addPoint(10, 0, 0)
        arcs = [occ.addCircleArc(a, occ.addPoint(5, h - (25 + h * h) / (2 * h), 0), b) for h in (1.0, 0.8)]
        surface = occ.addPlaneSurface([occ.addCurveLoop(arcs)])
        occ.synchronize()
        for arc, nodes in zip(arcs, (3, 21)):
            gmsh.model.mesh.setTransfiniteCurve(arc, nodes)
        gmsh.model.mesh.generate(1)
        su, sv, lo, _ = scales(surface)
        laid = layout(surface, (su, sv), lo)
        assert len(crossings(laid.plane, laid.segments)) == 2
        assert not crossed(surface)
        assert face_order(surface) == GMSH_ORDER


def test_a_face_whose_edges_cross_is_meshed_laid_flat_on_its_grids_without_hanging(tmp_path):
    """The crossing lens through the mesh job: gmsh's meshers hung on it in every strategy (2 minutes,
    then the face failed); laid flat and untangled first it is meshed on its grids, node for node, the
    folds at the crossings named."""
    pytest.importorskip("gmsh")
    from OCP.BRepTools import BRepTools

    from cadedge.mesh import mesh_shape

    path = tmp_path / "lens.brep"
    BRepTools.Write_s(_crossing_lens_face(DIP), str(path))
    result = mesh_shape(str(path), ald=1e-2, timeout=120)
    assert not result.failures and result.check.ok
    (face,) = result.faces
    assert face.strategy == "parameters laid flat, Frontal-Delaunay" and not face.attempts
    assert result.check.grid_nodes and not result.check.missing_grid_nodes
    (row,) = result.report.faces
    assert row.folded > 0 and row.reason == "tolerances"  # the folds at the crossings, named
    smalls = result.report.small_angles
    assert smalls and all(a.forced for a in smalls)
    assert any("crosses itself" in a.reason for a in smalls)
    assert math.isfinite(row.area_deficit) and abs(row.area_deficit) < 0.1


def _overshot_corner() -> tuple[np.ndarray, list[tuple[int, int]]]:
    """A unit square (counter-clockwise) whose top-right corner vertex sits 0.0014 above the top side, on the
    right side's line, the right side's grid running on past the top's line to it and the top's grid
    starting 0.0003 beyond the right side's line: the two sides cross at (1, 1) between finely spaced nodes
    (a TraceParts USB socket's plane face 787, its vertex off both edges' lines)."""
    right = [(1.0, y) for y in (0.0, 0.5, 0.99, 0.998, 0.9995, 0.99985, 1.0001, 1.0003, 1.0008, 1.0011)]
    top = [(x, 1.0) for x in (1.0003, 1.00014, 0.99998, 0.9998, 0.9995, 0.999, 0.99, 0.5)]
    plane = np.array([(0.0, 0.0)] + right + [(1.0, 1.0014)] + top + [(0.0, 1.0)])
    return plane, [(k, (k + 1) % len(plane)) for k in range(len(plane))]


def test_a_corner_whose_sides_overshoot_each_other_is_cut_off_not_turned_back():
    """The small loop between the corner vertex and where its two sides cross is turned inside out. Moving one
    node at a time across the other side's line sent the nodes back past their neighbours, and gmsh made no
    triangles of the plane (the face failed after every strategy hung). The loop's nodes now go onto the
    two sides' lines through the crossing, in order, each side's on its own (spread by length along both,
    a node of the top side went onto the right side's line, and at 1e-3 the socket's face made a
    triangle of three nodes of one straight edge)."""
    from cadedge.mesh.flat import mesh_plane

    plane, segments = _overshot_corner()
    assert len(crossings(plane, segments)) == 1
    moved, places = untangle(plane, segments, reach=0.01)
    assert not len(crossings(moved, segments)) and len(places) == 1
    steps = np.diff(np.vstack([moved, moved[:1]]), axis=0)
    turns = np.einsum("ij,ij->i", steps, np.roll(steps, -1, axis=0)) / (
        np.linalg.norm(steps, axis=1) * np.linalg.norm(np.roll(steps, -1, axis=0), axis=1))
    assert turns.min() > -0.5  # no side turns back on itself
    assert np.linalg.norm(moved - plane, axis=1).max() <= 0.0015  # within the corner's overshoot
    # each side's nodes on its own line: three nodes of one straight edge in a triangle make it flat
    right, top = plane[:, 0] == 1.0, (plane[:, 1] == 1.0) & (plane[:, 0] != 1.0)
    assert np.allclose(moved[right, 0], 1.0, atol=1e-12) and np.allclose(moved[top, 1], 1.0, atol=1e-12)
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        got = mesh_plane(moved, segments, np.full(len(moved), 0.1), 6, lambda: None, {})
    finally:
        gmsh.finalize()
    assert not isinstance(got, str)
    points, triangles = got
    corners = points[triangles]
    twice = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.all(twice > 0) and 0.5 * twice.sum() == pytest.approx(1.0, abs=1e-5)
