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
from cadedge.mesh.generate import BATCH_FACES, STRATEGIES, _chunk_size  # noqa: E402

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
