"""An assembly's repeated parts (one B-rep face under several locations) meshed once, their triangles
moved to the other placements (cadedge.mesh.instances, cadedge.occt.instances)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pytest.importorskip("gmsh")

import cadedge  # noqa: E402
from cadedge.mesh import mesh_shape  # noqa: E402
from cadedge.mesh.areas import face_mesh_areas  # noqa: E402
from cadedge.mesh.check import check_triangles  # noqa: E402
from cadedge.mesh.instances import copies, moved, unify  # noqa: E402
from cadedge.mesh.strategies import STRATEGIES  # noqa: E402
from cadedge.mesh.worker import MeshJob  # noqa: E402
from cadedge.occt.areas import face_areas  # noqa: E402
from cadedge.occt.instances import edge_placements, face_placements  # noqa: E402

from conftest import FIXTURES  # noqa: E402


def placed(path, motions):
    """The shape of STEP file ``path`` placed once for each ``(angle about z, (dx, dy, dz), scale)``, as one
    compound whose parts share their B-rep faces (an assembly's instances)."""
    from OCP.BRep import BRep_Builder
    from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Trsf, gp_Vec
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS_Compound

    shape = cadedge.refine_shape(path, ald=1e-1).shape
    builder, compound = BRep_Builder(), TopoDS_Compound()
    builder.MakeCompound(compound)
    for angle, shift, scale in motions:
        turn, move = gp_Trsf(), gp_Trsf()
        turn.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), angle)
        move.SetTranslation(gp_Vec(*shift))
        move.Multiply(turn)
        if scale != 1.0:
            grow = gp_Trsf()
            grow.SetScale(gp_Pnt(0, 0, 0), scale)
            move.Multiply(grow)
        builder.Add(compound, shape.Moved(TopLoc_Location(move)))
    return compound


THRICE = [(0.0, (0, 0, 0), 1.0), (0.7, (200, 37, 0), 1.0), (1.4, (400, 74, 5), 1.0)]


@pytest.fixture(scope="module")
def brackets():
    """The bracket (14 faces) placed three times, the second and third turned."""
    return placed(FIXTURES / "bracket.step", THRICE)


@pytest.fixture(scope="module")
def brackets_step(brackets, tmp_path_factory):
    """The three brackets written by OCCT's STEP writer, which keeps one part placed three times."""
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    from cadedge.occt.loading import quiet_occt

    path = tmp_path_factory.mktemp("placed") / "brackets.step"
    with quiet_occt():
        writer = STEPControl_Writer()
        writer.Transfer(brackets, STEPControl_AsIs)
        writer.Write(str(path))
    return path


def test_faces_and_edges_placed_again_are_found_with_their_motion(brackets):
    """Faces 15-42 are faces 1-14 moved; each motion maps the first face's vertices onto the copy's. A
    scaled placement is no copy."""
    grid = cadedge.refine_shape(brackets, ald=1e-2)
    faces = face_placements(brackets)
    assert sorted(faces) == list(range(15, 43))
    assert {f: first for f, (first, _) in faces.items()} == {f: (f - 1) % 14 + 1 for f in range(15, 43)}
    edges = edge_placements(brackets)
    by_id = {e.id: e for e in grid.edges}
    assert len(edges) == 2 * len(grid.edges) // 3
    for eid, (first, matrix) in edges.items():
        assert np.allclose(moved(by_id[first].points[[0, -1]], matrix), by_id[eid].points[[0, -1]], atol=1e-9)
    scaled = placed(FIXTURES / "bracket.step", [(0.0, (0, 0, 0), 1.0), (0.0, (200, 0, 0), 2.0)])
    assert face_placements(scaled) == {}
    areas = face_areas(brackets)  # measured once, for the first placement
    assert np.array_equal(areas[14:], np.tile(areas[:14], 2)) and areas.min() > 0
    assert np.allclose(face_areas(scaled)[14:], 4 * face_areas(scaled)[:14], rtol=1e-6)


def test_a_repeated_part_is_meshed_once_and_placed_on_its_own_boundary_nodes(brackets, tmp_path):
    """Every face of the three brackets is meshed, the mesh watertight with every grid node in it; the
    copies have their first face's triangles, areas and smallest angles; a note says so."""
    out = tmp_path / "b.msh"
    result = mesh_shape(brackets, ald=1e-2, output=out)
    assert result.ok, result.problems(verbose=True)
    assert result.check.missing_grid_nodes == 0 and all(s.watertight for s in result.check.shells)
    assert len(result.check.shells) == 3
    assert any(n.startswith("28 faces repeat 14 others") for n in result.notes), result.notes
    count = np.bincount(result.triangle_faces, minlength=43)
    areas = face_mesh_areas(result.nodes, result.triangles, result.triangle_faces, 42)
    rows = {r.face: r for r in result.report.faces}
    for face in range(15, 43):
        first = (face - 1) % 14 + 1
        assert count[face] == count[first] > 0
        assert areas[face - 1] == pytest.approx(areas[first - 1], rel=1e-12)
        assert rows[face].min_angle == pytest.approx(rows[first].min_angle, abs=1e-9)
    assert out.stat().st_size > 0


