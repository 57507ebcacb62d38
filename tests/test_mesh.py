"""cadedge.mesh: real gmsh on real OCCT shapes (fixtures, cadquery shapes, corpus solids)."""

from __future__ import annotations

import copy

import numpy as np
import pytest

gmsh = pytest.importorskip("gmsh")
trimesh = pytest.importorskip("trimesh")

import cadedge  # noqa: E402
from cadedge.errors import InputError  # noqa: E402
from cadedge.mesh import check_mesh, mesh_shape  # noqa: E402
from cadedge.mesh.check import check_triangles  # noqa: E402
from cadedge.mesh.report import faces_beside  # noqa: E402

from conftest import CORPUS, FIXTURES  # noqa: E402

ALD = 1e-2
CLOSED_FIXTURES = ["bracket", "cylinder", "sphere", "spline_prism", "two_solids"]


@pytest.fixture(scope="module")
def grids() -> dict[str, cadedge.ShapeGrid]:
    return {name: cadedge.refine_shape(FIXTURES / f"{name}.step", ald=ALD, max_growth=1.3)
            for name in CLOSED_FIXTURES + ["open_face"]}


@pytest.fixture(scope="module")
def meshed(grids):
    """``mesh_shape(grids[name])`` with the default options, run once per module for the tests that only
    read the result (each gmsh run costs seconds)."""
    cache: dict[str, object] = {}

    def get(name: str):
        if name not in cache:
            cache[name] = mesh_shape(grids[name])
        return cache[name]

    return get


def _assert_watertight(result) -> None:
    assert not result.failures, [f.line() for f in result.failures]
    assert result.check.ok, result.check.problems
    assert result.check.shells and all(s.watertight for s in result.check.shells)
    assert result.check.missing_grid_nodes == 0
    # independent of our check: trimesh on each connected piece, and exact grid points among the nodes
    mesh = trimesh.Trimesh(result.nodes, result.triangles, process=False)
    for part in mesh.split(only_watertight=False):
        assert part.is_watertight
    nodes = {tuple(p) for p in result.nodes[np.unique(result.triangles)]}
    for e in result.grid.edges:
        assert all(tuple(p) in nodes for p in e.points), f"edge {e.id}"
    faces = set(range(1, result.grid.faces + 1))
    assert set(np.unique(result.triangle_faces)) == faces


@pytest.mark.parametrize("name", CLOSED_FIXTURES)
def test_closed_fixtures_are_watertight_and_carry_every_grid_node(meshed, name):
    result = meshed(name)
    _assert_watertight(result)
    assert result.check.min_angle_deg > 5.0


def test_shells_match_solids(grids, meshed):
    result = meshed("two_solids")
    assert len(result.check.shells) == 2
    assert sum(len(s.faces) for s in result.check.shells) == grids["two_solids"].faces


def test_open_shell_boundary_is_reported_not_failed(meshed):
    result = meshed("open_face")
    assert not result.failures and result.check.ok
    (shell,) = result.check.shells
    assert not shell.watertight and shell.bad_edges == 0
    boundary_segments = sum(e.segments for e in result.grid.edges if len(e.faces) == 1)  # as meshed
    assert shell.boundary_edges == boundary_segments


def test_sizes_mode_is_watertight_without_imposed_nodes(grids):
    result = mesh_shape(grids["bracket"], mode="sizes")
    assert not result.failures and result.check.ok
    assert all(s.watertight for s in result.check.shells)
    assert result.check.grid_nodes == 0  # nodes are gmsh's own in this mode


def test_interior_is_graded_not_overrefined(grids, meshed):
    """Triangle sizes follow the edge spacings: far fewer triangles than a uniform mesh at the finest spacing."""
    grid = grids["bracket"]
    result = meshed("bracket")
    area = trimesh.Trimesh(result.nodes, result.triangles, process=False).area
    finest = min(min(e.spacing) for e in grid.edges if not e.degenerate)
    uniform = area / (np.sqrt(3) / 4 * finest ** 2)
    assert len(result.triangles) < uniform / 3  # curved faces are also sized for the area target


