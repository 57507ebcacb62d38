"""Every face meshed or named: batches of first attempts, the watchdog's CPU-time bound, the one-size
fallback, a finer re-mesh that hangs, and a shape gmsh imports only in part.

Real gmsh in a child process and real OCCT shapes; faults are injected into the child through hooks
(``mesh_faults.py``).
"""

from __future__ import annotations

import time

import numpy as np
import pytest

pytest.importorskip("gmsh")
pytest.importorskip("trimesh")

import cadedge  # noqa: E402
from cadedge.mesh import mesh_shape  # noqa: E402
from cadedge.mesh.strategies import STRATEGIES  # noqa: E402

from conftest import FIXTURES, listed_cone_and_sphere, listed_step_with_pieces_swapped  # noqa: E402

ALD = 1e-2
FAULT_FACE = 2  # mesh_faults.FAULT_FACE
ONE_SIZE = next(s.name for s in STRATEGIES if s.uniform)


@pytest.fixture(scope="module")
def cylinder() -> cadedge.ShapeGrid:
    return cadedge.refine_shape(FIXTURES / "cylinder.step", ald=ALD, max_growth=2.0)


def _every_face(result) -> None:
    assert result.ok, result.problems(verbose=True)
    assert set(np.unique(result.triangle_faces)) == set(range(1, result.grid.faces + 1))


def test_a_busy_hang_is_caught_by_cpu_time_and_the_face_meshes_with_one_size(cylinder):
    """A spinning attempt is stopped once it has used ``face_timeout`` of CPU; its batch is meshed face by
    face, and the face goes on to the one-size strategy (the others on the same sizes are barred)."""
    t0 = time.monotonic()
    result = mesh_shape(cylinder, hooks={"before_face": ["mesh_faults:spin"]}, timeout=120, face_timeout=2)
    assert time.monotonic() - t0 < 60
    _every_face(result)
    face = next(o for o in result.faces if o.face == FAULT_FACE)
    assert face.strategy == ONE_SIZE and "hung" in face.attempts[0][1]
    assert any("one by one" in n for n in result.notes)  # the batch it was in
    assert all(o.strategy == STRATEGIES[0].name for o in result.faces if o.face != FAULT_FACE)


def test_an_attempt_on_faces_with_many_boundary_segments_gets_a_longer_bound():
    from cadedge.mesh.isolate import MAX_BOUND_WEIGHT, SEGMENTS_PER_BOUND, attempt_bound

    segments = {1: 300, 5: 74_464, 6: 336}
    assert attempt_bound("batch 1 6", 60.0, segments) == 60.0
    assert attempt_bound("batch 5 6", 60.0, segments) == pytest.approx(60.0 * 74_800 / SEGMENTS_PER_BOUND)
    assert attempt_bound("face 5 0", 60.0, segments) == pytest.approx(60.0 * 74_464 / SEGMENTS_PER_BOUND)
    assert attempt_bound("refine 5 5 5", 60.0, segments) == 60.0 * MAX_BOUND_WEIGHT
    assert attempt_bound("face 6 3", 60.0, segments) == 60.0  # the strategy's index is not a face


def test_a_slow_face_with_many_boundary_segments_is_not_stopped_as_hung(cylinder, monkeypatch):
    """The same busy attempt (3 s of CPU against a 1.5 s bound) is stopped as hung on the cylinder as it
    is, and meshes with the first strategy when its boundary counts as large (the bound's segments
    lowered so the cylinder's faces get three times the bound)."""
    from cadedge.mesh import isolate

    hooks = {"before_face": ["mesh_faults:busy_a_while"]}
    slow = next(o for o in mesh_shape(cylinder, hooks=hooks, timeout=120, face_timeout=1.5).faces
                if o.face == FAULT_FACE)
    assert "hung" in slow.attempts[0][1]
    monkeypatch.setattr(isolate, "SEGMENTS_PER_BOUND", 1)
    result = mesh_shape(cylinder, hooks=hooks, timeout=120, face_timeout=1.5)
    _every_face(result)
    assert all(o.strategy == STRATEGIES[0].name for o in result.faces)


