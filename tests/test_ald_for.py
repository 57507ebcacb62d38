"""Local targets: ``refine_shape(..., ald_for=...)`` and ``cadedge refine --ald-edge/--ald-face``.

Each edge meets its own target against OCCT's length of the edge, the finest setting reaching an edge
wins, a face means its edges, every kind of key (cadquery, build123d, TopoDS, ids) resolves to the
same edges, other edges are untouched, shared vertices stay bit-identical, the output records the
settings, and bad keys or targets are one clear InputError (exit 2 on the command line).
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.BRepAdaptor import BRepAdaptor_Curve  # noqa: E402
from OCP.GCPnts import GCPnts_AbscissaPoint  # noqa: E402
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE  # noqa: E402
from OCP.TopExp import TopExp, TopExp_Explorer  # noqa: E402
from cadedge.occt.compat import TopTools_IndexedMapOfShape  # noqa: E402

import cadedge  # noqa: E402
from cadedge.cli import main  # noqa: E402
from cadedge.errors import InputError  # noqa: E402
from cadedge.exporters.json import to_document, validate  # noqa: E402
from cadedge.occt.topology import Topology  # noqa: E402
from cadedge.shapegrid import recorded_targets  # noqa: E402
from conftest import FIXTURES  # noqa: E402

BRACKET = FIXTURES / "bracket.step"
LENGTH_TOL = 1e-12


def occt_length(edge) -> float:
    return GCPnts_AbscissaPoint.Length_s(BRepAdaptor_Curve(edge), LENGTH_TOL)


def face_id(shape, face) -> int:
    faces = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_FACE, faces)
    return faces.FindIndex(face)


def expected_targets(topo: Topology, ald: float, edges: dict[int, float], faces: dict[int, float]) -> list[float]:
    """The finest of ``ald`` and every edge or face setting reaching each edge, from the topology alone."""
    return [min([ald, edges.get(i + 1, 1.0)] + [faces.get(f, 1.0) for f in topo.edge_faces[i]])
            for i in range(len(topo.edges))]


def check_targets(grid: cadedge.ShapeGrid, targets: list[float]) -> None:
    """Every edge meets its own target against OCCT's length; ends bit-identical to the vertices."""
    topo = Topology(grid.shape)
    vpts = [np.array(BRep_Tool.Pnt_s(v).Coord()) for v in topo.vertices]
    over = []
    for i, (e, target) in enumerate(zip(grid.edges, targets)):
        v1, v2 = e.vertices
        assert np.array_equal(e.points[0], vpts[v1 - 1]) and np.array_equal(e.points[-1], vpts[v2 - 1])
        if e.degenerate:
            continue
        assert e.ald_estimate <= target
        achieved = 1.0 - e.length / occt_length(topo.edges[i])
        if achieved > target * (1 + 1e-9):
            over.append((e.id, e.curve, target, achieved))
    assert not over, f"edges over their own target (id, curve, target, achieved): {over}"


def assert_same_grid(a, b) -> None:
    assert np.array_equal(a.params, b.params) and np.array_equal(a.points, b.points)


@pytest.fixture(scope="module")
def plate():
    cq = pytest.importorskip("cadquery")
    return (cq.Workplane("XY").box(40, 30, 8).faces(">Z").workplane().hole(12).edges("|Z").fillet(4))


@pytest.fixture(scope="module")
def plate_base(plate):
    return cadedge.refine_shape(plate, ald=1e-3)


@pytest.fixture(scope="module")
def bd_part():
    bd = pytest.importorskip("build123d")
    with bd.BuildPart() as part:
        bd.Box(60, 20, 10)
        bd.Cylinder(radius=6, height=10, mode=bd.Mode.SUBTRACT)
        bd.fillet(part.edges().filter_by(bd.Axis.Z), radius=3)
    return part.part


