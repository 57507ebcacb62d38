"""A mesh job's faces in several gmsh processes at once (cadedge.mesh.shards): the joined mesh conforms."""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import pytest

pytest.importorskip("gmsh")
meshio = pytest.importorskip("meshio")

import cadedge  # noqa: E402
from cadedge.cli import main  # noqa: E402
from cadedge.errors import InputError  # noqa: E402
from cadedge.mesh import mesh_shape, shards  # noqa: E402
from cadedge.mesh.check import check_triangles  # noqa: E402
from cadedge.mesh.outcomes import FaceOutcome  # noqa: E402
from cadedge.mesh.strategies import STRATEGIES  # noqa: E402
from cadedge.mesh.worker import JobResult, MeshJob, empty_result  # noqa: E402

from conftest import FIXTURES, listed_cone_and_sphere  # noqa: E402

FAULT_FACE = 2  # tests/mesh_faults.py


@pytest.fixture
def split_small_jobs(monkeypatch):
    """Split every job, however small: the fixtures are far below MIN_SEGMENTS."""
    monkeypatch.setattr(shards, "MIN_SEGMENTS", 0)


@pytest.fixture(scope="module")
def cylinder() -> cadedge.ShapeGrid:
    return cadedge.refine_shape(FIXTURES / "cylinder.step", ald=1e-2, max_growth=2.0)


def test_a_split_job_meshes_every_face_once_and_conforms(split_small_jobs, tmp_path):
    """The bracket in two processes: every face meshed, watertight, every grid node a mesh node, the same
    faces and about the same triangles as in one process, and the .msh keeps the B-rep ids."""
    out = tmp_path / "b.msh"
    one = mesh_shape(FIXTURES / "bracket.step", ald=1e-2, workers=1)
    two = mesh_shape(FIXTURES / "bracket.step", ald=1e-2, workers=2, output=out,
                     hooks={"after_mesh": ["mesh_probes:share"]})
    assert not any("processes at once" in n for n in one.notes)
    assert any("meshed in 2 processes at once" in n for n in two.notes)
    for result in (one, two):
        assert result.ok, result.problems(verbose=True)
        assert result.check.missing_grid_nodes == 0 and all(s.watertight for s in result.check.shells)
    assert set(np.unique(two.triangle_faces)) == set(range(1, two.grid.faces + 1))
    shares = two.extras["mesh_probes:share"]  # each child's share of the minimum time budgets
    assert len(shares) == 2 and all(0 < s < 1 for s in shares) and sum(shares) == pytest.approx(1.0)
    assert abs(len(two.triangles) - len(one.triangles)) <= 0.02 * len(one.triangles)
    assert abs(two.report.worst_deficit) <= 1e-2 and not two.report.over_target
    mesh = meshio.read(out)
    assert {f"face {f}" for f in range(1, two.grid.faces + 1)} <= set(mesh.field_data)
    tags = np.concatenate([t for (c, t) in zip(mesh.cells, mesh.cell_data["gmsh:physical"]) if c.type == "triangle"])
    assert sorted(np.unique(tags)) == list(range(1, two.grid.faces + 1))


def test_processes_agree_where_gmsh_numbers_nodes_in_its_own_order(split_small_jobs):
    """gmsh renumbers the nodes after meshing, in the order it binds points and curves; where that is not
    cadedge's (a compound listing vertices and edges before the solid, as gmsh writes a model), the edge
    chains each process imposed all looked changed, and faces were dropped as meshed on edges their
    neighbours had changed (gmsh's simple_plane.brep in two processes: all 108)."""
    result = mesh_shape(listed_cone_and_sphere(), ald=1e-2, workers=2)
    assert any("meshed in 2 processes at once" in n for n in result.notes)
    assert not any("dropped" in n or "meshed again" in n for n in result.notes), result.notes
    assert result.ok and result.check.ok, result.problems(verbose=True)
    assert set(np.unique(result.triangle_faces)) == set(range(1, result.grid.faces + 1))