def _shuffled_order(grid: cadedge.ShapeGrid) -> cadedge.ShapeGrid:
    """Same edges, but listed backwards, each with its points reversed and made-up parameters.

    gmsh's tags then no longer follow our ids and gmsh's curves run against our edges, so the mapping must
    fall back on geometry (end points, projection of every grid point) and handle the reversal.
    """
    g = copy.copy(grid)
    n = len(grid.edges)
    g.edges = []
    for k, e in enumerate(reversed(grid.edges)):
        e2 = copy.copy(e)
        e2.id = k + 1
        if not e.degenerate:
            e2.points = e.points[::-1].copy()
            e2.vertices = (e.vertices[1], e.vertices[0])
            e2.params = np.linspace(0.0, 1.0, len(e.params))
        g.edges.append(e2)
    assert len(g.edges) == n
    return g


def test_mapping_falls_back_on_geometry_for_reordered_reversed_edges(grids):
    result = mesh_shape(_shuffled_order(grids["cylinder"]))
    _assert_watertight(result)
    assert any("by geometry" in n for n in result.details)


def test_coinciding_free_curves_and_unsewn_faces_map_by_topology():
    """Free curves first in the compound, each on a boundary edge of one of two unsewn faces (every
    corner is three vertices at one point): gmsh binds the faces' curves first, and matched by position
    alone the free curves took the faces' curves and the corners the wrong points, so no face's boundary
    closed (a real file: a cage of unsewn spline faces with its construction curves)."""
    cq = pytest.importorskip("cadquery")
    left = cq.Face.makeFromWires(cq.Wire.makePolygon([(0, 0, 0), (4, 0, 0), (4, 3, 0), (0, 3, 0)], close=True))
    right = cq.Face.makeFromWires(cq.Wire.makePolygon([(4, 0, 0), (9, 0, 0), (9, 3, 0), (4, 3, 0)], close=True))
    free = [cq.Edge.makeLine(cq.Vector(*a), cq.Vector(*b)) for a, b in (((4, 0, 0), (4, 3, 0)), ((0, 3, 0), (4, 3, 0)))]
    shape = cq.Compound.makeCompound([*free, left, right]).wrapped
    result = mesh_shape(shape, ald=ALD)
    assert result.ok, result.problems(verbose=True)
    assert not result.own_mesh_edges and all(not o.attempts for o in result.faces)
    assert result.check.missing_grid_nodes == 0 and result.check.grid_nodes > 0
    assert any("through its edges" in n for n in result.details)


def test_a_folded_grid_fails_its_faces_until_gmsh_meshes_that_edge_itself(grids):
    """A folded grid on one box edge: its faces fail on that grid (each attempt named with gmsh's reason),
    then mesh on gmsh's own curve mesh of the edge; the other faces mesh at once."""
    g = copy.copy(grids["two_solids"])
    g.edges = [copy.copy(e) for e in g.edges]
    edge = next(e for e in g.edges if e.curve == "Line" and len(e.faces) == 2)
    k = 9
    t = np.linspace(0.0, 1.0, k)
    order = np.r_[0, np.arange(k - 2, 0, -1), k - 1]  # interior points run backwards: the boundary folds
    edge.params = edge.params[0] + (edge.params[-1] - edge.params[0]) * t[order]
    edge.params[[0, -1]] = grids["two_solids"].edges[edge.id - 1].params[[0, -1]]
    a, b = edge.points[0], edge.points[-1]
    edge.points = a + (b - a) * t[order][:, None]
    edge.points[[0, -1]] = a, b
    result = mesh_shape(g)
    assert result.ok, result.problems(verbose=True)
    retried = {o.face for o in result.faces if o.attempts}
    assert retried and retried <= set(edge.faces)
    # the first face to run out of strategies replaces the edge's grid by gmsh's curve mesh; a face whose
    # first attempt failed in the batch then meshes on that curve mesh too
    assert any("own curve mesh" in o.strategy for o in result.faces if o.face in retried)
    assert all(o.ok and all(why for _, why in o.attempts) for o in result.faces if o.face in retried)
    assert edge.id in result.own_mesh_edges and any("gmsh's own curve mesh replaced" in n for n in result.notes)
    beside = faces_beside(g, result.own_mesh_edges)  # the faces a report names for it when over target
    assert all(edge.id in beside[f] for f in edge.faces)
    assert set(beside) == {f for e in g.edges if e.id in result.own_mesh_edges for f in e.faces}
    assert set(np.unique(result.triangle_faces)) == set(range(1, g.faces + 1))