def test_one_curvature_size_follows_the_sampled_curvature():
    """On a sphere of radius 2 the size is 2 pi R / per_circle; on a plane there is none."""
    import gmsh

    from cadedge.mesh.generate import uniform_curvature_size
    from cadedge.mesh.gmsh_model import gmsh_session

    with gmsh_session():
        gmsh.model.occ.addSphere(0, 0, 0, 2.0)
        gmsh.model.occ.addRectangle(5, 0, 0, 1, 1)
        gmsh.model.occ.synchronize()
        assert uniform_curvature_size(1, 20.0) == pytest.approx(2 * np.pi * 2.0 / 20.0, rel=1e-3)
        assert uniform_curvature_size(2, 20.0) is None


def test_gmsh_curvature_sizes_are_held_to_the_face_triangle_budget(monkeypatch):
    """A sphere of radius 2 at 200 triangles per 2 pi would take about 29 000 triangles; with a budget of
    2 000 a face gmsh is given the count that fills it with about that many, and meshes it so. A torus
    R 35, r 0.2 (a small fillet along a 220 mm edge) at 57 per 2 pi would take 1.3 million triangles: it
    gets the count of the real budget, 400 000."""
    import gmsh

    import cadedge.mesh.budget as budget
    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.interior import install, sized_per_circle, use_per_circle

    with gmsh_session():
        gmsh.model.occ.addSphere(0, 0, 0, 2.0)
        gmsh.model.occ.addTorus(10, 0, 0, 35.0, 0.2)
        gmsh.model.occ.synchronize()
        install([])
        torus = sized_per_circle(2, 57.0)
        assert 2.3 * 4 * np.pi ** 2 * 35 * 0.2 * (57.0 / (2 * np.pi * 0.2)) ** 2 > 1.2e6
        assert 2.3 * 4 * np.pi ** 2 * 35 * 0.2 * (torus / (2 * np.pi * 0.2)) ** 2 == pytest.approx(4e5, rel=0.01)
        monkeypatch.setattr(budget, "MAX_FACE_TRIANGLES", 2_000)
        install([])
        use_per_circle(1, 200.0)
        assert gmsh.option.getNumber("Mesh.MeshSizeFromCurvature") == pytest.approx(sized_per_circle(1, 200.0), abs=1)
        gmsh.model.setVisibility([(2, 2)], 0)
        gmsh.option.setNumber("Mesh.MeshOnlyVisible", 1)
        gmsh.model.mesh.generate(2)
        assert 1_400 < len(gmsh.model.mesh.getElementsByType(2, 1)[0]) < 2_600


def test_a_hang_while_meshing_a_face_again_finer_keeps_it_as_first_meshed(cylinder):
    """The re-mesh for the surface target announces each face (``refine F``): when it hangs, the new child
    skips that face's re-mesh and delivers every face."""
    result = mesh_shape(cylinder, hooks={"after_generate": ["mesh_faults:hang_refining"]}, timeout=120,
                        face_timeout=2)
    _every_face(result)
    assert any(f"face {FAULT_FACE}: meshing it again finer" in n for n in result.notes)


def test_a_hang_while_meshing_faces_again_together_keeps_them_all_as_first_meshed(cylinder):
    """Faces meshed again in one gmsh call (``refine F1 F2``): a hang there bars all of them."""
    result = mesh_shape(cylinder, hooks={"after_generate": ["mesh_faults:hang_refining_together"]}, timeout=120,
                        face_timeout=2)
    _every_face(result)
    assert any("faces 1, 3: meshing them together again finer" in n for n in result.notes)


def test_faces_meshed_again_share_a_gmsh_call_within_five_percent():
    """Re-meshes are grouped by curvature count (each gmsh call walks the whole model): counts within
    :data:`~cadedge.mesh.remesh.SHARE` share a call at the largest, never coarser than a face needs."""
    from cadedge.mesh.remesh import BATCH_FACES, groups

    got = groups({1: 20.0, 2: 20.9, 3: 30.0, 4: 20.4, 5: 31.0, 6: 40.0})
    assert got == [(20.9, [1, 4, 2]), (31.0, [3, 5]), (40.0, [6])]
    assert groups({1: 20.0, 2: 20.5}, share=1.0) == [(20.0, [1]), (20.5, [2])]
    many = groups({s: 10.0 for s in range(1, 2 * BATCH_FACES + 2)})
    assert [len(g) for _, g in many] == [BATCH_FACES, BATCH_FACES, 1]
    # faces on the k**-1/2 size callback (gmsh's curvature sizes off) never share a call with the others
    assert groups({1: 20.0, 2: 20.4, 3: 20.2}, sizing={2: "sampled"}) == [(20.2, [1, 3]), (20.4, [2])]
    assert groups({1: 20.0, 2: 20.4, 3: 20.2}, sizing={2: "sampled", 3: "floored"}) == [
        (20.0, [1]), (20.2, [3]), (20.4, [2])]