def test_only_the_curve_a_strategy_split_counts_as_changed(cylinder, tmp_path):
    """gmsh renumbers every node after each meshing call, in its entity order: once a strategy split the
    first curve, every curve bound after it had new node tags and, compared by tags, counted as changed
    (ellipses.brep at 1e-3: 36 edges, their neighbours meshed again and two faces dropped). Compared by
    points, only the split curve's edge is."""
    import gmsh

    from cadedge.mesh.generate import split_curves
    from cadedge.mesh.gmsh_model import gmsh_session, import_brep, map_entities, shape_to_brep
    from cadedge.mesh.impose import impose_edge_grids
    from cadedge.mesh.worker import changed_edges, curve_points

    path = tmp_path / "c.brep"
    path.write_bytes(shape_to_brep(cylinder.shape))
    with gmsh_session():
        import_brep(str(path))
        emap = map_entities(cylinder)
        imposed = sorted(impose_edge_grids(cylinder, emap).edge_nodes)
        gmsh.option.setNumber("Mesh.MeshOnlyEmpty", 1)
        gmsh.model.mesh.generate(1)
        before = curve_points(imposed, emap)
        first = min(imposed, key=lambda e: emap.edges[e].tag)
        tags = {e: gmsh.model.mesh.getNodes(1, emap.edges[e].tag)[0].tolist() for e in imposed if e != first}
        split_curves([emap.edges[first].tag])
        gmsh.model.mesh.generate(2)
        assert any(gmsh.model.mesh.getNodes(1, emap.edges[e].tag)[0].tolist() != t for e, t in tags.items())
        changed = changed_edges(before, emap)
    assert list(changed) == [first]
    points, _ = changed[first]
    assert len(points) == 2 * len(before[first]) - 1


def test_a_face_repeated_on_the_same_edges_joins_as_in_one_process(split_small_jobs):
    """A face repeated on the same edges (gmsh's dlr_f6.brep has one; here a cylinder's side and a twin
    of it): the two are meshed alike in one process, and the join welded their interior nodes, which
    stand at the same points, so every inner edge had four triangles; and on the seam, which both hold
    twice, it expected two. The check failed with a line for every triangle."""
    from OCP.BRep import BRep_Builder, BRep_Tool
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.BRepTools import BRepTools
    from OCP.TopoDS import TopoDS_Compound, TopoDS_Face

    from cadedge.occt.topology import Topology

    solid = BRepPrimAPI_MakeCylinder(5.0, 10.0).Shape()
    side = Topology(solid).faces[0]
    builder, twin, compound = BRep_Builder(), TopoDS_Face(), TopoDS_Compound()
    builder.MakeFace(twin, BRep_Tool.Surface_s(side), 1e-7)
    builder.Add(twin, BRepTools.OuterWire_s(side))
    builder.MakeCompound(compound)
    builder.Add(compound, solid)
    builder.Add(compound, twin)
    assert Topology(compound).shared_seams() == {2: (1, 4)}
    one = mesh_shape(compound, ald=1e-2, workers=1)
    two = mesh_shape(compound, ald=1e-2, workers=2)
    assert any("meshed in 2 processes at once" in n for n in two.notes)
    for result in (one, two):
        assert result.ok and result.check.ok, result.problems()[:3]
        assert np.array_equal(np.bincount(result.triangle_faces), np.bincount(one.triangle_faces))
    assert len(two.nodes) == len(one.nodes)  # the twin's interior nodes its own


