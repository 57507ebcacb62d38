"""cadedge mesh under faults: gmsh crashes, hangs, timeouts, Ctrl-C, unmatched edges, retries, PMI files.

Faults are real and happen in the gmsh child process (hooks in ``mesh_faults.py``: a read of address 0, an
endless loop); the caller must get a result, never a crash.
"""

from __future__ import annotations

import copy
import dataclasses
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gmsh")
trimesh = pytest.importorskip("trimesh")
psutil = pytest.importorskip("psutil")

import cadedge  # noqa: E402
from cadedge.cli import main  # noqa: E402
from cadedge.mesh import mesh_shape  # noqa: E402
from cadedge.mesh.check import check_triangles  # noqa: E402
from cadedge.mesh.strategies import STRATEGIES  # noqa: E402

from conftest import FIXTURES, ROOT  # noqa: E402

ALD = 1e-2
CYL = FIXTURES / "cylinder.step"
FAULT_FACE = 2  # mesh_faults.FAULT_FACE


@pytest.fixture(scope="module")
def cylinder() -> cadedge.ShapeGrid:
    return cadedge.refine_shape(CYL, ald=ALD, max_growth=2.0)


def _watertight_with_every_face(result) -> None:
    assert result.ok, result.problems(verbose=True)
    assert all(s.watertight for s in result.check.shells)
    assert set(np.unique(result.triangle_faces)) == set(range(1, result.grid.faces + 1))


def test_a_segfault_in_gmsh_costs_one_attempt(cylinder, tmp_path):
    out = tmp_path / "c.msh"
    result = mesh_shape(cylinder, output=out, hooks={"before_face": ["mesh_faults:segfault"]})
    _watertight_with_every_face(result)
    face = next(o for o in result.faces if o.face == FAULT_FACE)
    assert face.strategy == STRATEGIES[1].name and "SIGSEGV" in face.attempts[0][1]
    assert any("SIGSEGV" in n for n in result.notes)
    assert out.exists()


def test_a_hang_in_gmsh_costs_one_attempt(cylinder):
    t0 = time.monotonic()
    said: list[str] = []
    result = mesh_shape(cylinder, hooks={"before_face": ["mesh_faults:hang"]}, timeout=60, face_timeout=2,
                        progress=said.append)
    assert time.monotonic() - t0 < 40
    _watertight_with_every_face(result)
    face = next(o for o in result.faces if o.face == FAULT_FACE)
    assert "hung" in face.attempts[0][1] and face.ok
    assert any(s.startswith(f"face {FAULT_FACE}: hung") and "new process" in s for s in said)  # the status says so
    assert f"meshing faces: {result.grid.faces}/{result.grid.faces} meshed" in " ".join(said)


def test_a_batch_that_hangs_inside_gmsh_is_pinned_on_the_face_gmsh_was_meshing(cylinder):
    """A batch of first attempts that hangs is done again face by face; the face gmsh was meshing when it
    hung (its progress, printed to the child's trace) is not tried again by the same strategy alone: on
    SparkFun's FlexyPin and an ABC-dataset part, a face that hung in its batch hung 60 s again alone
    before its next strategy."""
    from cadedge.mesh.worker import BATCH_MARK, trace_culprit

    said: list[str] = []
    result = mesh_shape(cylinder, hooks={"before_face": ["mesh_faults:spin_in_gmsh"]}, timeout=60,
                        face_timeout=2, progress=said.append)
    _watertight_with_every_face(result)
    face = next(o for o in result.faces if o.face == FAULT_FACE)
    assert face.ok and face.attempts[0][0] == STRATEGIES[0].name and "hung" in face.attempts[0][1]
    batch = next(n for n in result.notes if "meshing them together in one gmsh call: hung" in n)
    assert f"on face {FAULT_FACE} ({STRATEGIES[0].name}: gmsh's progress names it)" in batch
    assert not any(n.startswith(f"face {FAULT_FACE}: hung") for n in result.notes)  # not hung a second time

    trace = f"{BATCH_MARK} 2:5 3:7\nInfo    : Meshing 2D...\nInfo    : [  0%] Meshing surface 5 (Plane, Delaunay)\n"
    assert trace_culprit(trace, [2, 3]) == 2
    assert trace_culprit(trace + "Info    : [ 50%] Meshing surface 7 (Plane, Delaunay)\n", [2, 3]) == 3
    assert trace_culprit(trace + "Info    : Done meshing 2D (Wall 0.1s, CPU 0.1s)\n", [2, 3]) is None
    assert trace_culprit(trace, [3]) is None and trace_culprit("", [2, 3]) is None