def test_grids_a_repeated_part_refined_differently_are_made_the_same(brackets):
    """A copy's edge grid one node short of its first's (as a length at a threshold can make it) is
    given the first's grid, moved, its end points its own; edges with no copy stay as they are."""
    grid = cadedge.refine_shape(brackets, ald=1e-2)
    faces, edges = face_placements(brackets), edge_placements(brackets)
    eid = next(e for e in sorted(edges) if len(grid.edges[e - 1].points) > 3)
    first, matrix = edges[eid]
    edited = [dataclasses.replace(e, points=np.delete(e.points, 1, axis=0), params=np.delete(e.params, 1))
              if e.id == eid else e for e in grid.edges]
    short = dataclasses.replace(grid, edges=edited)
    assert set(copies(short, faces)) < set(faces)
    same = unify(short, faces, edges)
    assert set(copies(same, faces)) == set(faces)
    fixed = same.edges[eid - 1]
    assert np.array_equal(fixed.points[[0, -1]], grid.edges[eid - 1].points[[0, -1]])
    assert np.allclose(fixed.points, moved(grid.edges[first - 1].points, matrix), atol=1e-9)
    assert all(a is b for a, b in zip(same.edges, short.edges) if a.id not in edges)


def test_the_copies_are_set_aside_while_the_grids_are_fitted_and_get_the_same_grids(brackets, monkeypatch):
    """The grids' fits to the faces fit the first bracket only: faces 15-42 and their edges are set aside
    (the edges bound no face while the passes run) and get the first bracket's fitted grids, moved. The
    grids gmsh is given are the ones fitting every placement gave, edge for edge."""
    import cadedge.mesh as M
    from cadedge.mesh.instances import SetAside, set_aside

    grid = cadedge.refine_shape(brackets, ald=1e-2, max_growth=2.0)
    faces, edges = face_placements(brackets), edge_placements(brackets)
    aside = set_aside(grid, faces, edges)
    assert aside.faces == {f: (f - 1) % 14 + 1 for f in range(15, 43)} and set(aside.edges) == set(edges)
    apart = aside.apart(grid)
    assert {f for e in apart.edges for f in e.faces} == set(range(1, 15))
    assert all(not e.faces for e in apart.edges if e.id in edges) and aside.hide(np.ones(42)).sum() == 14
    back = aside.back(apart)
    assert [e.faces for e in back.edges] == [e.faces for e in grid.edges]

    class Imposed(Exception):
        pass

    def imposed(whole: bool) -> list:
        def stop(g, *args, **kwargs):
            raise Imposed(g)

        monkeypatch.setattr(M, "_run_gmsh", stop)
        if whole:  # nothing set aside: every placement fitted, then unify
            found = M._set_aside
            monkeypatch.setattr(M, "_set_aside", lambda g: SetAside({}, {}, {}, found(g).placements))
        with pytest.raises(Imposed) as got:
            mesh_shape(grid, ald=1e-2)
        return got.value.args[0].edges

    once, every = imposed(False), imposed(True)
    assert sum(len(e.points) for e in once) > sum(len(e.points) for e in grid.edges)  # fitted
    for a, b in zip(once, every):
        assert a.faces == b.faces and len(a.points) == len(b.points), a.id
        assert np.allclose(a.points, b.points, atol=1e-9), a.id


def test_a_placement_refined_to_a_target_of_its_own_keeps_its_grids(brackets):
    """``ald_for`` on one placement's face (20, a copy of face 6): its edges keep their finer grids, so the
    face is no copy and is meshed on its own; the other placement of face 6 (34) is still a copy."""
    grid = cadedge.refine_shape(brackets, ald=1e-2, ald_for={("face", 20): 1e-4})
    faces, edges = face_placements(brackets), edge_placements(brackets)
    same = unify(grid, faces, edges)
    mine = [e for e in grid.edges if 20 in e.faces]
    assert all(same.edges[e.id - 1] is e for e in mine)
    assert sum(len(e.points) for e in mine) > sum(len(e.points) for e in grid.edges if 6 in e.faces)
    found = copies(same, faces)
    assert 20 not in found and found[34][0] == 6


def _job(grid, skip):
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.sizes import SizeField

    return MeshJob(source="cylinders", brep=shape_to_brep(grid.shape),
                   grid=dataclasses.replace(grid, shape=None, curves=None), field=SizeField(grid), mode="nodes",
                   skip=skip, copies=copies(grid, face_placements(grid.shape)))