def test_check_finds_cracks_and_holes(grids, meshed):
    result = meshed("cylinder")
    nodes, tris = result.nodes, result.triangles
    holed = check_triangles(nodes, tris[1:])
    assert not holed.ok and any(not s.watertight for s in holed.shells)
    cracked_nodes = np.vstack([nodes, nodes[tris[0, 0]]])  # same coordinates, second node
    cracked = tris.copy()
    cracked[0, 0] = len(nodes)
    crack = check_triangles(cracked_nodes, cracked)
    assert not crack.ok and crack.duplicate_nodes == 1
    raw = check_mesh(nodes, tris, grid=grids["cylinder"])
    assert raw.ok and raw.missing_grid_nodes == 0
    moved = nodes.copy()
    vertex = np.asarray(grids["cylinder"].vertices[0].point)
    moved[np.flatnonzero((nodes == vertex).all(axis=1))[0]] += 1e-9  # off by a nanometre is not there
    assert check_mesh(moved, tris, grid=grids["cylinder"]).missing_grid_nodes == 1
    assert check_mesh(result) is result.check


def test_check_names_faces_meeting_inside_their_boundaries_and_fails_only_cracks(grids, meshed):
    """Two faces whose surfaces meet away from their edges (the SolidWorks part 2242-A's planes 337 and
    367 share an edge and lie on its same side, one overlapping the other) may each have an interior node
    at one point. No mesh closes that: the check named it a crack and failed. It now names the faces and
    passes; a copy of a node on a B-rep edge, or a point whose faces it cannot tell, is still a crack."""
    from cadedge.mesh import _multiplicity_from_grid

    result = meshed("cylinder")
    nodes, tris, faces = result.nodes, result.triangles, result.triangle_faces
    multiplicity = _multiplicity_from_grid(nodes, result.grid)  # the grid as meshed, every segment
    on_edge = np.zeros(len(nodes), dtype=bool)
    on_edge[np.array(list(multiplicity)).ravel()] = True
    inner = {int(f): [int(v) for v in np.unique(tris[faces == f]) if not on_edge[v]] for f in np.unique(faces)}
    a, b = sorted(f for f in inner if inner[f])[:2]
    met = nodes.copy()
    met[inner[a][0]] = nodes[inner[b][0]]
    check = check_triangles(met, tris, triangle_faces=faces, edge_multiplicity=multiplicity)
    assert check.ok and check.duplicate_nodes == 0 and check.meeting_faces == [(a, b)]
    assert any(f"{a} with {b}" in line for line in check.lines())
    unknown = check_triangles(met, tris, edge_multiplicity=multiplicity)  # no face ids: a crack
    assert not unknown.ok and unknown.duplicate_nodes == 1 and not unknown.meeting_faces
    cracked = nodes.copy()
    cracked[np.flatnonzero(on_edge & np.isin(np.arange(len(nodes)), tris[faces == a]))[0]] = nodes[inner[b][0]]
    crack = check_triangles(cracked, tris, triangle_faces=faces, edge_multiplicity=multiplicity)
    assert not crack.ok and crack.duplicate_nodes == 1 and not crack.meeting_faces


