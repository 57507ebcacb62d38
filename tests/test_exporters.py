"""Exporters: every format written from a hand-built ShapeGrid and read back by a real reader
(jsonschema, gmsh here; meshio, vtk, pyvista, trimesh and plyfile in tests/test_exporters_readers.py),
plus atomicity and suffix errors. Real STEP fixtures are in tests/test_cli_refine.py."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cadedge.errors import CadedgeError, InputError
from cadedge.exporters import FORMATS, write
from cadedge.exporters import json as json_exporter
from cadedge.shapegrid import ShapeEdgeGrid, ShapeGrid, VertexGrid


def _arc(u: np.ndarray) -> np.ndarray:
    return np.column_stack([1.0 + 0.3 * np.sin(np.pi * u), u * (0.1 + 0.2), np.zeros_like(u)])


def make_grid() -> ShapeGrid:
    """Three vertices (coordinates that are not short decimals), an open line, an arc, a closed circle
    on vertex 1, and a degenerate edge on vertex 3; edge ends are the vertex points bit for bit."""
    p1 = np.array([0.0, 0.0, 1.0 / 3.0])
    p2 = _arc(np.array([0.0]))[0]
    p3 = _arc(np.array([1.0]))[0]
    u_arc = np.linspace(0.0, 1.0, 6)
    arc = _arc(u_arc)
    arc[0], arc[-1] = p2, p3
    t = np.linspace(0.0, 2 * np.pi, 9)
    circle = p1 + 0.25 * np.column_stack([np.cos(t) - 1.0, np.sin(t), np.zeros_like(t)])
    circle[0] = circle[-1] = p1
    edges = [
        ShapeEdgeGrid(1, (1, 2), "Line", False, False, [1], np.array([0.0, 0.5, 1.0]),
                      np.array([p1, (p1 + p2) / 2, p2]), 0.0),
        ShapeEdgeGrid(2, (2, 3), "BSplineCurve", False, False, [1, 2], u_arc, arc, 7.5e-4),
        ShapeEdgeGrid(3, (1, 1), "Circle", False, True, [2], t, circle, 9.1e-4),
        ShapeEdgeGrid(4, (3, 3), "Line", True, False, [2], np.array([0.0, 1.0]), np.array([p3, p3]), 0.0),
    ]
    vertices = [VertexGrid(1, p1), VertexGrid(2, p2), VertexGrid(3, p3)]
    for v in vertices:
        ends = [e.spacing[0] for e in edges if not e.degenerate and e.vertices[0] == v.id]
        ends += [e.spacing[1] for e in edges if not e.degenerate and e.vertices[1] == v.id]
        v.spacing = min(ends)
    return ShapeGrid(source="hand.step", units="mm",
                     options={"ald": 1e-3, "min_length": None, "max_length": 2.0, "max_growth": 1.5},
                     vertices=vertices, edges=edges, faces=2, seconds=0.25)


@pytest.fixture
def grid() -> ShapeGrid:
    return make_grid()


def test_json_matches_contract_and_validates(grid, tmp_path):
    path = tmp_path / "g.json"
    write(grid, path)
    doc = json.loads(path.read_text())
    json_exporter.validate(doc)
    assert list(doc) == ["schema", "source", "units", "options", "vertices", "edges", "summary"]
    assert doc["schema"] == "cadedge.edgegrid/1" and doc["source"] == "hand.step" and doc["units"] == "mm"
    assert doc["options"] == {"ald": 1e-3, "min_length": None, "max_length": 2.0, "max_growth": 1.5}
    assert doc["summary"] == {"edges": 4, "segments": 2 + 5 + 8 + 0, "max_ald_estimate": 9.1e-4, "seconds": 0.25}
    e2 = doc["edges"][1]
    assert set(e2) == {"id", "vertices", "curve", "degenerate", "closed", "faces", "params", "points", "length",
                       "ald_estimate", "spacing"}
    assert e2["vertices"] == [2, 3] and e2["faces"] == [1, 2] and e2["curve"] == "BSplineCurve"
    assert e2["length"] == grid.edges[1].length and e2["spacing"] == list(grid.edges[1].spacing)
    assert doc["edges"][3]["degenerate"] is True and doc["edges"][3]["length"] == 0.0
    assert doc["edges"][2]["closed"] is True


def test_json_round_trip_is_bit_exact(grid, tmp_path):
    path = tmp_path / "g.json"
    grid.write(path)
    doc = json.loads(path.read_text())
    for e, de in zip(grid.edges, doc["edges"]):
        assert np.array_equal(np.array(de["points"]), e.points)
        assert np.array_equal(np.array(de["params"]), e.params)
    vpoint = {v["id"]: v["point"] for v in doc["vertices"]}
    for de in doc["edges"]:
        assert de["points"][0] == vpoint[de["vertices"][0]]
        assert de["points"][-1] == vpoint[de["vertices"][1]]
    assert vpoint[1][2] == 1.0 / 3.0


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d.pop("units"), "units"),
    (lambda d: d.update(schema="cadedge.edgegrid/2"), "schema"),
    (lambda d: d["edges"][0]["points"].pop(), "params but"),
    (lambda d: d["edges"][1]["points"][0].pop(), "edges/1/points/0"),
    (lambda d: d["edges"][0].update(vertices=[1, 9]), "unknown vertex"),
    (lambda d: d["edges"][0].update(params=[0.0, 1.0, 0.5]), "not increasing"),
    (lambda d: d["vertices"].reverse(), "vertex ids"),
    (lambda d: d["edges"][0].update(extra=1), "extra"),
    (lambda d: d["options"].update(ald=0), "options/ald"),
])
def test_validate_rejects_broken_documents(grid, mutate, message):
    doc = json_exporter.to_document(grid)
    json_exporter.validate(doc)
    mutate(doc)
    with pytest.raises(InputError, match=message):
        json_exporter.validate(doc)


def test_schema_is_valid_draft_2020_12():
    jsonschema = pytest.importorskip("jsonschema")
    schema = json_exporter.schema()
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    jsonschema.Draft202012Validator.check_schema(schema)


def test_csv_one_row_per_grid_point(grid, tmp_path):
    path = tmp_path / "g.csv"
    write(grid, path)
    lines = path.read_text().splitlines()
    assert lines[0] == "edge_id,index,param,x,y,z"
    rows = [line.split(",") for line in lines[1:]]
    assert len(rows) == sum(len(e.params) for e in grid.edges)
    table = np.array(rows, dtype=float)
    for e in grid.edges:
        mine = table[table[:, 0] == e.id]
        assert np.array_equal(mine[:, 1], np.arange(len(e.params)))
        assert np.array_equal(mine[:, 2], e.params) and np.array_equal(mine[:, 3:], e.points)


@pytest.fixture
def gmsh_session():
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(["cadedge-test"], readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        yield gmsh
    finally:
        gmsh.finalize()


def test_msh_loads_in_gmsh_with_cadedge_tags(grid, tmp_path, gmsh_session):
    gmsh = gmsh_session
    path = tmp_path / "g.msh"
    write(grid, path)
    gmsh.open(str(path))
    assert sorted(tag for _, tag in gmsh.model.getEntities(0)) == [1, 2, 3]
    assert sorted(tag for _, tag in gmsh.model.getEntities(1)) == [1, 2, 3, 4]
    for e in grid.edges:
        if e.vertices[0] != e.vertices[1]:  # gmsh reports no boundary for closed curves
            assert [t for _, t in gmsh.model.getBoundary([(1, e.id)], oriented=False)] == list(e.vertices)
        if e.degenerate:
            continue
        tags, coords, _ = gmsh.model.mesh.getNodes(1, e.id, includeBoundary=True)
        assert len(tags) == len(e.params)
        xyz = coords.reshape(-1, 3)
        # interior nodes come first, then the boundary (vertex) nodes
        assert np.array_equal(xyz[: len(e.params) - 2], e.points[1:-1])
        types, _, nodes = gmsh.model.mesh.getElements(1, e.id)
        assert list(types) == [1] and len(nodes[0]) == 2 * (len(e.params) - 1)
        chain = nodes[0].reshape(-1, 2)
        assert chain[0, 0] == e.vertices[0] and chain[-1, 1] == e.vertices[1]
        assert np.array_equal(chain[1:, 0], chain[:-1, 1])
    for v in grid.vertices:
        tags, coords, _ = gmsh.model.mesh.getNodes(0, v.id)
        assert list(tags) == [v.id] and np.array_equal(coords, v.point)


def test_geo_opens_in_gmsh_and_meshes_back_to_the_grid(grid, tmp_path, gmsh_session):
    gmsh = gmsh_session
    path = tmp_path / "g.geo"
    write(grid, path)
    gmsh.open(str(path))
    for v in grid.vertices:
        assert np.array_equal(gmsh.model.getValue(0, v.id, []), v.point)
    gmsh.model.mesh.generate(1)
    groups = dict((tag, dim) for dim, tag in gmsh.model.getPhysicalGroups(1))
    live = [e for e in grid.edges if not e.degenerate]
    assert sorted(groups) == [e.id for e in live]
    for e in live:
        assert gmsh.model.getPhysicalName(1, e.id) == f"edge {e.id}"
        segments = gmsh.model.getEntitiesForPhysicalGroup(1, e.id)
        assert len(segments) == e.segments
        count = sum(len(gmsh.model.mesh.getElements(1, int(s))[1][0]) for s in segments)
        assert count == e.segments
        tags, _ = gmsh.model.mesh.getNodesForPhysicalGroup(1, e.id)
        assert len(tags) == len(np.unique(e.points, axis=0))


@pytest.mark.parametrize("suffix", sorted(FORMATS))
def test_every_format_writes_and_is_nonempty(grid, tmp_path, suffix):
    path = tmp_path / f"g{suffix.upper()}"  # suffix matching is case-insensitive
    write(grid, path)
    assert path.stat().st_size > 100
    assert [p.name for p in tmp_path.iterdir()] == [path.name]


def test_format_overrides_suffix(grid, tmp_path):
    path = tmp_path / "grid.out"
    write(grid, path, format="csv")
    assert path.read_text().startswith("edge_id,")
    write(grid, path, format=".json")
    json_exporter.validate(json.loads(path.read_text()))


def test_unknown_suffix_names_path_and_supported(grid, tmp_path):
    path = tmp_path / "grid.stl"
    with pytest.raises(InputError) as info:
        write(grid, path)
    message = str(info.value)
    assert str(path) in message and ".stl" in message
    assert all(s in message for s in FORMATS)
    assert not path.exists()


def test_failing_export_leaves_no_file(grid, tmp_path):
    path = tmp_path / "g.json"
    path.write_text("previous")
    grid.edges[1].points[2, 0] = np.nan
    with pytest.raises(CadedgeError, match="edge 2 points"):
        write(grid, path)
    assert path.read_text() == "previous"
    assert [p.name for p in tmp_path.iterdir()] == ["g.json"]


def test_unwritable_target_is_input_error(grid, tmp_path):
    path = tmp_path / "missing-folder" / "g.csv"
    with pytest.raises(InputError, match="missing-folder"):
        write(grid, path)
    assert not path.parent.exists()


FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"


@pytest.fixture(scope="module", params=["bracket.step", "sphere.step", "two_solids.step", "helix_wire.step"])
def real_grid(request) -> ShapeGrid:
    pytest.importorskip("OCP")
    import cadedge

    return cadedge.refine_shape(FIXTURES / request.param, ald=1e-3)


def test_real_json_validates_and_keeps_shared_vertices_bit_identical(real_grid, tmp_path):
    path = tmp_path / "real.json"
    real_grid.write(path)
    doc = json.loads(path.read_text())
    json_exporter.validate(doc)
    assert doc["source"] == real_grid.source and len(doc["edges"]) == len(real_grid.edges)
    vpoint = {v["id"]: v["point"] for v in doc["vertices"]}
    for e, de in zip(real_grid.edges, doc["edges"]):
        assert np.array_equal(np.array(de["points"]), e.points) and np.array_equal(np.array(de["params"]), e.params)
        assert de["points"][0] == vpoint[de["vertices"][0]] and de["points"][-1] == vpoint[de["vertices"][1]]
    assert doc["summary"]["segments"] == sum(len(e["params"]) - 1 for e in doc["edges"] if not e["degenerate"])


def test_real_msh_is_conforming_in_gmsh(real_grid, tmp_path, gmsh_session):
    gmsh = gmsh_session
    path = tmp_path / "real.msh"
    real_grid.write(path)
    gmsh.open(str(path))
    live = [e for e in real_grid.edges if not e.degenerate]
    for e in live:
        tags, _, _ = gmsh.model.mesh.getNodes(1, e.id, includeBoundary=True)
        assert len(set(tags.tolist())) == len(np.unique(e.points, axis=0))  # closed: boundary node listed twice
    all_tags, _, _ = gmsh.model.mesh.getNodes()
    interior = sum(len(e.params) - 2 for e in live)
    assert len(all_tags) == len(real_grid.vertices) + interior  # shared vertex nodes appear once


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")
@pytest.mark.parametrize("suffix", [".json", ".csv"])
def test_text_formats_round_trip_any_float(tmp_path, suffix):
    """Any finite float64, subnormals and extremes included, survives the text formats bit for bit."""
    pytest.importorskip("hypothesis")
    from hypothesis import given, settings
    from hypothesis import strategies as st

    finite = st.floats(allow_nan=False, allow_infinity=False, width=64)

    @settings(max_examples=60, deadline=None, database=None)
    @given(st.lists(st.tuples(finite, finite, finite), min_size=2, max_size=6))
    def check(coords):
        grid = make_grid()
        edge = grid.edges[0]
        edge.points = np.array(coords, dtype=float)
        edge.params = np.arange(len(coords), dtype=float) / 7.0
        grid.vertices[0].point, grid.vertices[1].point = edge.points[0], edge.points[-1]
        path = tmp_path / f"h{suffix}"
        try:
            write(grid, path)
        except CadedgeError:  # the polyline length overflowed to inf: refused, never written wrong
            assert not np.isfinite(edge.length)
            return
        if suffix == ".json":
            doc = json.loads(path.read_text())
            assert np.array_equal(np.array(doc["edges"][0]["points"]), edge.points)
            assert doc["vertices"][0]["point"] == doc["edges"][0]["points"][0]
        else:
            rows = np.array([r.split(",") for r in path.read_text().splitlines()[1:]], dtype=float)
            assert np.array_equal(rows[rows[:, 0] == 1][:, 3:], edge.points)

    check()