def _box_and_open_face():
    """A 10 mm box and, beside it, a planar face whose wire is two disjoint segments: gmsh cannot fix that
    wire with or without its wire fixing ("Could not fix wire in surface 7")."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.Geom import Geom_Plane
    from OCP.gp import gp_Dir, gp_Pnt
    from OCP.TopoDS import TopoDS_Compound, TopoDS_Face, TopoDS_Wire

    b = BRep_Builder()
    wire = TopoDS_Wire()
    b.MakeWire(wire)
    b.Add(wire, BRepBuilderAPI_MakeEdge(gp_Pnt(20, 0, 0), gp_Pnt(30, 0, 0)).Edge())
    b.Add(wire, BRepBuilderAPI_MakeEdge(gp_Pnt(30, 10, 0), gp_Pnt(20, 10, 0)).Edge())
    face = TopoDS_Face()
    b.MakeFace(face, Geom_Plane(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 1e-7)
    b.Add(face, wire)
    compound = TopoDS_Compound()
    b.MakeCompound(compound)
    b.Add(compound, BRepPrimAPI_MakeBox(10, 10, 10).Shape())
    b.Add(compound, face)
    return compound


def test_a_shape_gmsh_imports_only_in_part_meshes_the_rest_and_names_the_face(tmp_path):
    out = tmp_path / "part.msh"
    result = mesh_shape(_box_and_open_face(), ald=ALD, output=out)
    assert result.error is None and not result.ok
    assert [f.face for f in result.failures] == [7]
    assert "Could not fix wire" in result.failures[0].reason
    assert set(np.unique(result.triangle_faces)) == set(range(1, 7))
    assert result.check.ok and out.exists() and result.output == out
    assert any("only in part" in n for n in result.notes)


def test_the_hard_timeout_delivers_the_faces_already_meshed(cylinder, tmp_path):
    """A child stuck after meshing (no attempt under way, so only the hard timeout ends it) is killed; the
    faces it delivered as it went make a complete, watertight mesh, written by meshio."""
    trimesh = pytest.importorskip("trimesh")
    out = tmp_path / "c.stl"
    result = mesh_shape(cylinder, output=out, hooks={"after_generate": ["mesh_faults:hang_after_meshing"]},
                        timeout=20, face_timeout=100)
    assert result.error is None and not result.failures, result.problems()
    assert set(np.unique(result.triangle_faces)) == set(range(1, cylinder.faces + 1))
    assert result.check.ok and all(s.watertight for s in result.check.shells)
    assert any("stopped" in n and "delivered" in n for n in result.notes)
    assert result.output == out and trimesh.load(out).is_watertight


def _msh_groups(path) -> tuple[dict, dict]:
    """Physical groups of a .msh file read by gmsh: {(dim, tag): name} and {(dim, tag): element count}."""
    import gmsh

    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        names, counts = {}, {}
        for dim, tag in gmsh.model.getPhysicalGroups():
            names[(dim, tag)] = gmsh.model.getPhysicalName(dim, tag)
            counts[(dim, tag)] = sum(len(gmsh.model.mesh.getElements(dim, e)[1][0])
                                     for e in gmsh.model.getEntitiesForPhysicalGroup(dim, tag))
        return names, counts
    finally:
        gmsh.finalize()


def test_a_hard_timeout_mesh_keeps_its_groups_and_names_the_missing_face(cylinder, tmp_path):
    """A child that loses face 2 and then hangs: the hard timeout delivers faces 1 and 3 in a .msh with the
    physical groups ``face <id>`` / ``edge <id>`` gmsh's writer gives, and the report names face 2."""
    out = tmp_path / "c.msh"
    result = mesh_shape(cylinder, output=out, hooks={"after_generate": ["mesh_faults:lose_a_face_and_hang"]},
                        timeout=20, face_timeout=100)
    assert result.error is None and [f.face for f in result.failures] == [FAULT_FACE]
    assert "not finished: no result within 20 s" in result.failures[0].reason
    assert set(np.unique(result.triangle_faces)) == {1, 3}
    assert result.check.ok, result.check.problems  # the missing face's edges are open boundaries, not cracks
    report = {f.face: f for f in result.report.faces}
    assert report[FAULT_FACE].status == "failed" and "no result within" in report[FAULT_FACE].note
    assert report[1].status != "failed" and report[1].triangles > 0
    assert any(f"face {FAULT_FACE}" in line and "no result within" in line for line in result.problems())
    names, counts = _msh_groups(out)
    assert {k: v for k, v in names.items() if k[0] == 2} == {(2, 1): "face 1", (2, 3): "face 3"}
    assert counts[(2, 1)] + counts[(2, 3)] == len(result.triangles)
    edges = {e.id for e in cylinder.edges if not e.degenerate}
    assert {k[1] for k in names if k[0] == 1} == edges
    assert all(names[(1, e)] == f"edge {e}" and counts[(1, e)] > 0 for e in edges)