def test_a_face_that_hung_once_gets_a_shorter_bound_on_its_later_attempts():
    """A face that hangs one strategy tends to hang the others (an ABC-dataset part's B-spline face hung
    three attempts, 60 s each, and faces were left out of time); one that meshes does so in seconds."""
    from cadedge.mesh.isolate import RETRY_SHARE, retry_share

    skip = {2: {0: "hung: no result within 60 s", 1: "not tried: Frontal-Delaunay hung on the same sizes"},
            3: {0: "gmsh crashed (SIGSEGV)"}}
    assert 0 < RETRY_SHARE < 1
    assert retry_share("face 2 3", skip) == RETRY_SHARE
    assert retry_share("face 3 1", skip) == retry_share("face 4 0", skip) == 1.0  # crashed, or never hung
    assert retry_share("batch 2 3", skip) == retry_share("refine 2", skip) == 1.0


def test_a_hang_bars_the_strategies_the_face_has_not_tried_on_the_same_or_finer_sizes():
    """What a hang bars follows the face's own order, not the list's: a curved face with many holes tries
    Delaunay first, and its hang bars Frontal-Delaunay and MeshAdapt at the same sizes; what the face
    tried already keeps the reason it failed with."""
    from cadedge.mesh.isolate import _bar, _Run
    from cadedge.mesh.strategies import HOLED_ORDER

    names = [s.name for s in STRATEGIES]
    fd, ma, dl, finer = (names.index(n) for n in ("Frontal-Delaunay", "MeshAdapt", "Delaunay",
                                                  "Frontal-Delaunay, finer sizes"))
    assert HOLED_ORDER[0] == dl
    hung = _Run(result=None, status="hung", last=f"face 7 {dl}", detail="hung: no result within 60 s")
    skip: dict[int, dict[int, str]] = {}
    _bar(skip, 7, dl, hung)
    assert skip[7][dl] == hung.detail
    assert skip[7][fd] == skip[7][ma] == "not tried: Delaunay hung on the same sizes"
    assert skip[7][finer] == "not tried: Delaunay hung; finer sizes take longer"
    assert names.index("MeshAdapt, coarser sizes") not in skip[7]  # coarser sizes are still tried

    skip = {7: {fd: "failed: 3 triangles folded"}}  # tried first (learned from the child's progress)
    _bar(skip, 7, ma, dataclasses.replace(hung, last=f"face 7 {ma}"))
    assert skip[7][fd] == "failed: 3 triangles folded" and skip[7][dl].startswith("not tried: MeshAdapt hung")
    crashed = dataclasses.replace(hung, status="crashed", detail="gmsh crashed (SIGSEGV)")
    skip = {}
    _bar(skip, 7, fd, crashed)
    assert skip == {7: {fd: "gmsh crashed (SIGSEGV)"}}  # a crash bars that attempt only


def test_a_crash_outside_the_faces_fails_the_run_not_the_caller(cylinder, tmp_path):
    out = tmp_path / "c.msh"
    result = mesh_shape(cylinder, output=out, hooks={"before_generate": ["mesh_faults:crash_before_meshing"]})
    assert not result.ok and "SIGSEGV" in result.error
    assert len(result.failures) == cylinder.faces and len(result.triangles) == 0
    assert not out.exists() and result.output is None  # nothing meshed: no file


def test_the_whole_run_is_bounded_by_the_timeout(cylinder, tmp_path):
    """The whole job (the grids' stages in this process, every child, the delivery and the writing) ends
    within the timeout and a few seconds: the hang alone would last WALL_SLACK * 100 s."""
    t0 = time.monotonic()
    result = mesh_shape(cylinder, output=tmp_path / "c.msh", hooks={"before_face": ["mesh_faults:hang"]},
                        timeout=4, face_timeout=100)
    assert time.monotonic() - t0 < 4 + 10
    assert not result.ok
    # Out of time with nothing delivered (the job's error: gmsh not reached before 70% of the 4 s on a
    # loaded machine, or nothing meshed by then) or with the faces meshed so far (face 1, in its own first
    # batch, before face 2 hung): then face 2 is named as out of time (killed at the soft deadline) or not
    # finished at the hard timeout, and only a partial mesh is written.
    if result.error is not None:
        assert "no result within 4 s" in result.error or "of --timeout (4 s)" in result.error
        assert not (tmp_path / "c.msh").exists()
    else:
        failed = {f.face: f.reason for f in result.failures}
        assert "out of time" in failed[2] or "no result within 4 s (--timeout)" in failed[2]
        assert (tmp_path / "c.msh").exists() == (len(result.triangles) > 0)