def _squares_on_two_edges_between_two_vertices():
    """Four unit squares in a compound: two on one edge from (0, 0, 0) to (1, 0, 0) and two on another
    edge between the same two vertices, lying on it (a solid touching itself along a segment, as Voron
    Trident's umbilical mount does where a hole's 0.00067 arc and a wall's line share their vertices)."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import (BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeVertex,
                                    BRepBuilderAPI_MakeWire)
    from OCP.gp import gp_Pnt
    from OCP.TopoDS import TopoDS_Compound

    def vertex(p):
        return BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, p))).Vertex()

    a, b = vertex((0, 0, 0)), vertex((1, 0, 0))
    one, two = BRepBuilderAPI_MakeEdge(a, b).Edge(), BRepBuilderAPI_MakeEdge(a, b).Edge()
    compound, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(compound)
    for edge, far in [(one, (0, -1, 0)), (one, (0, 0, 1)), (two, (0, 1, 0)), (two, (0, 0, -1))]:
        c, d = vertex(np.add((1, 0, 0), far)), vertex(far)
        wire = BRepBuilderAPI_MakeWire(edge, BRepBuilderAPI_MakeEdge(b, c).Edge(), BRepBuilderAPI_MakeEdge(c, d).Edge(),
                                       BRepBuilderAPI_MakeEdge(d, a).Edge()).Wire()
        builder.Add(compound, BRepBuilderAPI_MakeFace(wire, True).Face())
    return compound


def test_check_counts_a_segment_of_two_edges_for_both_edges_faces():
    """Two B-rep edges between the same two vertices, lying on each other, share their one segment: the
    faces of both put four triangles on it. The check expected one edge's two and failed the mesh (exit 1
    on the umbilical mount); it now expects both edges' counts, and still fails a missing triangle."""
    from cadedge.mesh import _multiplicity_from_grid

    grid = cadedge.refine_shape(_squares_on_two_edges_between_two_vertices(), ald=ALD)
    shared = [e for e in grid.edges if len(e.faces) == 2]
    assert len(shared) == 2 and np.array_equal(shared[0].points, shared[1].points)
    result = mesh_shape(grid)
    assert result.check.ok and not any(s.bad_edges for s in result.check.shells)
    multiplicity = _multiplicity_from_grid(result.nodes, grid)  # the raw check, from the grid alone
    (segment,) = [pair for pair, n in multiplicity.items() if n == 4]
    assert check_mesh(result.nodes, result.triangles, grid=grid).ok
    on_segment = np.flatnonzero(np.isin(result.triangles, segment).sum(axis=1) == 2)
    assert len(on_segment) == 4
    assert not check_mesh(result.nodes, np.delete(result.triangles, on_segment[0], axis=0), grid=grid).ok