def test_a_failed_gmsh_writer_does_not_lose_the_mesh(cylinder, tmp_path):
    """gmsh's writer failing after every face meshed (it did, giving no reason, on a shape it had imported
    only in part) turned the whole job into "internal error" on every face: the faces' meshes are now
    written by meshio, with their groups, and the failure is a note."""
    out = tmp_path / "c.msh"
    plain = mesh_shape(cylinder)
    result = mesh_shape(cylinder, output=out, hooks={"before_write": ["mesh_faults:break_the_writer"]})
    _every_face(result)
    assert result.output == out and result.check.ok and all(s.watertight for s in result.check.shells)
    assert any(n.startswith("gmsh's writer failed (giving no reason)") for n in result.notes)
    names, counts = _msh_groups(out)
    assert {k: v for k, v in names.items() if k[0] == 2} == {(2, f): f"face {f}" for f in (1, 2, 3)}
    assert sum(counts[(2, f)] for f in (1, 2, 3)) == len(result.triangles) == len(plain.triangles)


def test_a_hard_timeout_after_the_re_mesh_delivers_the_final_mesh(cylinder):
    """A face meshed again finer after its first meshing is delivered again: a child killed before writing
    hands over the mesh a finished run gives, not the first meshes."""
    first = mesh_shape(cylinder)
    t0 = time.monotonic()
    done = mesh_shape(cylinder, hooks={"after_generate": ["mesh_faults:remesh_finer"]})
    took = time.monotonic() - t0
    assert np.sum(done.triangle_faces == FAULT_FACE) > np.sum(first.triangle_faces == FAULT_FACE)
    # finish_by (0.85 of the timeout) stops the face optimiser, which would give other triangles:
    # the timeout leaves the killed run more than twice what the finished run took (on a loaded machine too)
    killed = mesh_shape(cylinder, hooks={"after_generate": ["mesh_faults:remesh_finer"],
                                         "before_write": ["mesh_faults:hang_before_writing"]},
                        timeout=max(20.0, 4.0 * took), face_timeout=100)
    assert killed.error is None and not killed.failures
    assert any("stopped" in n for n in killed.notes)
    for f in range(1, cylinder.faces + 1):
        assert np.sum(killed.triangle_faces == f) == np.sum(done.triangle_faces == f)
    used = np.unique(done.nodes[done.triangles.ravel()], axis=0)
    assert np.array_equal(np.unique(killed.nodes[killed.triangles.ravel()], axis=0), used)


def test_a_face_broken_after_meshing_is_meshed_again(cylinder):
    """A face whose triangles stop matching its boundary after the after-meshing steps (here one triangle
    dropped) is checked again and meshed from scratch: the mesh stays watertight."""
    result = mesh_shape(cylinder, hooks={"after_generate": ["mesh_faults:break_a_face"]})
    _every_face(result)
    assert all(s.watertight for s in result.check.shells)
    assert any(f"faces {FAULT_FACE}: the steps after meshing" in n for n in result.notes)