def test_two_touching_solids_are_split_and_keep_their_own_nodes_where_they_touch(split_small_jobs):
    """Two boxes of an assembly side by side, each with its own faces where they touch: their points
    there are at the same coordinates but in two pieces of the shape, so the job is split (before, any
    two points at one place kept it in one process), and the join merges nodes only within a piece:
    each box's shell closed on its own, the same nodes as in one process."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.gp import gp_Pnt
    from OCP.TopoDS import TopoDS_Compound

    builder, assembly = BRep_Builder(), TopoDS_Compound()
    builder.MakeCompound(assembly)
    for x in (-1.0, 1.0):
        builder.Add(assembly, BRepPrimAPI_MakeBox(gp_Pnt(x, -1.0, -1.0), 2.0, 2.0, 2.0).Shape())
    grid = cadedge.refine_shape(assembly, ald=1e-2)
    assert not shards.coincident(grid)
    assert shards.coincident(dataclasses.replace(grid, edges=[
        dataclasses.replace(e, faces=[1]) for e in grid.edges]))  # as if in one piece: the points repeat
    one = mesh_shape(grid, workers=1)
    two = mesh_shape(grid, workers=2)
    assert any("meshed in 2 processes at once" in n for n in two.notes)
    for result in (one, two):
        assert result.ok and result.check.ok, result.problems()[:3]
        assert len(result.check.shells) == 2 and all(s.watertight for s in result.check.shells)
    assert len(two.nodes) == len(one.nodes)
    assert len(np.unique(two.nodes, axis=0)) < len(two.nodes)  # the touching points: a node in each box


@pytest.mark.parametrize("fallback", ["split", "own_curves"])
def test_a_neighbour_is_meshed_again_on_an_edge_another_process_changed(split_small_jobs, cylinder, fallback,
                                                                        tmp_path):
    """The cylinder's cap (face 2) in one process meshed only by a strategy that splits its curve or
    meshes it itself; the side, in the other process, was meshed on the imposed grid: it is meshed again
    on the cap's new curve, and the joined mesh conforms."""
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.isolate import run_isolated
    from cadedge.mesh.sizes import SizeField

    first = next(k for k, s in enumerate(STRATEGIES) if getattr(s, fallback))
    skip = {FAULT_FACE: {k: "barred by the test" for k in range(first)}}
    job = MeshJob(source="cyl", brep=shape_to_brep(cylinder.shape),
                  grid=dataclasses.replace(cylinder, shape=None, curves=None), field=SizeField(cylinder), mode="nodes",
                  skip=skip)
    out = tmp_path / "c.msh"
    res = run_isolated(job, output=out, workers=2)
    assert all(o.ok for o in res.faces), res.faces
    assert next(o for o in res.faces if o.face == FAULT_FACE).strategy == STRATEGIES[first].name
    assert any("meshed again on the changed edge" in n for n in res.notes), res.notes
    multiplicity = {(int(a), int(b)): int(n) for (a, b), n in zip(res.edge_pairs, res.edge_uses)}
    check = check_triangles(res.nodes, res.triangles, triangle_faces=res.triangle_faces,
                            edge_multiplicity=multiplicity)
    assert check.ok and all(s.watertight for s in check.shells)
    if fallback == "split":  # the cap's curve is not its grid any more, on both sides
        assert len(res.edge_pairs) > sum(e.segments for e in cylinder.edges if not e.degenerate)
    else:
        assert res.own_mesh_edges
    mesh = meshio.read(out)
    assert {"face 1", "face 2", "face 3"} <= set(mesh.field_data)


def test_faces_meshed_again_after_the_shards_get_the_time_then_left(split_small_jobs, cylinder, tmp_path):
    """The shards end past the job's kill point (their optimiser may run that long): the side, meshed again
    on the cap's split curve, gets its share of the time then left (11 s of 40), and is meshed, not
    stopped at its first attempt."""
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.isolate import KILL_SHARE, run_isolated
    from cadedge.mesh.sizes import SizeField

    first = next(k for k, s in enumerate(STRATEGIES) if s.split)
    job = MeshJob(source="cyl", brep=shape_to_brep(cylinder.shape),
                  grid=dataclasses.replace(cylinder, shape=None, curves=None), field=SizeField(cylinder), mode="nodes",
                  skip={FAULT_FACE: {k: "barred by the test" for k in range(first)}},
                  hooks={"after_mesh": ["mesh_faults:idle_past_the_kill_point"]})
    timeout = 40.0
    started = time.monotonic()
    res = run_isolated(job, output=tmp_path / "c.msh", workers=2, timeout=timeout)
    assert time.monotonic() - started > KILL_SHARE * timeout  # the shards did idle past the kill point
    assert any("meshed again on the changed edge" in n for n in res.notes), res.notes
    assert all(o.ok for o in res.faces), res.faces
    assert sorted(np.unique(res.triangle_faces)) == [1, 2, 3]