def test_the_grids_stages_count_against_the_timeout(cylinder, monkeypatch):
    """Past a share of the timeout the stages fitting the grids to the faces are left out and named, and
    the job goes on to gmsh with what is left of its time; a job whose time was used before gmsh starts no
    child and names its faces out of time."""
    import cadedge.mesh.jobclock as jobclock

    monkeypatch.setattr(jobclock, "PREP_SHARE", 0.0)
    result = mesh_shape(cylinder, timeout=120)
    _watertight_with_every_face(result)
    note = next(n for n in result.notes if n.startswith("the edge grids were meshed without"))
    assert "the boundary fit for the area target" in note and "the thin faces' splits" in note
    assert "over 0% of --timeout (120 s)" in note

    class Late(jobclock.JobClock):
        def __init__(self, timeout: float):
            super().__init__(timeout)
            self.started -= 0.75 * timeout  # as if reading and refining had taken three quarters of it

    monkeypatch.setattr(jobclock, "JobClock", Late)
    t0 = time.monotonic()
    result = mesh_shape(cylinder, timeout=120)
    assert time.monotonic() - t0 < 30
    assert not result.ok and len(result.triangles) == 0 and len(result.failures) == cylinder.faces
    assert "past 70% of --timeout (120 s); gmsh was not started" in result.error


def test_an_attempt_killed_late_ends_the_job_with_what_was_delivered(cylinder, tmp_path):
    """An attempt still running at KILL_SHARE of the timeout (a slow batch, not a hang: the face bound is
    far off) is killed, and the job ends there with the faces delivered so far. A new child's first attempt
    would be killed at once in turn: a heat sink at 1e-3 went through 12 restarts that way and ended with
    none of its 81 meshed faces."""
    said: list[str] = []
    result = mesh_shape(cylinder, output=tmp_path / "c.msh", hooks={"before_face": ["mesh_faults:hang"]},
                        timeout=20, face_timeout=1000, progress=said.append)
    assert not any("in a new process" in line for line in said)  # no new child after the kill
    assert not result.ok
    if result.error is not None:  # face 2 was batched with every other face: nothing was delivered
        assert "out of time: meshing was stopped at 70% of --timeout (20 s)" in result.error
        assert not (tmp_path / "c.msh").exists()
    else:
        failed = {f.face: f.reason for f in result.failures}
        assert "out of time: meshing was stopped at 70% of --timeout (20 s)" in failed[FAULT_FACE]
        assert (tmp_path / "c.msh").exists() and len(result.triangles)


def _offset_edge(grid: cadedge.ShapeGrid) -> tuple[cadedge.ShapeGrid, int]:
    """The grid with one seamless circle edge lifted off its curve: no gmsh curve matches it any more."""
    g = copy.copy(grid)
    g.edges = list(grid.edges)
    e = next(e for e in g.edges if e.curve == "Circle" and len(e.faces) == 2)
    g.edges[e.id - 1] = dataclasses.replace(e, points=e.points + np.array([0.0, 0.0, 0.05]),
                                            params=e.params + 0.01)
    return g, e.id


def test_an_edge_gmsh_cannot_match_leaves_its_faces_meshed(cylinder):
    grid, eid = _offset_edge(cylinder)
    for mode in ("nodes", "sizes"):
        result = mesh_shape(grid, mode=mode)
        _watertight_with_every_face(result)
        assert result.unmatched_edges == [eid]
        assert any(f"edges {eid} match no gmsh curve" in n for n in result.notes)


@pytest.mark.parametrize("fallback", ["split", "own_curves"])
def test_fallback_strategies_keep_neighbours_conforming(cylinder, fallback):
    """Every earlier strategy barred on a face: it is meshed after its boundary segments are split, or on
    gmsh's own curve mesh; its neighbours are meshed again on the changed curves and stay conforming, and
    every grid node of the edges still imposed is a mesh node. gmsh's own curve mesh is no coarser than the
    grids it replaces."""
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.sizes import SizeField
    from cadedge.mesh.worker import MeshJob, run_job

    first = next(k for k, s in enumerate(STRATEGIES) if getattr(s, fallback))
    skip = {FAULT_FACE: {k: "barred by the test" for k in range(first)}}
    job = MeshJob(source="cyl", brep=shape_to_brep(cylinder.shape), grid=dataclasses.replace(cylinder, shape=None),
                  field=SizeField(cylinder), mode="nodes", skip=skip)
    res = run_job(job)
    face = next(o for o in res.faces if o.face == FAULT_FACE)
    assert face.ok and face.strategy == STRATEGIES[first].name
    assert all(o.ok for o in res.faces)
    multiplicity = {(int(a), int(b)): int(n) for (a, b), n in zip(res.edge_pairs, res.edge_uses)}
    imposed = set(res.imposed_edges)
    pts = np.vstack([e.points for e in cylinder.edges if e.id in imposed])
    check = check_triangles(res.nodes, res.triangles, triangle_faces=res.triangle_faces, grid_points=pts,
                            edge_multiplicity=multiplicity)
    assert check.ok and check.missing_grid_nodes == 0 and all(s.watertight for s in check.shells)
    if fallback == "split":
        assert sum(e.segments for e in cylinder.edges) < len(res.edge_pairs)  # more curve segments
    else:  # gmsh meshes the edges at their grids' spacings: no coarser (by the boundary field alone, 8 of 13)
        assert res.own_mesh_edges and not imposed.intersection(res.own_mesh_edges)
        assert len(res.edge_pairs) >= sum(e.segments for e in cylinder.edges)