def test_cadquery_face_selection_refines_its_edges_only(plate, plate_base):
    top = plate.faces(">Z")
    grid = cadedge.refine_shape(plate, ald=1e-3, ald_for={top: 1e-5})
    topo = Topology(grid.shape)
    fid = face_id(grid.shape, top.val().wrapped)
    targets = expected_targets(topo, 1e-3, {}, {fid: 1e-5})
    check_targets(grid, targets)
    local = [i for i, t in enumerate(targets) if t == 1e-5]
    assert local and all(grid.edges[i].curve == "Line" or grid.edges[i].segments > plate_base.edges[i].segments
                         for i in local)
    for i, t in enumerate(targets):  # the other edges are exactly what the global target gives
        if t == 1e-3:
            assert_same_grid(grid.edges[i], plate_base.edges[i])
    assert grid.options["ald_for"] == [{"kind": "face", "id": fid, "ald": 1e-5}]
    assert grid.options["ald"] == 1e-3 and not grid.warnings


def test_cadquery_edge_selection_and_shape_keys(plate, plate_base):
    circles = plate.faces(">Z").edges("%CIRCLE")  # a Workplane holding several edges
    hole = max(circles.vals(), key=lambda e: e.radius())  # a cadquery Edge: the hole
    grid = cadedge.refine_shape(plate, ald=1e-3, ald_for={circles: 1e-4, hole: 1e-6})
    emap = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(grid.shape, TopAbs_EDGE, emap)
    ids = {emap.FindIndex(e.wrapped): 1e-4 for e in circles.vals()}
    ids[emap.FindIndex(hole.wrapped)] = 1e-6
    assert 0 not in ids and len(ids) == len(circles.vals())
    check_targets(grid, expected_targets(Topology(grid.shape), 1e-3, ids, {}))
    assert grid.options["ald_for"] == [{"kind": "edge", "id": k, "ald": ids[k]} for k in sorted(ids)]
    for i, e in enumerate(grid.edges):
        if i + 1 not in ids:
            assert_same_grid(e, plate_base.edges[i])


def test_build123d_edge_and_face_keys_finest_wins(bd_part):
    bd = pytest.importorskip("build123d")
    hole = bd_part.edges().filter_by(bd.GeomType.CIRCLE).sort_by(bd.Axis.Z)[-1]
    top = bd_part.faces().sort_by(bd.Axis.Z)[-1]
    fillet_face = bd_part.faces().filter_by(bd.GeomType.CYLINDER)[0]
    grid = cadedge.refine_shape(bd_part, ald=1e-3, ald_for={top: 1e-4, hole: 1e-6, fillet_face: 1e-5})
    emap = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(grid.shape, TopAbs_EDGE, emap)
    hole_id = emap.FindIndex(hole.wrapped)
    faces = {face_id(grid.shape, top.wrapped): 1e-4, face_id(grid.shape, fillet_face.wrapped): 1e-5}
    targets = expected_targets(Topology(grid.shape), 1e-3, {hole_id: 1e-6}, faces)
    assert targets[hole_id - 1] == 1e-6 and 1e-5 in targets and 1e-4 in targets
    check_targets(grid, targets)
    # the same settings by TopoDS shape (one reversed: orientation does not matter) and by id
    fillet_id = face_id(grid.shape, fillet_face.wrapped)
    same = cadedge.refine_shape(bd_part, ald=1e-3, ald_for={top.wrapped: 1e-4, hole.wrapped.Reversed(): 1e-6,
                                                             ("face", fillet_id): 1e-5})
    by_id = cadedge.refine_shape(bd_part, ald=1e-3, ald_for={("edge", hole_id): 1e-6,
                                                              **{("face", f): v for f, v in faces.items()}})
    for a, b, c in zip(grid.edges, same.edges, by_id.edges):
        assert_same_grid(a, b)
        assert_same_grid(a, c)
    assert grid.options["ald_for"] == same.options["ald_for"] == by_id.options["ald_for"]


