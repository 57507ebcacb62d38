"""Vertices of one face at one point are meshed as one node (cadedge.mesh.coincident, cadedge.occt.merge);
the tees where that happens mesh cleanly (real cadquery parts through STEP, real OCCT, real gmsh)."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from cadedge.mesh.coincident import coincident_vertices, meshed_as, point_tags
from cadedge.mesh.quality import flat_triangles
from cadedge.shapegrid import ShapeEdgeGrid, ShapeGrid, VertexGrid
from conftest import ROOT


def _edge(eid, vertices, faces, points):
    points = np.array(points, dtype=float)
    return ShapeEdgeGrid(id=eid, vertices=vertices, curve="Line", degenerate=False, closed=False, faces=faces,
                         params=np.linspace(0.0, 1.0, len(points)), points=points, ald_estimate=0.0)


def _grid(points, edges, tolerance=1e-7):
    vertices = [VertexGrid(id=i, point=np.array(p, dtype=float), tolerance=tolerance)
                for i, p in enumerate(points, start=1)]
    return ShapeGrid(source="t", units="mm", options={}, vertices=vertices, edges=edges, faces=3)


def test_vertices_of_one_face_at_one_point_go_to_the_lowest_id():
    """1 and 4 bound face 1 at one point (4 off by 5e-8, within tolerance): 4 is meshed as 1. 2 and 5
    coincide but share no face; 3 and 6 coincide but are the two ends of one edge: both pairs stay."""
    points = [(0, 0, 0), (5, 0, 0), (9, 0, 0), (5e-8, 0, 0), (5, 0, 0), (9, 0, 0)]
    edges = [_edge(1, (1, 2), [1], [(0, 0, 0), (5, 0, 0)]),
             _edge(2, (4, 3), [1], [(5e-8, 0, 0), (4, 1, 0), (9, 0, 0)]),
             _edge(3, (5, 6), [2], [(5, 0, 0), (9, 0, 0)]),
             _edge(4, (3, 6), [3], [(9, 0, 0), (9, 1, 0), (9, 0, 0)])]
    grid = _grid(points, edges)
    into = coincident_vertices(grid)
    assert into == {4: 1}
    assert point_tags(grid, into) == {1: 1, 2: 2, 3: 3, 4: 1, 5: 4, 6: 5}
    snapped = meshed_as(grid, into)
    assert np.array_equal(snapped.vertices[3].point, grid.vertices[0].point)
    assert np.array_equal(snapped.edges[1].points[0], grid.vertices[0].point)
    assert np.array_equal(snapped.edges[1].points[1:], grid.edges[1].points[1:])
    assert snapped.edges[0] is grid.edges[0]
    # beyond both tolerances: two points
    assert coincident_vertices(_grid(points, edges, tolerance=1e-8)) == {}


def _tee(name: str, folder) -> str:
    """The tee written as STEP and its path: read back, the run's face has two vertices at the tangent
    point (in memory, after the boolean, it has one)."""
    pytest.importorskip("cadquery")
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        import hard_models
    finally:
        sys.path.remove(str(ROOT / "scripts"))
    return str(hard_models.write_model(name, folder))


def test_merging_keeps_the_order_of_the_other_vertices_and_a_valid_face(tmp_path):
    """The tee's run face has its seam vertex (1) and the intersection loop's (6) at one point: merged,
    the shape has one vertex less, the rest in their order, and OCCT's check passes it."""
    import cadedge
    from cadedge.occt.merge import merge_vertices
    from cadedge.occt.topology import Topology
    from cadedge.occt.validity import face_problems

    grid = cadedge.refine_shape(_tee("tangent_inlet_tee", tmp_path), ald=1e-2)
    into = coincident_vertices(grid)
    assert into == {6: 1}
    merged, applied = merge_vertices(grid.shape, into)
    assert applied == into
    before, after = Topology(grid.shape), Topology(merged)
    assert len(after.vertices) == len(before.vertices) - 1
    tags, points = point_tags(grid, into), after.vertex_points()
    assert all(np.allclose(points[tags[v.id] - 1], v.point) for v in grid.vertices)
    assert not face_problems(merged, list(range(1, len(after.faces) + 1)))
    assert len(after.edges) == len(before.edges) and len(after.faces) == len(before.faces)


@pytest.mark.parametrize("name", ["tangent_inlet_tee", "pipe_tee_equal"])
def test_a_seam_through_the_tangent_point_of_a_tee_meshes_without_crack_or_sliver(name, tmp_path):
    """The run's seam passes where the branch touches the run: the two vertices there were two mesh
    nodes at one point (the check failed: a crack), with 0-degree triangles between them, and
    Frontal-Delaunay laid three seam nodes beside the point out as one flat triangle. One node now; the
    faces Frontal-Delaunay leaves flat are meshed by the next strategy."""
    from cadedge.mesh import mesh_shape

    result = mesh_shape(_tee(name, tmp_path), ald=1e-2, workers=1)
    assert result.ok, result.problems(verbose=True)
    assert result.check.duplicate_nodes == 0 and all(s.watertight for s in result.check.shells)
    assert result.check.missing_grid_nodes == 0
    assert not flat_triangles(result.nodes, result.triangles).any()
    assert result.report.min_angle >= 20.0
    assert any("meshed as one node: 6 with 1" in n for n in result.notes)


def test_the_geo_export_of_a_tee_has_one_point_where_its_run_face_had_two(tmp_path):
    """The ``.geo`` export merges the BREP it writes the same way, and its vertex size fields name the
    merged shape's points: gmsh meshes it without two nodes at one point or a flat triangle."""
    import gmsh

    import cadedge
    from cadedge.mesh.spacing_geo import write_geo

    grid = cadedge.refine_shape(_tee("tangent_inlet_tee", tmp_path), ald=1e-2)
    geo = write_geo(grid, tmp_path / "tee.geo")
    points = {int(t) for line in geo.read_text().splitlines() if "PointsList" in line
              for t in line.split("{")[1].split("}")[0].split(",")}
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(geo))
        assert len(gmsh.model.getEntities(0)) == len(grid.vertices) - 1
        assert points <= {t for _, t in gmsh.model.getEntities(0)}
        gmsh.model.mesh.generate(2)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        _, tri = gmsh.model.mesh.getElementsByType(2)
    finally:
        gmsh.finalize()
    nodes = np.asarray(coords).reshape(-1, 3)
    index = {int(t): k for k, t in enumerate(tags)}
    triangles = np.array([index[int(t)] for t in tri]).reshape(-1, 3)
    assert len(np.unique(nodes, axis=0)) == len(nodes)
    assert len(triangles) and not flat_triangles(nodes, triangles).any()