def _two_faces_on_one_loop():
    """Two gmsh surfaces on one 10 x 10 square loop, one segment a side, each meshed as the same two
    triangles on the corners (a lens flattened: the wing's revolved face and its cap at ALD 1e-1), and a
    re-check context for them with the progress lines it writes."""
    import types

    import gmsh

    from cadedge.mesh.outcomes import FaceOutcome

    occ = gmsh.model.occ
    pts = [occ.addPoint(x, y, 0) for x, y in ((0, 0), (10, 0), (10, 10), (0, 10))]
    loop = occ.addCurveLoop([occ.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)])
    occ.addPlaneSurface([loop])
    occ.addPlaneSurface([loop])
    occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeMin", 20.0)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 20.0)
    gmsh.model.mesh.generate(1)  # one segment a side; both faces as two triangles on the corners only
    corner = [int(gmsh.model.mesh.getNodes(0, p)[0][0]) for p in pts]
    for s in (1, 2):
        first = int(gmsh.model.mesh.getMaxElementTag()) + 1
        gmsh.model.mesh.addElementsByType(s, 2, [first, first + 1], [corner[i] for i in (0, 1, 2, 0, 2, 3)])
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
    lines: list[str] = []
    ctx = types.SimpleNamespace(emap=types.SimpleNamespace(face_of_surface={1: 1, 2: 2}),
                                outcomes={s: FaceOutcome(face=s, surface=s, strategy="x") for s in (1, 2)},
                                job=types.SimpleNamespace(no_refine=set()), progress=lines.append)
    return ctx, lines


def test_two_faces_on_one_boundary_loop_get_interior_nodes():
    """Faces that repeat each other's triangles are meshed again finer, with interior nodes, so no inner
    edge is shared any more; each re-mesh is announced to the watchdog as a finer re-mesh."""
    import gmsh

    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.worker import _overlapping_faces, _recheck

    with gmsh_session():
        ctx, lines = _two_faces_on_one_loop()
        overlap = _overlapping_faces([1, 2])
        assert set(overlap) == {1, 2} and overlap[1] == pytest.approx(10 * np.sqrt(2))
        notes: list[str] = []
        _recheck(ctx, notes)
        assert all(o.ok for o in ctx.outcomes.values()) and _overlapping_faces([1, 2]) == {}
        assert all(len(gmsh.model.mesh.getNodes(2, s, includeBoundary=False)[0]) for s in (1, 2))
        assert any("faces 1, 2: triangulated from their boundary nodes alone" in n for n in notes)
        assert lines == ["refine 1", "refined 1", "refine 2", "refined 2"]


def test_the_recheck_meshes_no_face_finer_than_its_triangle_budget(monkeypatch):
    """The re-check's sizes stop at the size that fills the face with its triangle budget: a 1.1e-13 inner
    edge shared with another face (a Fusion caster part) asked gmsh for sizes of 3e-14 on a face of
    square millimetres, and it ran until the job's timeout. Here the square (area 100) is meshed again
    at a quarter of its shared diagonal with the default budget, and at the size that fills it with 6
    triangles when that is all it may have."""
    import gmsh

    from cadedge.mesh import generate
    from cadedge.mesh.budget import filling_size, held
    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.worker import _recheck

    asked: list[float] = []
    mesh_faces = generate.mesh_faces

    def recording(surfaces, face_of, **kw):
        asked.append(gmsh.option.getNumber("Mesh.MeshSizeMax"))
        return mesh_faces(surfaces, face_of, **kw)

    monkeypatch.setattr(generate, "mesh_faces", recording)
    sizes = {}
    for budget in (6, 400_000):
        asked.clear()
        with gmsh_session(), held(budget):
            ctx, _ = _two_faces_on_one_loop()
            _recheck(ctx, [])
            sizes[budget] = list(asked)
            floor = float(filling_size(100.0))
        assert floor == pytest.approx(np.sqrt(2.3 * 100 / budget))
    assert sizes[400_000] == pytest.approx([0.25 * 10 * np.sqrt(2)] * 2)
    assert sizes[6] == pytest.approx([np.sqrt(2.3 * 100 / 6)] * 2)


def test_a_face_whose_recheck_hung_before_is_kept_as_it_was():
    """A face whose re-mesh hung or crashed an earlier child (the watchdog put it in ``job.no_refine``) is
    not meshed again by the re-check: it keeps its triangles, and a note names it."""
    import gmsh

    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.worker import _recheck

    with gmsh_session():
        ctx, lines = _two_faces_on_one_loop()
        ctx.job.no_refine.add(2)
        notes: list[str] = []
        _recheck(ctx, notes)
        assert lines == ["refine 1", "refined 1"]
        assert len(gmsh.model.mesh.getElementsByType(2, 2)[0]) == 2  # its two triangles on the corners
        assert len(gmsh.model.mesh.getNodes(2, 1, includeBoundary=False)[0])
        assert any(n.startswith("faces 2: the re-check would have meshed them again") for n in notes), notes