@pytest.fixture(scope="module")
def cylinders():
    """The cylinder fixture (side 1, caps 2 and 3) placed twice: faces 4-6 are faces 1-3 moved."""
    shape = placed(FIXTURES / "cylinder.step", [(0.0, (0, 0, 0), 1.0), (0.3, (50, 0, 0), 1.0)])
    return cadedge.refine_shape(shape, ald=1e-2, max_growth=2.0)


def test_copies_of_a_face_meshed_on_split_curves_are_meshed_on_their_own(cylinders):
    """Cap 2 meshed only by the strategy that splits its curve: side 1 is meshed again on it, so neither
    has the boundary of its copy (5 and 4), which are meshed on their own; cap 3's copy 6 is placed. The
    mesh conforms, and the status line's count takes in the faces meshed late: it never passes its total
    and ends at 5 of 5."""
    from cadedge.mesh.isolate import run_isolated
    from cadedge.mesh.status import MeshStatus

    split = next(k for k, s in enumerate(STRATEGIES) if s.split)
    job = _job(cylinders, {2: {k: "barred by the test" for k in range(split)}})
    assert sorted(job.copies) == [4, 5, 6]
    shown: list[str] = []
    res = run_isolated(job, workers=1, progress=MeshStatus(shown.append, faces={1, 2, 3}))
    counts = [tuple(map(int, t.split()[2].split("/"))) for t in shown if t.startswith("meshing faces: ")]
    assert all(done <= total for done, total in counts) and counts[-1] == (5, 5), counts
    assert all(o.ok for o in res.faces), res.faces
    assert next(o for o in res.faces if o.face == 2).strategy == STRATEGIES[split].name
    assert any("faces 4, 5 meshed on their own" in n for n in res.notes), res.notes
    assert any(n.startswith("1 face repeats 1 other ") for n in res.notes), res.notes
    multiplicity = {(int(a), int(b)): int(n) for (a, b), n in zip(res.edge_pairs, res.edge_uses)}
    check = check_triangles(res.nodes, res.triangles, triangle_faces=res.triangle_faces,
                            edge_multiplicity=multiplicity)
    assert check.ok and len(check.shells) == 2 and all(s.watertight for s in check.shells)


def test_a_copy_of_a_face_that_failed_fails_with_its_reason(cylinders):
    """Every strategy barred on cap 2: its copy 5 fails too, naming face 2 and its reason; the other
    copies are placed."""
    from cadedge.mesh.isolate import run_isolated

    job = _job(cylinders, {2: {k: "barred by the test" for k in range(len(STRATEGIES))}})
    res = run_isolated(job, workers=1)
    failed = {o.face: o.reason() for o in res.faces if not o.ok}
    assert sorted(failed) == [2, 5]
    assert "face 2, the same face placed elsewhere, failed: " in failed[5] and "barred by the test" in failed[5]
    assert set(np.unique(res.triangle_faces)) == {1, 3, 4, 6}


def test_a_step_assembly_is_meshed_with_every_placement_in_the_msh_and_the_report(brackets_step, tmp_path, capsys):
    """``cadedge mesh`` on the STEP file: exit 0, every face a physical group with triangles, every face in
    the report, and the summary's note on the placed faces."""
    import json

    meshio = pytest.importorskip("meshio")
    from cadedge.cli import main

    out, report = tmp_path / "b.msh", tmp_path / "b.json"
    assert main(["mesh", str(brackets_step), "--ald", "1e-2", "-o", str(out), "--report", str(report)]) == 0
    assert "note: 28 faces repeat 14 others" in capsys.readouterr().out
    mesh = meshio.read(out)
    tags = np.concatenate([t for (c, t) in zip(mesh.cells, mesh.cell_data["gmsh:physical"]) if c.type == "triangle"])
    assert sorted(np.unique(tags)) == list(range(1, 43))
    assert {f"face {f}" for f in range(1, 43)} <= set(mesh.field_data)
    rows = json.loads(report.read_text())["faces"]
    assert [r["face"] for r in rows] == list(range(1, 43)) and all(r["status"] == "ok" for r in rows)


def test_copies_of_faces_a_stopped_job_delivered_are_placed_and_the_others_named(cylinders):
    """A child that loses cap 2 and then hangs: the hard timeout delivers faces 1 and 3, whose copies 4 and
    6 are placed; cap 2 fails for the time, and its copy 5 with it."""
    result = mesh_shape(cylinders, hooks={"after_generate": ["mesh_faults:lose_a_face_and_hang"]}, timeout=20,
                        face_timeout=100)
    assert sorted(f.face for f in result.failures) == [2, 5]
    reasons = {f.face: f.reason for f in result.failures}
    assert "no result within 20 s" in reasons[2]
    assert "face 2, the same face placed elsewhere, failed: " in reasons[5] and "no result within" in reasons[5]
    assert set(np.unique(result.triangle_faces)) == {1, 3, 4, 6}
    assert result.check.ok, result.check.problems
    count = np.bincount(result.triangle_faces, minlength=7)
    assert count[4] == count[1] and count[6] == count[3]