def test_a_face_meshed_again_alone_by_a_splitting_strategy_has_its_neighbours_meshed_again():
    """A hook meshes one face again on its own (as the surface target does) by a strategy that splits its
    curves: the neighbours, meshed already but outside that call's faces, are meshed again on the split
    curves (this raised a KeyError in the child before)."""
    grid = cadedge.refine_shape(CYL, ald=ALD, max_growth=2.0)
    result = mesh_shape(grid, hooks={"after_generate": ["mesh_faults:remesh_split"]})
    _watertight_with_every_face(result)
    face = next(o for o in result.faces if o.face == FAULT_FACE)
    assert face.strategy == next(s.name for s in STRATEGIES if s.split)


class _Stopped(Exception):
    """A mesh process stopped during an attempt (as a hang or the timeout ends it)."""


def _delivered_when_stopped(cylinder, tmp_path, first: int):
    """Run the mesh job of ``cylinder`` in this process, face ``FAULT_FACE``'s strategies before ``first``
    barred, until an attempt raises :class:`_Stopped`; what the parent then has (``delivered``)."""
    import pickle

    from cadedge.mesh.delivered import delivered
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.sizes import SizeField
    from cadedge.mesh.worker import MeshJob, run_job

    job = MeshJob(source="cyl", brep=shape_to_brep(cylinder.shape), grid=dataclasses.replace(cylinder, shape=None),
                  field=SizeField(cylinder), mode="nodes",
                  skip={FAULT_FACE: {k: "barred by the test" for k in range(first)}})
    path = tmp_path / "faces"
    with open(path, "wb") as f, pytest.raises(_Stopped):
        run_job(job, deliver=lambda dim, tag, corners: pickle.dump((dim, tag, corners), f))
    return delivered(str(path), job, {}, "stopped by the test", [])


def test_two_solids_touching_face_to_face_stay_two_closed_shells_when_delivered(tmp_path):
    """Two cubes of an assembly touching along a face, each with its own faces, edges and vertices there:
    the faces a process delivered (what a stopped or timed-out job hands over) are welded per connected
    piece of the shape, as gmsh gives each solid its own nodes. Welded by coordinates alone, a Fusion
    pump's two solids shared the segments round their common face, each used four times: check FAILED
    on a mesh that had none."""
    import pickle

    from OCP.BRep import BRep_Builder
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.gp import gp_Pnt
    from OCP.TopoDS import TopoDS_Compound

    from cadedge.mesh.delivered import delivered
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.shards import pieces
    from cadedge.mesh.sizes import SizeField
    from cadedge.mesh.worker import MeshJob, run_job

    pair, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(pair)
    for x in (0.0, 10.0):
        builder.Add(pair, BRepPrimAPI_MakeBox(gp_Pnt(x, 0.0, 0.0), 10.0, 10.0, 10.0).Shape())
    grid = cadedge.refine_shape(pair, ald=ALD, max_growth=2.0)
    assert sorted(set(pieces(grid)[0].values())) == [0, 1]
    job = MeshJob(source="pair", brep=shape_to_brep(pair), grid=dataclasses.replace(grid, shape=None),
                  field=SizeField(grid), mode="nodes")
    path = tmp_path / "faces"
    with open(path, "wb") as f:
        run_job(job, deliver=lambda dim, tag, corners: pickle.dump((dim, tag, corners), f))
    res = delivered(str(path), job, {}, "stopped by the test", []).result
    assert {o.face for o in res.faces if o.ok} == set(range(1, 13))
    multiplicity = {(int(a), int(b)): int(n) for (a, b), n in zip(res.edge_pairs, res.edge_uses)}
    check = check_triangles(res.nodes, res.triangles, triangle_faces=res.triangle_faces,
                            edge_multiplicity=multiplicity)
    assert check.ok, check.lines()
    assert len(check.shells) == 2 and all(s.watertight for s in check.shells)