def test_a_split_job_past_its_timeout_joins_what_every_child_delivered(split_small_jobs, cylinder, tmp_path):
    """Both children hang once their faces are meshed: at the timeout each hands over its faces, named in
    a note of its own, and the joined mesh is whole and written."""
    out = tmp_path / "c.msh"
    result = mesh_shape(cylinder, workers=2, timeout=10, output=out,
                        hooks={"after_generate": ["mesh_faults:hang_after_meshing"]})
    assert result.ok and all(s.watertight for s in result.check.shells)
    stopped = [n for n in result.notes if "was stopped" in n]
    assert len(stopped) == 2 and all(n.startswith("the mesh process of face") for n in stopped)
    assert out.exists() and len(meshio.read(out).cells_dict["triangle"]) == len(result.triangles)


def _part(faces, meshed, changed=None, adopted=()):
    result = empty_result("")
    result.error = None
    result.faces = [FaceOutcome(face=f, surface=f, strategy="MeshAdapt" if f in meshed else None) for f in faces]
    result.changed_edges = changed or {}
    return shards.Part(faces=frozenset(faces), result=result, adopted=frozenset(adopted))


def test_conflicts_name_the_faces_to_mesh_again_and_those_that_cannot_be():
    from types import SimpleNamespace as E

    grid = E(faces=4, edges=[E(id=1, degenerate=False, faces=[1, 2]), E(id=2, degenerate=False, faces=[3, 4]),
                             E(id=3, degenerate=False, faces=[1, 3])])
    chain = (np.zeros((3, 3)), np.arange(3.0))
    a, b = _part([1, 3], {1, 3}, {1: chain}), _part([2, 4], {2, 4})
    adopt, redo, lost = shards.conflicts(grid, [a, b])
    assert list(adopt) == [1] and redo == {2} and not lost
    again = _part([2], {2}, adopted=[1])  # face 2 meshed again on edge 1: nothing left to do
    b.faces = frozenset({4})
    assert shards.conflicts(grid, [a, b, again]) == ({}, set(), set())
    # an edge changed on both sides: the first side's chain is imposed on the other's faces
    a, b = _part([1, 3], {1, 3}, {1: chain}), _part([2, 4], {2, 4}, {1: (np.ones((5, 3)), np.arange(5.0))})
    adopt, redo, lost = shards.conflicts(grid, [a, b])
    assert adopt[1] is chain and redo == {2} and not lost
    # a chain that cannot be imposed: the other side's faces on it are lost
    a, b = _part([1, 3], {1, 3}, {1: None}), _part([2, 4], {2, 4}, {2: chain})
    adopt, redo, lost = shards.conflicts(grid, [a, b])
    assert lost == {2} and redo == {3} and list(adopt) == [2]
    shards.drop_faces(b, {2}, "dropped")
    assert not next(o for o in b.result.faces if o.face == 2).ok


def test_extras_of_the_parts_are_merged():
    parts = []
    for faces, split in (([1], [1]), ([2], [])):
        part = _part(faces, set(faces))
        part.result.nodes = np.zeros((0, 3))
        part.result.extras = {"cadedge.mesh.fidelity:after_mesh": {"split": split, "stuck": [], "floored": {}}}
        parts.append(part)
    grid = type("G", (), {"faces": 2, "edges": []})()
    result, _, _ = shards.join(grid, parts, {})
    assert result.extras["cadedge.mesh.fidelity:after_mesh"]["split"] == [1]
    assert [o.ok for o in result.faces] == [True, True]
    assert isinstance(result, JobResult)


def test_workers_must_be_a_whole_number_of_processes(tmp_path, capsys):
    with pytest.raises(InputError, match="workers"):
        mesh_shape(FIXTURES / "cylinder.step", workers=0)
    code = main(["mesh", str(FIXTURES / "cylinder.step"), "-o", str(tmp_path / "c.msh"), "--workers", "two"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--workers must be a whole number" in err[0]
    assert not (tmp_path / "c.msh").exists()