def _faces_on_a_hooked_edge():
    """Two unit-wide planar faces at right angles on one edge from (0, 0, 0) to (2, 0, 0) whose curve (a
    degree-1 B-spline) runs out to x = 1, back to 0.9 and on: a hook along itself, as a SolidWorks
    helix's or a TraceParts socket's edges make."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import (BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeVertex,
                                    BRepBuilderAPI_MakeWire)
    from OCP.Geom import Geom_BSplineCurve
    from OCP.gp import gp_Pnt
    from OCP.TopoDS import TopoDS_Compound

    from cadedge.occt.compat import TColgp_Array1OfPnt, TColStd_Array1OfInteger, TColStd_Array1OfReal

    along = [0.0, 1.0, 0.9, 2.0]
    poles, knots, mults = TColgp_Array1OfPnt(1, 4), TColStd_Array1OfReal(1, 4), TColStd_Array1OfInteger(1, 4)
    for i, x in enumerate(along, start=1):
        poles.SetValue(i, gp_Pnt(x, 0.0, 0.0))
        knots.SetValue(i, float(i))
        mults.SetValue(i, 2 if i in (1, 4) else 1)
    vertex = {name: BRepBuilderAPI_MakeVertex(gp_Pnt(*p)).Vertex() for name, p in
              {"a": (0.0, 0.0, 0.0), "b": (2.0, 0.0, 0.0), "c": (2.0, -1.0, 0.0), "d": (0.0, -1.0, 0.0),
               "e": (2.0, 0.0, 1.0), "f": (0.0, 0.0, 1.0)}.items()}
    hook = BRepBuilderAPI_MakeEdge(Geom_BSplineCurve(poles, knots, mults, 1), vertex["a"], vertex["b"]).Edge()
    compound, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(compound)
    for far, near in (("c", "d"), ("e", "f")):
        wire = BRepBuilderAPI_MakeWire(hook, BRepBuilderAPI_MakeEdge(vertex["b"], vertex[far]).Edge(),
                                       BRepBuilderAPI_MakeEdge(vertex[far], vertex[near]).Edge(),
                                       BRepBuilderAPI_MakeEdge(vertex[near], vertex["a"]).Edge()).Wire()
        builder.Add(compound, BRepBuilderAPI_MakeFace(wire, True).Face())
    return compound


def test_a_grid_point_where_the_edges_curve_turns_back_is_not_imposed():
    """The refined grid follows a curve that hooks back along itself, a point at the hook's tip; both faces
    on the edge then fill the hook (a SolidWorks DIN-rail mount at 1e-3: 48 segments with four triangles,
    check FAILED), or gmsh fails on the grid and its own curve mesh replaces it (here, before). The tip is
    dropped from the grid imposed on the faces, and a note says which edge turns back."""
    grid = cadedge.refine_shape(_faces_on_a_hooked_edge(), ald=ALD)
    (hooked,) = [e for e in grid.edges if len(e.faces) == 2]
    assert np.allclose(hooked.points[:, 0], [0.0, 1.0, 0.9, 2.0])  # the refiner follows the curve
    result = mesh_shape(grid)
    assert result.check.ok and len(result.failures) == 0
    assert any(n.startswith(f"edge {hooked.id}: the curve turns back on itself") for n in result.notes)
    assert not any("gmsh's own curve mesh" in n for n in result.notes)
    assert not np.any(np.all(np.isclose(result.nodes, [1.0, 0.0, 0.0]), axis=1))  # the tip is no node


def test_geo_export_meshes_in_gmsh(grids, tmp_path):
    out = tmp_path / "cyl.geo"
    result = mesh_shape(grids["cylinder"], output=out)
    assert result.check is None and out.exists() and out.with_suffix(".brep").exists()
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(out))
        gmsh.model.mesh.generate(2)
        _, _, tri = gmsh.model.mesh.getElements(2)
        assert sum(len(t) for t in tri) > 0
    finally:
        gmsh.finalize()


@pytest.mark.parametrize("suffix", [".msh", ".stl", ".vtk"])
def test_outputs_are_written(grids, tmp_path, suffix):
    out = tmp_path / f"cyl{suffix}"
    result = mesh_shape(grids["cylinder"], output=out)
    assert result.output == out and out.stat().st_size > 0
    assert [p.name for p in tmp_path.iterdir()] == [out.name]  # no temporary left behind
    if suffix == ".stl":
        read = trimesh.load(out, force="mesh")
        assert len(read.faces) == len(result.triangles)


def test_bad_arguments(grids, tmp_path):
    with pytest.raises(InputError):
        mesh_shape(grids["cylinder"], mode="quads")
    with pytest.raises(InputError):
        mesh_shape(grids["cylinder"], output=tmp_path / "x.obj")
    with pytest.raises(InputError):
        mesh_shape(FIXTURES / "helix_wire.step", ald=ALD)


def test_cadquery_shapes_with_poles_seams_and_apex():
    cq = pytest.importorskip("cadquery")
    cone = cq.Solid.makeCone(1.0, 0.0, 2.0, pnt=cq.Vector(0, -5, 0))
    shape = cq.Compound.makeCompound([cq.Workplane().box(2, 3, 4).faces(">Z").hole(1).edges("|Z").fillet(0.3).val(),
                                      cq.Workplane().sphere(1).translate((5, 0, 0)).val(), cone])
    result = mesh_shape(shape, ald=ALD)
    _assert_watertight(result)
    assert len(result.check.shells) == 3


@pytest.mark.parametrize("name", ["live-clones__gmsh__Kurbelwelle.stp", "LLNL__axom_data__sliced_cylinder.step"])
@pytest.mark.corpus
def test_corpus_solids(name):
    path = CORPUS / name
    if not path.exists():
        pytest.fail(f"corpus file missing: {path}")
    result = mesh_shape(path, ald=ALD)
    _assert_watertight(result)


def test_loose_edge_beside_a_solid_is_not_required_in_the_mesh():
    cq = pytest.importorskip("cadquery")
    box = cq.Workplane().box(1, 1, 1).val()
    wire = cq.Edge.makeCircle(0.5, pnt=cq.Vector(3, 0, 0))
    result = mesh_shape(cq.Compound.makeCompound([box, wire]), ald=ALD)
    assert result.ok, result.problems()
    assert len(result.check.shells) == 1 and result.check.shells[0].watertight


def test_long_boundary_segments_near_small_features_are_split(fixtures_dir):
    """The bracket's 24 mm boundary lines pass 7 mm from a finely meshed hole: without splitting them to
    the size field the plate's face fills with slivers (1.7 degrees); split to within 3x the size field, the minimum angle is above 10."""
    result = mesh_shape(fixtures_dir / "bracket.step", ald=1e-3)
    assert result.check.ok
    assert result.check.min_angle_deg > 10.0
    plain = cadedge.refine_shape(fixtures_dir / "bracket.step", ald=1e-3, max_growth=2.0)
    assert result.grid.segments > plain.segments  # split, never coarsened
    ends = {e.id: (e.points[0].tolist(), e.points[-1].tolist()) for e in plain.edges}
    assert all(ends[e.id] == (e.points[0].tolist(), e.points[-1].tolist()) for e in result.grid.edges)