def test_faces_a_stopped_process_meshed_on_curves_a_later_one_changed_are_left_out(cylinder, tmp_path):
    """A first process meshes every face and is stopped; the next meshes the side again on finer curve
    meshes (as when a failed face's curves are meshed at other spacings) and is stopped in turn. The caps
    the first delivered sit on the old circles: joined, they would not conform to the side (an Inventor
    worm gear's check failed on 9 segments), so they are left out and named, and the rest checks."""
    import pickle

    from cadedge.mesh.delivered import STALE, delivered
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.sizes import SizeField
    from cadedge.mesh.worker import MeshJob, run_job

    path = tmp_path / "faces"
    finer = cadedge.refine_shape(CYL, ald=ALD / 10, max_growth=2.0)
    jobs = [MeshJob(source="cyl", brep=shape_to_brep(cylinder.shape), grid=dataclasses.replace(g, shape=None),
                    field=SizeField(g), mode="nodes", faces=faces)
            for g, faces in ((cylinder, None), (finer, frozenset({FAULT_FACE})))]
    with open(path, "wb") as f:
        for job in jobs:
            run_job(job, deliver=lambda dim, tag, corners: pickle.dump((dim, tag, corners), f))
    r = delivered(str(path), dataclasses.replace(jobs[-1], faces=None), {}, "stopped by the test", []).result
    outcomes = {o.face: o for o in r.faces}
    assert {f for f, o in outcomes.items() if o.ok} == {FAULT_FACE}
    assert all(o.attempts[0][1] == STALE for f, o in outcomes.items() if f != FAULT_FACE)
    assert any(n.endswith(STALE) for n in r.notes)
    multiplicity = {(int(a), int(b)): int(n) for (a, b), n in zip(r.edge_pairs, r.edge_uses)}
    check = check_triangles(r.nodes, r.triangles, triangle_faces=r.triangle_faces, edge_multiplicity=multiplicity)
    assert check.ok, check.lines()


def test_faces_whose_meshes_gmsh_deletes_splitting_a_curve_are_meshed_again_on_it(tmp_path):
    """A disk with a hole next to its rim, meshed on coarse grids (4 segments a circle): the top and bottom
    faces' boundaries cross in their parameters, so gmsh splits the rim's and the hole's segments as it
    meshes them and deletes the rim face meshed before. That face is meshed again on the split curves
    before the hooks (not left empty as "meshed": an Inventor worm gear's flanks came out missing), the
    split edges are named, and what the process delivered joins into a mesh that checks."""
    import pickle

    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt

    from cadedge.mesh.delivered import delivered
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.sizes import SizeField
    from cadedge.mesh.worker import MeshJob, run_job

    at = 7.99 * np.sqrt(0.5)  # 45 degrees round, between the rim's grid points; 0.01 from the rim
    hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(at, at, -1.0), gp_Dir(0.0, 0.0, 1.0)), 2.0, 4.0).Shape()
    shape = BRepAlgoAPI_Cut(BRepPrimAPI_MakeCylinder(10.0, 2.0).Shape(), hole).Shape()
    grid = cadedge.refine_shape(shape, ald=0.1)
    assert max(e.segments for e in grid.edges) == 4
    job = MeshJob(source="rim", brep=shape_to_brep(shape), grid=dataclasses.replace(grid, shape=None),
                  field=SizeField(grid), mode="nodes")
    path = tmp_path / "faces"
    with open(path, "wb") as f:
        res = run_job(job, deliver=lambda dim, tag, corners: pickle.dump((dim, tag, corners), f))
    assert all(o.ok and o.triangles for o in res.faces)
    assert set(np.unique(res.triangle_faces)) == set(range(1, grid.faces + 1))
    assert any("gmsh added nodes to their grids" in n for n in res.notes)
    assert not any("the steps after meshing" in n for n in res.notes), res.notes  # not left to the last check
    got = delivered(str(path), job, {}, "stopped by the test", []).result
    assert {o.face for o in got.faces if o.ok} == set(range(1, grid.faces + 1))
    assert any("meshed on other nodes than their grids" in n for n in got.notes)  # said when stopped too
    multiplicity = {(int(a), int(b)): int(n) for (a, b), n in zip(got.edge_pairs, got.edge_uses)}
    check = check_triangles(got.nodes, got.triangles, triangle_faces=got.triangle_faces,
                            edge_multiplicity=multiplicity)
    assert check.ok and all(s.watertight for s in check.shells), check.lines()


def test_a_process_stopped_during_a_splitting_attempt_still_hands_over_the_neighbours(cylinder, tmp_path,
                                                                                      monkeypatch):
    """A face whose earlier strategies are barred splits its curves, which clears its meshed neighbours in
    gmsh, and the process is stopped during that attempt (here the attempt raises, as a hang or the
    timeout ends it). What the parent has, the delivered faces and edges, must still hold the neighbours'
    meshes on the curves as they were, and join watertight where they meet: a horn torus at 1e-2, whose
    pinched face hung in its splitting strategies, ended with no face at all, its 4 meshed neighbours
    cleared from what the process had delivered."""
    from cadedge.mesh import generate

    attempt = generate._attempt

    def stopped_when_split(surface, strategy):
        if strategy.split:
            raise _Stopped
        return attempt(surface, strategy)

    monkeypatch.setattr(generate, "_attempt", stopped_when_split)
    got = _delivered_when_stopped(cylinder, tmp_path, next(k for k, s in enumerate(STRATEGIES) if s.split))
    meshed = {o.face for o in got.result.faces if o.ok}
    neighbours = {f for e in cylinder.edges if FAULT_FACE in e.faces for f in e.faces} - {FAULT_FACE}
    assert neighbours and meshed == set(range(1, cylinder.faces + 1)) - {FAULT_FACE}
    res = got.result
    multiplicity = {(int(a), int(b)): int(n) for (a, b), n in zip(res.edge_pairs, res.edge_uses)}
    check = check_triangles(res.nodes, res.triangles, triangle_faces=res.triangle_faces,
                            edge_multiplicity=multiplicity)
    assert check.ok, check.lines()
    assert check.lines(missing=1)[-1] == "check: ok on the faces meshed, open where the 1 failed face is missing"
    assert check.lines()[-1] == "check: ok"


