"""The geometric exporters opened by the readers users have: meshio, vtk, pyvista, plyfile, trimesh.

Each check rebuilds every edge's chain of points from what the reader returns (segments or
polylines plus the edge ids the format carries) and compares it with the grid bit for bit, so
point counts, cell counts, shared vertex nodes, edge ids and full precision are all tested at once.
What a reader is documented to drop (docs/formats.md) is asserted too, so a change shows up here.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from cadedge.shapegrid import ShapeGrid
from test_exporters import make_grid

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"


@pytest.fixture
def grid() -> ShapeGrid:
    return make_grid()


@pytest.fixture(scope="module", params=["bracket.step", "sphere.step", "two_solids.step", "helix_wire.step"])
def real_grid(request) -> ShapeGrid:
    pytest.importorskip("OCP")
    import cadedge

    return cadedge.refine_shape(FIXTURES / request.param, ald=1e-3)


def live(grid: ShapeGrid) -> list:
    return [e for e in grid.edges if not e.degenerate]


def n_points(grid: ShapeGrid) -> int:
    """Shared nodes: one per B-rep vertex, plus the interior points of the non-degenerate edges."""
    return len(grid.vertices) + sum(len(e.params) - 2 for e in live(grid))


def check_segments(grid: ShapeGrid, points: np.ndarray, segments: np.ndarray, segment_edge: np.ndarray) -> None:
    """2-point cells with an edge id each chain up, edge by edge, into exactly the grid's polylines."""
    assert len(segments) == grid.segments and len(points) == n_points(grid)
    assert sorted(set(np.asarray(segment_edge).tolist())) == [e.id for e in live(grid)]
    for e in live(grid):
        mine = np.asarray(segments)[np.asarray(segment_edge) == e.id]
        assert np.array_equal(mine[1:, 0], mine[:-1, 1])
        chain = np.concatenate(([mine[0, 0]], mine[:, 1]))
        assert chain[0] == e.vertices[0] - 1 and chain[-1] == e.vertices[1] - 1  # point k - 1 = vertex k
        assert np.array_equal(np.asarray(points, dtype=float)[chain], e.points)


def check_polylines(grid: ShapeGrid, points: np.ndarray, chains: list[np.ndarray]) -> None:
    """One polyline per non-degenerate edge, in id order, on the shared nodes."""
    assert len(points) == n_points(grid) and len(chains) == len(live(grid))
    for e, chain in zip(live(grid), chains):
        assert chain[0] == e.vertices[0] - 1 and chain[-1] == e.vertices[1] - 1
        assert np.array_equal(np.asarray(points, dtype=float)[chain], e.points)


def meshio_segments(path: Path):
    meshio = pytest.importorskip("meshio")
    mesh = meshio.read(path)
    assert [c.type for c in mesh.cells] == ["line"]
    return mesh, mesh.cells[0].data, mesh.cell_data["edge_id"][0]


def pyvista_read(path: Path):
    pyvista = pytest.importorskip("pyvista")
    with warnings.catch_warnings():
        warnings.simplefilter("error", pyvista.InvalidMeshWarning)  # a layout pyvista flags is a bug
        return pyvista.read(path)


def vtk_chains(lines) -> list[np.ndarray]:
    """The point ids of each cell of a vtkCellArray (polylines, or 2-point cells)."""
    from vtk.util.numpy_support import vtk_to_numpy

    offsets = vtk_to_numpy(lines.GetOffsetsArray())
    connectivity = vtk_to_numpy(lines.GetConnectivityArray())
    return [connectivity[a:b] for a, b in zip(offsets[:-1], offsets[1:])]


@pytest.mark.parametrize("suffix", [".vtu", ".vtk", ".ply"])
def test_meshio_reads_line_cells_with_edge_ids(grid, tmp_path, suffix):
    path = tmp_path / f"g{suffix}"
    grid.write(path)
    mesh, segments, segment_edge = meshio_segments(path)
    check_segments(grid, mesh.points, segments, segment_edge)
    nv = len(grid.vertices)
    assert np.array_equal(mesh.point_data["vertex_id"][:nv], [v.id for v in grid.vertices])
    assert not mesh.point_data["vertex_id"][nv:].any() and not mesh.point_data["edge_id"][:nv].any()
    assert np.isnan(mesh.point_data["param"][:nv]).all()
    interior = np.concatenate([e.params[1:-1] for e in live(grid)])
    assert np.array_equal(mesh.point_data["param"][nv:], interior)


@pytest.mark.parametrize("suffix", [".vtu", ".vtk"])
def test_vtk_reads_line_cells_with_edge_ids(grid, tmp_path, suffix):
    vtk = pytest.importorskip("vtk")
    from vtk.util.numpy_support import vtk_to_numpy

    path = tmp_path / f"g{suffix}"
    grid.write(path)
    reader = vtk.vtkXMLUnstructuredGridReader() if suffix == ".vtu" else vtk.vtkUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    ugrid = reader.GetOutput()
    assert set(vtk_to_numpy(ugrid.GetCellTypesArray()).tolist()) == {vtk.VTK_LINE}
    segments = np.array(vtk_chains(ugrid.GetCells()))
    check_segments(grid, vtk_to_numpy(ugrid.GetPoints().GetData()), segments,
                   vtk_to_numpy(ugrid.GetCellData().GetArray("edge_id")))