def test_a_face_retried_on_curves_gmsh_already_meshed_keeps_every_curve_mesh():
    """A face that reaches the own-curve strategy when all its curves were replaced already (by a
    neighbour) has nothing to replace: ``gmsh.model.mesh.clear([])`` would delete the whole model's mesh,
    and every face after it failed with no nodes on its boundary (mesh_T106_V3 at ALD 1e-3: 0 of 8)."""
    import gmsh

    from cadedge.mesh.generate import clear, mesh_faces, remesh_curves
    from cadedge.mesh.gmsh_model import gmsh_session, surface_curve_uses

    with gmsh_session():
        gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.model.mesh.generate(1)
        nodes = len(gmsh.model.mesh.getNodes()[0])
        clear([])
        assert remesh_curves([]) == []
        assert len(gmsh.model.mesh.getNodes()[0]) == nodes
        surfaces = [t for _, t in gmsh.model.getEntities(2)]
        own = set(surface_curve_uses(surfaces[0]))  # as if a neighbour had replaced them
        first = next(k for k, s in enumerate(STRATEGIES) if s.own_curves)
        out = mesh_faces(surfaces, {}, skip={surfaces[0]: {k: "failed before" for k in range(first)}},
                         own_curves=own)
        assert all(o.ok for o in out.values())
        assert out[surfaces[0]].strategy == STRATEGIES[first].name


def test_a_face_with_a_sharp_ridge_is_meshed_alone_after_the_batches():
    """A face held at a size floor (its curvature has sharp ridges: it may take gmsh long) is not put in a
    batch with other faces, so a hang on it costs no other face: a box beside a thin elliptic tube
    (semi-axes 10 and 0.05: curvature 4 000 at its ends) has the tube's side meshed on its own, after the
    box's faces were batched. And it is meshed, within the target: gmsh's fallback from Frontal-Delaunay
    (taking triangles across the ridge for a failure) hung on it in every strategy."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeWire
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakePrism
    from OCP.BRep import BRep_Builder
    from OCP.gp import gp_Ax2, gp_Dir, gp_Elips, gp_Pnt, gp_Vec
    from OCP.TopoDS import TopoDS_Compound

    ellipse = BRepBuilderAPI_MakeEdge(gp_Elips(gp_Ax2(gp_Pnt(30, 0, 0), gp_Dir(0, 0, 1)), 10.0, 0.05)).Edge()
    cap = BRepBuilderAPI_MakeFace(BRepBuilderAPI_MakeWire(ellipse).Wire()).Face()
    tube = BRepPrimAPI_MakePrism(cap, gp_Vec(0, 0, 5.0)).Shape()
    box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 8.0, 6.0, 5.0).Shape()
    both = TopoDS_Compound()
    builder = BRep_Builder()
    builder.MakeCompound(both)
    builder.Add(both, box)
    builder.Add(both, tube)
    grid = cadedge.refine_shape(both, ald=ALD)
    said: list[str] = []
    result = mesh_shape(grid, progress=said.append, timeout=60)
    _every_face(result)
    assert result.report.worst_deficit <= ALD
    side = 7  # the box's 6 faces come first, then the tube's side and caps
    assert [r.surface for r in result.report.faces if r.face == side] == ["SurfaceOfExtrusion"]
    from cadedge.mesh.report import AFTER_MESH_HOOK

    assert side in result.extras[AFTER_MESH_HOOK]["floored"]  # held at a size floor: may take gmsh long
    together = [line for line in said if "together" in line]
    assert together and not any(f" {side}," in line or f" {side} " in line for line in together)
    assert any(line.endswith(f"face {side}") for line in said)


def test_a_face_whose_edges_gmsh_does_not_carry_still_gets_its_own_surface(tmp_path):
    """Faces are matched to gmsh's surfaces by their edges; edges no gmsh curve carries leave some faces
    with no exact match, and those kept gmsh's surface of their own id, which an edge match could have
    given to another face: gmsh's benchmark ellipses.brep (14 edges gmsh does not carry) left faces 21 and
    22 with no surface, their triangles labelled as faces 26 and 27 and missing from the ``.msh``. Here
    a cylinder's faces are handed to gmsh in reverse order and its two circles left unmatched: each cap
    must get its own surface, placed by where it is."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepTools import BRepTools
    from OCP.TopoDS import TopoDS_Compound

    from cadedge.mesh.gmsh_model import _match_faces, gmsh_session, import_brep, map_entities
    from cadedge.occt.topology import Topology

    grid = cadedge.refine_shape(FIXTURES / "cylinder.step", ald=1e-2)
    builder, compound = BRep_Builder(), TopoDS_Compound()
    builder.MakeCompound(compound)
    for face in reversed(Topology(grid.shape).faces):  # gmsh's surfaces: cap 3, cap 2, the cylinder
        builder.Add(compound, face)
    path = tmp_path / "reversed.brep"
    assert BRepTools.Write_s(compound, str(path))
    circles = [e.id for e in grid.edges if e.curve == "Circle"]
    assert len(circles) == 2 and grid.faces == 3
    with gmsh_session():
        import_brep(str(path))
        edges = map_entities(grid).edges
        assert map_entities(grid).faces == {1: 3, 2: 2, 3: 1}  # every edge matched: their sets decide
        faces = _match_faces(grid, {e: m for e, m in edges.items() if e not in circles})
    assert faces == {1: 3, 2: 2, 3: 1}  # before: {1: 3, 2: 2}, face 3 left out and surface 1 labelled face 1