def test_faces_gmshs_curve_meshing_wiped_stay_delivered_where_their_curves_did_not_change(cylinder, tmp_path,
                                                                                         monkeypatch):
    """A face meshed on gmsh's own curve mesh (a late fallback) has gmsh mesh its curves again, which wipes
    every face's 2-D mesh; faces on other curves are meshed again on the same boundary, and until then
    their delivered meshes stand. OCCT's Alias test file at 1e-3 reached that strategy on one face late in
    its job: its 46 meshed faces were cleared from what the process had delivered, the process was
    stopped before meshing them again, and 1 face was delivered."""
    from cadedge.mesh import generate

    attempt, done = generate._attempt, []

    def stopped_after_own_curves(surface, strategy):
        if done:  # the first face meshed again after the fallback: the process is stopped
            raise _Stopped
        reason = attempt(surface, strategy)
        if strategy.own_curves:
            done.append(reason)
        return reason

    monkeypatch.setattr(generate, "_attempt", stopped_after_own_curves)
    got = _delivered_when_stopped(cylinder, tmp_path, next(k for k, s in enumerate(STRATEGIES) if s.own_curves))
    assert done == [None]  # the fallback meshed the face
    meshed = {o.face for o in got.result.faces if o.ok}
    users = {f for e in cylinder.edges if FAULT_FACE in e.faces for f in e.faces}
    others = set(range(1, cylinder.faces + 1)) - users
    assert others and others | {FAULT_FACE} <= meshed  # the neighbours on its curves are cleared, the rest stand


def test_check_names_faces_with_small_angles():
    nodes = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [1.05, 0.5, 0]], dtype=float)
    tris = np.array([[0, 1, 2], [1, 3, 2], [1, 4, 3]])
    check = check_triangles(nodes, tris, triangle_faces=np.array([1, 1, 7]))
    assert check.small_angle_share == pytest.approx(1 / 3)
    assert [f for f, _, _ in check.small_angle_faces] == [7]
    text = "\n".join(check.lines())
    assert "under 10 deg" in text and "faces 7 (" in text


def _run_cli(tmp_path, *argv: str) -> tuple[int, list[str]]:
    """``cadedge mesh`` in-process from ``tmp_path`` (relative paths as a user types them)."""
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        import io
        from contextlib import redirect_stderr, redirect_stdout

        err, out = io.StringIO(), io.StringIO()
        with redirect_stderr(err), redirect_stdout(out):
            code = main(["mesh", *argv])
    finally:
        os.chdir(cwd)
    return code, err.getvalue().splitlines()


def test_cli_timeout_is_exit_1_naming_the_file_and_writes_nothing(tmp_path):
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "part.step").write_bytes(CYL.read_bytes())
    code, err = _run_cli(tmp_path, "in/part.step", "--ald", "1e-2", "-o", "part.msh", "--timeout", "0.2")
    assert code == 1 and err
    assert all(line.startswith("cadedge mesh: in/part.step: ") for line in err)
    # the time used before gmsh (reading, refining, the grids' stages; under 0.14 s where the STEP read
    # is cached) or gmsh's own ran out
    assert any("past 70% of --timeout (0.2 s); gmsh was not started" in line
               or "no result within 0.2 s (--timeout)" in line for line in err)
    assert not (tmp_path / "part.msh").exists()


def test_cli_internal_error_on_a_valid_file_is_one_line_exit_1(tmp_path, monkeypatch):
    """A fault of ours after meshing (here the report raising) is not bad input: exit 1, one line naming
    the file, no traceback."""
    import cadedge.mesh.report as report

    def broken(*args, **kwargs):
        raise ValueError("injected fault")

    monkeypatch.setattr(report, "report_of", broken)
    (tmp_path / "part.step").write_bytes(CYL.read_bytes())
    code, err = _run_cli(tmp_path, "part.step", "--ald", "1e-1", "-o", "part.msh")
    assert code == 1
    assert err == ["cadedge mesh: part.step: internal error: ValueError: injected fault"]