def test_step_ids_finest_wins_where_settings_meet():
    topo = Topology(cadedge.refine_shape(BRACKET, ald=1e-2).shape)
    edges, faces = {9: 1e-4, 5: 1e-5}, {1: 1e-4, 3: 1e-6}
    assert 1 in topo.edge_faces[8] and 3 in topo.edge_faces[8]  # edge 9 bounds faces 1 and 3
    ald_for = {**{("edge", np.int64(k)): v for k, v in edges.items()}, **{("face", k): v for k, v in faces.items()}}
    grid = cadedge.refine_shape(BRACKET, ald=1e-3, ald_for=ald_for)
    targets = expected_targets(topo, 1e-3, edges, faces)
    assert targets[8] == 1e-6 and targets[4] == 1e-5  # two faces meet at edge 9; an edge finer than its face
    check_targets(grid, targets)
    assert grid.options["ald_for"] == [{"kind": "edge", "id": 5, "ald": 1e-5}, {"kind": "edge", "id": 9, "ald": 1e-4},
                                       {"kind": "face", "id": 1, "ald": 1e-4}, {"kind": "face", "id": 3, "ald": 1e-6}]
    read = recorded_targets(grid)  # read back from the grid's options, as the mesher does
    assert [read[e.id] for e in grid.edges] == list(targets)


def test_a_coarser_setting_changes_nothing_and_says_so():
    base = cadedge.refine_shape(BRACKET, ald=1e-3)
    grid = cadedge.refine_shape(BRACKET, ald=1e-3, ald_for={("edge", 13): 1e-2})
    for a, b in zip(base.edges, grid.edges):
        assert_same_grid(a, b)
    assert grid.warnings == ["local ald for edge 13: 0.01 is coarser than ald 0.001, and the finest target wins, "
                             "so it changes nothing"]


def test_the_same_edge_named_twice_keeps_the_finest():
    shape = cadedge.refine_shape(BRACKET, ald=1e-2).shape
    explorer = TopExp_Explorer(shape, TopAbs_EDGE)  # generic TopoDS_Shape items, in MapShapes order
    first = explorer.Current()
    grid = cadedge.refine_shape(shape, ald=1e-3, ald_for={first: 1e-5, ("edge", 1): 1e-4})
    assert grid.options["ald_for"] == [{"kind": "edge", "id": 1, "ald": 1e-5}]


def test_max_growth_keeps_each_edge_within_its_target(plate):
    grid = cadedge.refine_shape(plate, ald=1e-3, max_growth=1.5, ald_for={plate.faces(">Z"): 1e-5})
    fid = face_id(grid.shape, plate.faces(">Z").val().wrapped)
    check_targets(grid, expected_targets(Topology(grid.shape), 1e-3, {}, {fid: 1e-5}))


def test_json_records_the_settings_and_validates(tmp_path, plate):
    grid = cadedge.refine_shape(plate, ald=1e-3, ald_for={plate.faces(">Z"): 1e-4, ("edge", 1): 1e-4})
    out = tmp_path / "p.json"
    grid.write(out)
    doc = json.loads(out.read_text())
    validate(doc)
    assert doc["options"]["ald_for"] == grid.options["ald_for"]
    assert {r["kind"] for r in doc["options"]["ald_for"]} == {"edge", "face"}
    plain = to_document(cadedge.refine_shape(plate, ald=1e-3))
    assert "ald_for" not in plain["options"]  # unchanged output when no local target is given
    doc["options"]["ald_for"][0]["id"] = len(doc["edges"]) + 1
    with pytest.raises(InputError, match="unknown edge"):
        validate(doc)
    doc["options"]["ald_for"][0].update(id=1, ald=2.0)
    with pytest.raises(InputError, match="ald_for"):
        validate(doc)