def test_a_gmsh_surface_no_face_matches_is_named_and_not_meshed(cylinder):
    """A gmsh surface with no cadedge face (an import that splits a face or adds one) was meshed and
    labelled with its own tag, which can be another face's id: its triangles would have counted as that
    face's. Here a hook adds a free square to gmsh's model after the faces are matched: it is named in a
    note and left unmeshed: the mesh holds the cylinder's three faces, and only those."""
    result = mesh_shape(cylinder, hooks={"before_generate": ["mesh_faults:add_free_surface"]})
    assert result.error is None and not result.failures, result.problems()
    assert any(n.startswith("gmsh surface(s) 4 match no face") for n in result.notes), result.notes
    assert set(np.unique(result.triangle_faces)) == {1, 2, 3}  # before: face 4 too, the square's triangles
    assert result.check.ok and result.report.worst_deficit <= 1e-2


def test_an_edge_is_not_given_the_curve_of_its_id_beyond_that_curve_s_range():
    """An edge was given gmsh's curve of its own id when that curve, evaluated at the edge's parameters,
    gave the edge's points; gmsh evaluates a line beyond its range, so another piece of the edge's own
    line passed, and the edge's own curve was left to nothing (gmsh's ellipses.brep: edge 87 matched no
    curve and faces 50 and 51 were dropped at ALD 1e-3). Here cadedge's edge 5 is the line's piece [1, 2],
    gmsh's curve 5 its piece [0, 1]."""
    result = mesh_shape(listed_step_with_pieces_swapped(), ald=1e-2)
    assert any(d.startswith("edge 5 matched to gmsh curve 17 by geometry") for d in result.details), result.details
    assert not any("match no gmsh curve" in n for n in result.notes), result.notes  # before: edge 17
    assert result.ok and result.check.ok and result.check.missing_grid_nodes == 0, result.problems(verbose=True)
    assert abs(result.report.worst_deficit) <= 1e-2


def test_a_degenerate_edge_takes_the_gmsh_curve_at_its_point_not_the_one_of_its_id():
    """A degenerate edge was given gmsh's curve of its own id unchecked; where gmsh binds curves in
    another order, that is a real curve, and the edge whose curve it was matched none (gmsh meshed it
    itself, off the grid: gmsh's simple_plane.brep lost 7 edges so, three faces 1.6-3.4 times the area
    target). Here the cone's apex (edge 1) is gmsh's curve 5, and gmsh's curve 1 the circle."""
    result = mesh_shape(listed_cone_and_sphere(), ald=ALD)
    degenerate = [e.id for e in result.grid.edges if e.degenerate]
    assert degenerate == [1]
    assert any(d.startswith("degenerate edge 1 matched to gmsh curve") for d in result.details), result.details
    assert not any("match no gmsh curve" in n for n in result.notes), result.notes  # before: edge 5
    assert result.ok and result.check.missing_grid_nodes == 0, result.problems(verbose=True)
    assert abs(result.report.worst_deficit) <= ALD