def _command(process: psutil.Process) -> str:
    """A process's command line; "" for one that has ended (the fork that read the STEP file, between
    its exit and its reaping, is a zombie, whose command line psutil refuses)."""
    try:
        return " ".join(process.cmdline())
    except psutil.Error:
        return ""


def _cli_hung_in_gmsh(tmp_path):
    """``cadedge mesh`` in a new process whose gmsh child hangs in a face: (the process, the child)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "tests")]))
    code = ("import functools, sys; import cadedge.mesh as m; from cadedge.cli import main; "
            "m.mesh_shape = functools.partial(m.mesh_shape, hooks={'before_face': ['mesh_faults:hang']}); "
            "sys.exit(main(['mesh', 'cyl.step', '--ald', '1e-2', '-o', 'c.msh']))")
    (tmp_path / "cyl.step").write_bytes(CYL.read_bytes())
    proc = subprocess.Popen([sys.executable, "-c", code], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    parent = psutil.Process(proc.pid)
    deadline = time.monotonic() + 120
    child = None
    while child is None and time.monotonic() < deadline and proc.poll() is None:
        child = next((c for c in parent.children() if "cadedge.mesh.worker" in _command(c)), None)
        time.sleep(0.05)
    if child is None:
        proc.kill()
        pytest.fail("the gmsh child never started")
    return proc, child


@pytest.mark.parametrize("sig, code, word", [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")])
def test_cli_interrupt_is_one_line_and_kills_gmsh(tmp_path, sig, code, word):
    """Ctrl-C, and SIGTERM (``kill``, ``timeout``, a job scheduler) the same way: one line, exit 130 or 143,
    the gmsh child killed, no output file (SIGTERM used to end the process with no line at all)."""
    proc, child = _cli_hung_in_gmsh(tmp_path)
    time.sleep(1.0)  # into the hung face attempt
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == code
    assert err.strip() == f"cadedge mesh: cyl.step: {word}"
    assert not child.is_running() or child.status() == psutil.STATUS_ZOMBIE
    assert not (tmp_path / "c.msh").exists()


def test_the_gmsh_child_dies_with_its_caller(cylinder, tmp_path):
    """A caller killed outright (SIGKILL: no handler, no cleanup) takes its gmsh child with it, even one hung
    in a face: an orphan would go on meshing or hanging with nobody to time it. The job folder it leaves is
    removed by the next mesh job, and a live caller's folder is not."""
    import tempfile

    proc, child = _cli_hung_in_gmsh(tmp_path)
    proc.kill()
    proc.communicate(timeout=60)
    try:
        child.wait(timeout=30)
    except psutil.TimeoutExpired:
        child.kill()
        pytest.fail("the gmsh child outlived its caller")
    root = Path(tempfile.gettempdir())
    # the killed caller's folder (made again here: a job running beside this test may have removed it already)
    (root / f"cadedge-mesh-{proc.pid}-left").mkdir(exist_ok=True)
    live = Path(tempfile.mkdtemp(prefix=f"cadedge-mesh-{os.getpid()}-"))
    try:
        assert mesh_shape(cylinder).ok
        assert not list(root.glob(f"cadedge-mesh-{proc.pid}-*")) and live.exists()
    finally:
        live.rmdir()


def _hard_models():
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        import hard_models
    finally:
        sys.path.remove(str(ROOT / "scripts"))
    return hard_models


def test_ap242_with_pmi_written_by_xde_meshes_every_face(tmp_path):
    pytest.importorskip("cadquery")
    path = tmp_path / "pmi.step"
    _hard_models().write_pmi_step(path)
    assert "AP242" in path.read_text()[:600] and "DIMENSIONAL_SIZE" in path.read_text()
    for mode in ("nodes", "sizes"):
        code, err = _run_cli(tmp_path, "pmi.step", "--ald", "1e-1", "--mode", mode, "-o", f"{mode}.msh")
        assert code == 0, err
        assert (tmp_path / f"{mode}.msh").exists()


@pytest.mark.parametrize("name", ["revolved_spline", "bspline_cage", "tangent_union"])
def test_hard_models_mesh_every_face(name):
    pytest.importorskip("cadquery")
    shape = _hard_models().MODELS[name]()
    result = mesh_shape(shape, ald=ALD)
    assert result.ok, result.problems(verbose=True)
    assert set(np.unique(result.triangle_faces)) == set(range(1, result.grid.faces + 1))
    assert result.check.missing_grid_nodes == 0