@pytest.mark.parametrize("ald_for, message", [
    ({("edge", 37): 1e-4}, "bracket.step: local ald for edge 37: no such edge (the shape has edges 1 to 36)"),
    ({("face", 15): 1e-4}, "bracket.step: local ald for face 15: no such face (the shape has faces 1 to 14)"),
    ({("face", 0): 1e-4}, "ald_for key ('face', 0): ids start at 1"),
    ({3: 1e-4}, "ald_for key 3: a bare integer could be an edge or a face id; write ('edge', 3) or ('face', 3)"),
    ({("vertex", 1): 1e-4}, "an id key is ('edge', N) or ('face', N)"),
    ({("edge", 1.0): 1e-4}, "an id key is ('edge', N) or ('face', N)"),
    ({("edge", True): 1e-4}, "an id key is ('edge', N) or ('face', N)"),
    ({"edge 3": 1e-4}, "ald_for key 'edge 3': expected an edge or a face"),
    ({("edge", 1): 0}, "ald_for key ('edge', 1): ald must be positive and below 1, got 0"),
    ({("edge", 1): 1.0}, "ald_for key ('edge', 1): ald must be positive"),
    ({("edge", 1): 1e-12}, "ald_for key ('edge', 1): ald 1e-12 is below 1e-9, the smallest target"),
    ({("edge", 1): -1e-3}, "ald must be positive"),
    ({("edge", 1): math.nan}, "ald must be positive"),
    ({("edge", 1): "fine"}, "ald_for key ('edge', 1): ald must be a number, got 'fine'"),
    ({("edge", 1): None}, "ald must be a number, got None"),
    ({("edge", 1): True}, "ald must be a number, got True"),
    ([(("edge", 1), 1e-4)], "ald_for must be a mapping from edges or faces to their ald, got a list"),
])
def test_bad_keys_and_targets(ald_for, message):
    with pytest.raises(InputError) as info:
        cadedge.refine_shape(BRACKET, ald=1e-3, ald_for=ald_for)
    assert message in str(info.value) and "\n" not in str(info.value)


def test_targets_are_checked_before_the_file_is_read(tmp_path):
    with pytest.raises(InputError, match="ald must be positive"):
        cadedge.refine_shape(tmp_path / "missing.step", ald_for={("edge", 1): 5})


def test_shape_keys_not_in_the_shape(plate, bd_part):
    cq = pytest.importorskip("cadquery")
    bd = pytest.importorskip("build123d")
    other = cq.Workplane("XY").box(1, 1, 1)
    with pytest.raises(InputError, match=r"<cadquery Edge>: not an edge of the shape being refined"):
        cadedge.refine_shape(plate, ald_for={other.edges().val(): 1e-4})
    moved = bd_part.moved(bd.Location((5, 0, 0)))  # same geometry elsewhere: different edges
    with pytest.raises(InputError, match=r"<build123d Face>: not a face of the shape being refined"):
        cadedge.refine_shape(bd_part, ald_for={moved.faces()[0]: 1e-4})
    with pytest.raises(InputError, match=r"<TopoDS_Edge>: not an edge"):
        cadedge.refine_shape(BRACKET, ald_for={plate.edges().val().wrapped: 1e-4})  # a file: ids only
    with pytest.raises(InputError, match=r"<build123d Solid>: expected an edge or a face, got a solid"):
        cadedge.refine_shape(bd_part, ald_for={bd_part.solids()[0]: 1e-4})
    with pytest.raises(InputError, match=r"<cadquery Workplane>: the selection holds no edges or faces"):
        cadedge.refine_shape(plate, ald_for={cq.Workplane("XY"): 1e-4})
    with pytest.raises(InputError, match=r"<build123d Wire>: expected an edge or a face, got a wire"):
        cadedge.refine_shape(bd_part, ald_for={bd_part.wires()[0]: 1e-4})
    with pytest.raises(InputError, match=r"<builtins object>: expected an edge or a face"):
        cadedge.refine_shape(bd_part, ald_for={object(): 1e-4})
    with pytest.raises(InputError, match=r"ald_for key <cadquery Workplane>: ald must be positive and below 1"):
        cadedge.refine_shape(plate, ald_for={plate.faces(">Z"): 2})


def test_face_ids_on_a_shape_without_faces():
    with pytest.raises(InputError, match=r"no such face \(the shape has no faces\)"):
        cadedge.refine_shape(FIXTURES / "helix_wire.step", ald_for={("face", 1): 1e-4})