def test_a_face_left_folded_is_meshed_again_by_meshadapt_only_where_it_is_small(monkeypatch):
    """A Frontal-Delaunay mesh whose folds are not undone goes to MeshAdapt, as gmsh's switch would send it,
    only where it holds at most ``ADAPT_SHARE`` of the face budget; a larger one keeps its mesh, node for
    node (a spring's 118 733-triangle coil face at 1e-3 was stopped as hung in MeshAdapt in every
    strategy). Here a disk's folds are made up (``unfolds`` answers no) and the budget is its size."""
    import gmsh

    from cadedge.mesh import budget, generate, optimize
    from cadedge.mesh.gmsh_model import gmsh_session

    monkeypatch.setattr(optimize, "unfolds", lambda surface: False)
    for share, remeshed in ((0.5, False), (2.0, True)):
        with gmsh_session():
            gmsh.model.occ.addDisk(0, 0, 0, 1.0, 1.0)
            gmsh.model.occ.synchronize()
            gmsh.option.setNumber("Mesh.MeshSizeMax", 0.1)
            gmsh.option.setNumber("Mesh.Algorithm", 6)
            gmsh.model.mesh.generate(2)
            before = gmsh.model.mesh.getElementsByType(2, 1)[1].copy()
            monkeypatch.setattr(budget, "MAX_FACE_TRIANGLES", len(before) // 3)  # the disk's triangles
            monkeypatch.setattr(generate, "ADAPT_SHARE", share)
            out = generate.keep_or_adapt([1], STRATEGIES[0])
            after = gmsh.model.mesh.getElementsByType(2, 1)[1]
            assert out == ({1: None} if remeshed else {})
            assert (len(after) != len(before) or not np.array_equal(after, before)) == remeshed


def test_a_curved_face_with_many_holes_is_meshed_by_delaunay_first():
    """gmsh's Frontal-Delaunay takes time on a curved face in proportion to its triangles times its holes
    (:data:`~cadedge.mesh.strategies.HOLED_ORDER`): a tube's walls, each with 18 holes, are meshed by
    Delaunay first; a plate's faces with as many holes, and the tube's faces with none, keep
    Frontal-Delaunay; every face meets the target."""
    bd = pytest.importorskip("build123d")
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_Cylinder, GeomAbs_Plane
    from OCP.TopAbs import TopAbs_FACE, TopAbs_WIRE
    from OCP.TopExp import TopExp

    from cadedge.mesh.strategies import HOLES
    from cadedge.occt.compat import TopoDS, TopTools_IndexedMapOfShape

    radial = (bd.Align.CENTER, bd.Align.CENTER, bd.Align.MIN)
    holes = [bd.Cylinder(0.8, 15, rotation=(0, 90, 0), align=radial)  # three rows of six, clear of the seam
             .moved(bd.Location((0, 0, 9 * (k // 6) - 9), (0, 0, 60 * k + 30 * (k // 6) + 20))) for k in range(18)]
    tube = bd.Cylinder(10, 30) - bd.Cylinder(9, 30) - holes
    plate = bd.Box(40, 30, 2) - [bd.Cylinder(0.8, 4).moved(bd.Location((6 * i - 15, 6 * j - 6, 0)))
                                 for i in range(6) for j in range(3)]
    shape = bd.Compound([tube, plate.moved(bd.Location((40, 0, 0)))]).wrapped
    result = mesh_shape(shape, ald=ALD)
    _every_face(result)
    assert result.report.worst_deficit <= ALD
    faces = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_FACE, faces)
    kinds = {}
    for outcome in result.faces:
        face = TopoDS.Face_s(faces.FindKey(outcome.face))
        wires = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(face, TopAbs_WIRE, wires)
        key = (BRepAdaptor_Surface(face).GetType(), wires.Extent() - 1 >= HOLES, wires.Extent() > 1)
        kinds.setdefault(key, []).append(outcome.strategy)
    assert kinds[(GeomAbs_Cylinder, True, True)] == ["Delaunay"] * 2  # the tube's walls
    assert kinds[(GeomAbs_Plane, True, True)] == ["Frontal-Delaunay"] * 2  # the plate's top and bottom
    assert "Frontal-Delaunay" in kinds[(GeomAbs_Cylinder, False, False)]  # the holes' own walls
