"""Batches of first attempts start small: a face that alone exceeds one attempt's bound costs only itself.

Real gmsh in a child process on the cylinder fixture; the fault is injected through a hook
(``mesh_faults.spin_first_face``).
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gmsh")
pytest.importorskip("trimesh")

import cadedge  # noqa: E402
from cadedge.mesh import mesh_shape  # noqa: E402
from cadedge.mesh.generate import BATCH_FACES, _chunk_size  # noqa: E402
from cadedge.mesh.strategies import STRATEGIES  # noqa: E402

from conftest import FIXTURES  # noqa: E402


def test_chunks_grow_from_one_face_to_the_batch_size_unless_faces_take_long():
    sizes, size = [], 0
    for _ in range(8):
        size = _chunk_size(size, 0.5, 60.0)
        sizes.append(size)
    assert sizes == [1, 2, 4, 8, 16, BATCH_FACES, BATCH_FACES, BATCH_FACES]
    assert _chunk_size(2, 17.5, 60.0) == 1  # two faces took 35 s: a quarter of the bound holds one
    assert _chunk_size(8, 4.0, 60.0) == 3 and _chunk_size(8, 4.0, None) == 16


def test_a_first_face_that_hangs_alone_costs_only_its_own_attempt():
    """Face 1 is the first batch, alone: when it hangs, the watchdog bars that face's first attempt (as for
    a face meshed on its own) instead of meshing a whole batch again one by one; the other faces keep
    their batches and their first strategy."""
    grid = cadedge.refine_shape(FIXTURES / "cylinder.step", ald=1e-2, max_growth=2.0)
    result = mesh_shape(grid, hooks={"before_face": ["mesh_faults:spin_first_face"]}, timeout=120, face_timeout=2)
    assert result.ok, result.problems(verbose=True)
    assert set(np.unique(result.triangle_faces)) == set(range(1, grid.faces + 1))
    assert any(n.startswith("face 1: hung") for n in result.notes)
    assert not any("one by one" in n for n in result.notes)
    assert all(o.strategy == STRATEGIES[0].name and not o.attempts for o in result.faces if o.face != 1)


def test_a_face_with_many_boundary_nodes_starts_from_the_older_triangulation_in_its_own_call(monkeypatch):
    """Two plane faces in one batch: a 2 x 100 strip with 1 001 nodes on each long side and a unit square
    with 12. gmsh's newer initial triangulation takes time growing with the square of the
    boundary nodes; the strip is meshed in a gmsh call of its own with the older one
    (``Mesh.OldInitialDelaunay2D``), the square with gmsh's default, and the option is reset after."""
    import gmsh

    from cadedge.mesh.generate import OLD_INITIAL_FROM, boundary_nodes, mesh_faces
    from cadedge.mesh.gmsh_model import gmsh_session

    with gmsh_session():
        strip, square = _rectangle(0.0, 2.0, 100.0, 3, 1001), _rectangle(20.0, 1.0, 1.0, 4, 4)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
        gmsh.model.mesh.generate(1)
        assert boundary_nodes(strip) >= OLD_INITIAL_FROM > boundary_nodes(square)
        calls = _record_calls(monkeypatch, "Mesh.OldInitialDelaunay2D")
        out = mesh_faces([strip, square], {}, batch_started=lambda faces: None)
        assert all(o.ok for o in out.values()), out
        assert sorted(calls) == [([strip], 1.0), ([square], 0.0)]
        assert gmsh.option.getNumber("Mesh.OldInitialDelaunay2D") == 0


def _record_calls(monkeypatch, option: str) -> list:
    """gmsh's ``generate`` patched to record each 2-D call: its visible surfaces and ``option``'s value."""
    import gmsh

    calls = []
    generate = gmsh.model.mesh.generate

    def recorded(dim=3):
        if dim == 2:
            visible = [s for _, s in gmsh.model.getEntities(2) if gmsh.model.getVisibility(2, s)]
            calls.append((visible, gmsh.option.getNumber(option)))
        return generate(dim)

    monkeypatch.setattr(gmsh.model.mesh, "generate", recorded)
    return calls


def _rectangle(x0, w, h, nw, nh):
    """A plane gmsh rectangle (geo kernel) with ``nw`` x ``nh`` nodes on its sides; returns its surface."""
    import gmsh

    geo = gmsh.model.geo
    p = [geo.addPoint(x0, 0, 0), geo.addPoint(x0 + w, 0, 0), geo.addPoint(x0 + w, h, 0), geo.addPoint(x0, h, 0)]
    lines = [geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
    surface = geo.addPlaneSurface([geo.addCurveLoop(lines)])
    for line, n in zip(lines, (nw, nh, nw, nh)):
        geo.mesh.setTransfiniteCurve(line, n)
    geo.synchronize()
    return surface


def test_every_gmsh_call_of_a_batch_is_announced_to_the_watchdog():
    """The second batch holds the strip and a square, meshed in two gmsh calls (different initial
    triangulations): each call is announced, so the watchdog, which bounds the attempt it last heard of,
    bounds the second one too. Announcing only the batch left the call after the first group's results
    unbounded: 260 s of a 300 s job on a face that hangs gmsh."""
    import gmsh

    from cadedge.mesh.generate import mesh_faces
    from cadedge.mesh.gmsh_model import gmsh_session

    with gmsh_session():
        first = _rectangle(-10.0, 1.0, 1.0, 4, 4)
        strip, square = _rectangle(0.0, 2.0, 100.0, 3, 1001), _rectangle(20.0, 1.0, 1.0, 4, 4)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
        gmsh.model.mesh.generate(1)
        announced = []
        out = mesh_faces([first, strip, square], {}, batch_started=announced.append)
        assert all(o.ok for o in out.values()), out
        assert announced == [[first], [strip, square], [square]]


def test_faces_of_the_same_options_share_their_batches_gmsh_calls(monkeypatch):
    """Six squares whose ``prepare`` gives alternate faces two curvature counts: taken in their order, the
    chunks of 1, 2 and 3 faces each mixed both, and gmsh was called once per count per chunk (5 calls; a
    3 379-face circuit board spent 0.2-1.6 s a call, whatever its faces). Taken in ``batch_order`` (the
    job's count per face, known before any hook runs), each chunk holds one count: 3 calls, each face
    meshed with its own count, every face's options still set by ``prepare`` inside its batch."""
    import gmsh

    from cadedge.mesh.generate import mesh_faces
    from cadedge.mesh.gmsh_model import gmsh_session

    def count(face: int) -> float:
        return 10.0 + face % 2

    def prepare(face: int, strategy: int) -> None:
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", count(face))

    with gmsh_session():
        squares = [_rectangle(3.0 * k, 1.0, 1.0, 4, 4) for k in range(6)]
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
        gmsh.model.mesh.generate(1)
        calls = _record_calls(monkeypatch, "Mesh.MeshSizeFromCurvature")
        mixed = mesh_faces(squares, {}, batch_started=lambda faces: None, prepare=prepare)
        assert all(o.ok for o in mixed.values()), mixed
        assert len(calls) == 5
        calls.clear()
        for s in squares:
            gmsh.model.mesh.clear([(2, s)])
        out = mesh_faces(squares, {}, batch_started=lambda faces: None, prepare=prepare, batch_order=count)
        assert all(o.ok for o in out.values()), out
    even, odd = [s for s in squares if s % 2 == 0], [s for s in squares if s % 2]
    assert calls == [(even[:1], 10.0), (even[1:], 10.0), (odd, 11.0)]