def test_readme_local_targets_example_runs(tmp_path, monkeypatch, capsys):
    """The README's "Local targets" block, run after the cadquery example it continues."""
    pytest.importorskip("cadquery")
    from test_readme_examples import README, examples

    code = re.search(r"```python\n(# local targets\n.*?)```", README.read_text(encoding="utf-8"), re.S).group(1)
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__main__"}
    exec(compile(examples()["cadquery"], "README.md:cadquery", "exec"), namespace)
    exec(compile(code, "README.md:local targets", "exec"), namespace)
    fine, plate = namespace["fine"], namespace["plate"]
    fid = face_id(fine.shape, plate.faces(">Z").val().wrapped)
    assert fine.options["ald_for"] == [{"kind": "edge", "id": 1, "ald": 1e-4},
                                       {"kind": "face", "id": fid, "ald": 1e-5}]
    check_targets(fine, expected_targets(Topology(fine.shape), 1e-3, {1: 1e-4}, {fid: 1e-5}))
    assert str(fine.options["ald_for"]) in capsys.readouterr().out


def test_cli_ald_edge_and_face(tmp_path, capsys):
    out = tmp_path / "b.json"
    argv = ["refine", str(BRACKET), "--ald", "1e-3", "--ald-edge", "9=1e-4", "--ald-face", "3=1e-6",
            "--ald-edge", "5=1e-5", "--ald-edge", "9=1e-5", "-o", str(out), "--quiet"]
    assert main(argv) == 0
    assert capsys.readouterr().err == ""
    doc = json.loads(out.read_text())
    validate(doc)
    assert doc["options"]["ald_for"] == [{"kind": "edge", "id": 5, "ald": 1e-5},
                                         {"kind": "edge", "id": 9, "ald": 1e-5},
                                         {"kind": "face", "id": 3, "ald": 1e-6}]
    api = cadedge.refine_shape(BRACKET, ald=1e-3, ald_for={("edge", 5): 1e-5, ("edge", 9): 1e-5, ("face", 3): 1e-6})
    for e, a in zip(doc["edges"], api.edges):
        assert np.array_equal(np.array(e["points"]), a.points)
    targets = expected_targets(Topology(api.shape), 1e-3, {5: 1e-5, 9: 1e-5}, {3: 1e-6})
    check_targets(api, targets)


@pytest.mark.parametrize("extra, message", [
    (["--ald-edge", "3"], "--ald-edge expects ID=EPS, ID a positive edge id (as listed by cadedge info), got '3'"),
    (["--ald-face", "x=1e-4"], "--ald-face expects ID=EPS, ID a positive face id"),
    (["--ald-edge", "0=1e-4"], "--ald-edge expects ID=EPS"),
    (["--ald-edge=-2=1e-4"], "--ald-edge expects ID=EPS"),
    (["--ald-edge", "٣=1e-4"], "--ald-edge expects ID=EPS"),  # a non-ASCII digit
    (["--ald-edge", "3=2"], "--ald-edge 3: ald must be positive and below 1, got '2'"),
    (["--ald-face", "3=abc"], "--ald-face 3: ald must be a number, got 'abc'"),
    (["--ald-edge", "3=1e-12"], "--ald-edge 3: ald '1e-12' is below 1e-9, the smallest target"),
    (["--ald-face", "3="], "--ald-face 3: ald must be a number, got ''"),
    (["--ald-edge", "37=1e-4"], "local ald for edge 37: no such edge (the shape has edges 1 to 36)"),
    (["--ald-face", "15=1e-4"], "local ald for face 15: no such face (the shape has faces 1 to 14)"),
])
def test_cli_bad_local_targets_exit_2_one_line(tmp_path, capsys, extra, message):
    out = tmp_path / "b.json"
    assert main(["refine", str(BRACKET), *extra, "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("cadedge refine: error: ") and "bracket.step: " in err
    assert message in err
    assert not out.exists()