def test_vtp_reads_back_with_vtk_and_pyvista(grid, tmp_path):
    vtk = pytest.importorskip("vtk")
    from vtk.util.numpy_support import vtk_to_numpy

    path = tmp_path / "g.vtp"
    grid.write(path)
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    poly = reader.GetOutput()
    check_polylines(grid, vtk_to_numpy(poly.GetPoints().GetData()), vtk_chains(poly.GetLines()))
    assert np.array_equal(vtk_to_numpy(poly.GetCellData().GetArray("edge_id")), [e.id for e in live(grid)])
    mesh = pyvista_read(path)
    assert (mesh.n_points, mesh.n_lines) == (n_points(grid), len(live(grid)))
    assert np.array_equal(mesh.cell_data["edge_id"], [e.id for e in live(grid)])
    assert np.array_equal(mesh.point_data["vertex_id"][: len(grid.vertices)], [v.id for v in grid.vertices])


def test_pyvista_reads_vtu_and_legacy_vtk(grid, tmp_path):
    for suffix in (".vtu", ".vtk"):
        grid.write(tmp_path / f"g{suffix}")
        mesh = pyvista_read(tmp_path / f"g{suffix}")
        assert (mesh.n_points, mesh.n_cells) == (n_points(grid), grid.segments)
        assert np.array_equal(np.sort(np.unique(mesh.cell_data["edge_id"])), [e.id for e in live(grid)])


def test_ply_opens_in_plyfile_vtk_and_trimesh(grid, tmp_path):
    plyfile = pytest.importorskip("plyfile")
    trimesh = pytest.importorskip("trimesh")
    path = tmp_path / "g.ply"
    grid.write(path)
    ply = plyfile.PlyData.read(str(path))
    assert [e.name for e in ply.elements] == ["vertex", "face"]
    v, f = ply["vertex"], ply["face"]
    points = np.column_stack([v["x"], v["y"], v["z"]])
    check_segments(grid, points, np.stack(f["vertex_indices"]), f["edge_id"])
    mesh = pyvista_read(path)  # vtk's PLY reader: the segments as 2-point polygons, float32, no ids
    assert (mesh.n_points, mesh.n_cells) == (n_points(grid), grid.segments)
    assert np.array_equal(mesh.points, points.astype(np.float32))
    loaded = trimesh.load(path)  # trimesh: the points only (its PLY lines come from `edge` elements)
    assert np.array_equal(loaded.vertices, points) and len(loaded.faces) == 0


def test_obj_polylines_in_vtk_points_in_trimesh_and_meshio(grid, tmp_path):
    path = tmp_path / "g.obj"
    grid.write(path)
    groups = [line.split()[1] for line in path.read_text().splitlines() if line.startswith("o ")]
    assert groups == [f"edge_{e.id}" for e in live(grid)]
    mesh = pyvista_read(path)  # vtkOBJReader keeps `l` records as polylines, in file (edge id) order
    check_polylines(grid, mesh.points, vtk_chains(mesh.GetLines()))
    trimesh = pytest.importorskip("trimesh")
    cloud = trimesh.load(path)  # trimesh and meshio parse faces only: the lines are dropped
    assert isinstance(cloud, trimesh.PointCloud) and np.array_equal(cloud.vertices, mesh.points)
    meshio = pytest.importorskip("meshio")
    assert len(meshio.read(path).cells) == 0


def test_trimesh_path_from_meshio_lines(grid, tmp_path):
    """The recipe in docs/formats.md for a trimesh Path3D: meshio's line cells to trimesh.load_path."""
    trimesh = pytest.importorskip("trimesh")
    grid.write(tmp_path / "g.vtu")
    mesh, _, _ = meshio_segments(tmp_path / "g.vtu")
    path = trimesh.load_path(mesh.points[mesh.cells_dict["line"]])
    assert math.isclose(path.length, sum(e.length for e in live(grid)), rel_tol=1e-12)


def test_real_models_in_every_reader(real_grid, tmp_path):
    for suffix in (".vtu", ".vtk", ".ply"):
        real_grid.write(tmp_path / f"r{suffix}")
        mesh, segments, segment_edge = meshio_segments(tmp_path / f"r{suffix}")
        check_segments(real_grid, mesh.points, segments, segment_edge)
    real_grid.write(tmp_path / "r.vtp")
    mesh = pyvista_read(tmp_path / "r.vtp")
    check_polylines(real_grid, mesh.points, vtk_chains(mesh.GetLines()))
    real_grid.write(tmp_path / "r.obj")
    mesh = pyvista_read(tmp_path / "r.obj")
    check_polylines(real_grid, mesh.points, vtk_chains(mesh.GetLines()))