def test_past_the_deadline_only_faces_meshed_before_are_replayed(cylinder):
    """A child started after the soft deadline meshes the faces a killed child had meshed and names the
    others: a partial mesh, not nothing."""
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.isolate import _learn
    from cadedge.mesh.sizes import SizeField
    from cadedge.mesh.worker import MeshJob, run_job

    skip: dict = {}
    known_ok: dict = {}
    _learn(["import", "face 1 0", "result 1 0 ok", "face 2 0", "result 2 0 fail no triangles", "face 2 1"],
           skip, known_ok)
    assert known_ok == {1: 0} and skip == {2: {0: "no triangles"}}
    job = MeshJob(source="cyl", brep=shape_to_brep(cylinder.shape), grid=dataclasses.replace(cylinder, shape=None),
                  field=SizeField(cylinder), mode="nodes", skip=skip, known_ok=known_ok, deadline=time.time() - 1)
    res = run_job(job)
    outcome = {o.face: o for o in res.faces}
    assert outcome[1].ok and not outcome[2].ok and not outcome[3].ok
    assert "out of time" in outcome[3].attempts[-1][1]
    assert set(np.unique(res.triangle_faces)) == {1}


def test_faces_an_earlier_child_delivered_are_kept_when_the_last_one_did_not_mesh_them(cylinder, tmp_path):
    """A restarted child that meshes only part of the model (its replays stopped or past the soft deadline)
    finishes normally; the faces an earlier, killed child had delivered are added to its mesh, so the job
    does not end with fewer faces than were meshed (a twisted blade at 1e-3 under load ended with none)."""
    import pickle

    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.delivered import with_earlier_faces
    from cadedge.mesh.sizes import SizeField
    from cadedge.mesh.worker import MeshJob, run_job

    path = tmp_path / "faces"

    def deliver(dim, tag, corners):
        with open(path, "ab") as f:
            pickle.dump((dim, tag, corners), f)

    def job(**kw):
        return MeshJob(source="cyl", brep=shape_to_brep(cylinder.shape),
                       grid=dataclasses.replace(cylinder, shape=None), field=SizeField(cylinder), mode="nodes", **kw)

    full = run_job(job(), deliver=deliver)  # the first child: every face meshed and delivered
    last = run_job(job(known_ok={2: 0}, deadline=time.time() - 1), deliver=deliver)  # face 2 only
    assert [o.face for o in last.faces if o.ok] == [2]
    merged = with_earlier_faces(last, str(path), job(), {2: 0}).result
    assert [o.face for o in merged.faces if o.ok] == [1, 2, 3]
    assert set(np.unique(merged.triangle_faces)) == {1, 2, 3}
    assert len(merged.triangles) == len(full.triangles) and len(merged.nodes) == len(np.unique(full.nodes, axis=0))
    assert any("faces 1, 3: meshed by an earlier mesh process" in n for n in merged.notes)
    assert with_earlier_faces(full, str(path), job(), {}) is None  # nothing to add


def test_the_optimiser_runs_past_the_soft_deadline_until_finish_by(cylinder):
    """Meshing that used the soft deadline (mesh_T106_V3 under load) still leaves the face optimiser its
    time up to ``finish_by``; past ``finish_by`` it leaves every face as gmsh made it."""
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.sizes import SizeField
    from cadedge.mesh.worker import MeshJob, run_job

    def job(finish_by: float) -> MeshJob:
        return MeshJob(source="cyl", brep=shape_to_brep(cylinder.shape),
                       grid=dataclasses.replace(cylinder, shape=None), field=SizeField(cylinder), mode="nodes",
                       known_ok={f: 0 for f in range(1, cylinder.faces + 1)}, deadline=time.time() - 1,
                       finish_by=finish_by, hooks={"after_generate": ["cadedge.mesh.optimize:after_generate"],
                                                   "after_mesh": ["mesh_probes:smoothed"]})

    late = run_job(job(time.time() + 120))
    assert all(o.ok for o in late.faces)
    assert late.extras["mesh_probes:smoothed"]  # past the soft deadline, faces were still improved
    over = run_job(job(time.time() - 1))
    assert all(o.ok for o in over.faces) and over.extras["mesh_probes:smoothed"] == []


def test_past_the_deadline_with_nothing_meshed_the_first_faces_are_still_tried(cylinder):
    """A child restarted after the soft deadline when nothing was meshed before (its batch of first
    attempts hung, as on mesh_T106_V3 in sizes mode under load) meshes faces until one is meshed, so the
    job delivers a mesh; the rest are named out of time."""
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.sizes import SizeField
    from cadedge.mesh.worker import MeshJob, run_job

    job = MeshJob(source="cyl", brep=shape_to_brep(cylinder.shape), grid=dataclasses.replace(cylinder, shape=None),
                  field=SizeField(cylinder), mode="nodes", skip={}, known_ok={}, deadline=time.time() - 1)
    res = run_job(job)
    meshed = [o.face for o in res.faces if o.ok]
    assert len(meshed) == 1 and len(res.triangles)
    assert all("out of time" in o.attempts[-1][1] for o in res.faces if not o.ok)
