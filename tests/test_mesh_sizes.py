"""Sizes mode (``--mode sizes``: gmsh meshes the curves from our sizes), on real shapes through real gmsh."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest

gmsh = pytest.importorskip("gmsh")
cq = pytest.importorskip("cadquery")
pytest.importorskip("trimesh")

import cadedge  # noqa: E402
from cadedge.mesh import mesh_shape  # noqa: E402
from cadedge.mesh.generate import STRATEGIES  # noqa: E402

ALD = 1e-2
PROBE = {"after_mesh": ["mesh_probes:curve_segments"]}


def _segments_per_edge(result) -> dict[int, tuple[int, int]]:
    """Edge id -> (grid segments, gmsh curve segments) for every matched, non-degenerate edge."""
    probe = result.extras["mesh_probes:curve_segments"]
    return {e.id: (len(e.points) - 1, probe["segments"][probe["curve_of_edge"][e.id]])
            for e in result.grid.edges if not e.degenerate and e.id in probe["curve_of_edge"]}


def test_sizes_mode_meshes_a_cone_apex_with_curves_that_follow_the_grid():
    """gmsh's surface-curvature sizing split the seam running into a cone's apex far below the grid's
    spacing (3 times its segments here; 52 times on the cone of the hard model ``seams_and_poles``, where
    gmsh then failed three strategies on that face, for a minute): curves now follow the grids, and every
    face meshes at the first strategy."""
    cone = cq.Solid.makeCone(1.5, 0.0, 3.0).wrapped
    result = mesh_shape(cone, ald=ALD, mode="sizes", hooks=PROBE, timeout=120)
    assert result.ok, result.problems(verbose=True)
    assert {f.strategy for f in result.faces} == {STRATEGIES[0].name}
    assert not [n for n in result.notes if "hung" in n or "crashed" in n]
    for eid, (grid, ours) in _segments_per_edge(result).items():
        assert 0.5 * grid <= ours <= 2 * grid + 2, (eid, grid, ours)


def test_sizes_mode_sizes_an_unmatched_curve_from_its_neighbours():
    """A curve no edge grid maps to is graded from the size field on gmsh's own curve, not left at the
    largest size."""
    grid = cadedge.refine_shape(cq.Solid.makeCylinder(2.0, 5.0).wrapped, ald=ALD, max_growth=2.0)
    g = copy.copy(grid)
    g.edges = list(grid.edges)
    e = next(e for e in g.edges if e.curve == "Circle" and len(e.faces) == 2)
    g.edges[e.id - 1] = dataclasses.replace(e, points=e.points + np.array([0.0, 0.0, 0.05]), params=e.params + 0.01)
    result = mesh_shape(g, mode="sizes", hooks=PROBE, timeout=120)
    assert result.ok and result.unmatched_edges == [e.id], result.problems(verbose=True)
    probe = result.extras["mesh_probes:curve_segments"]
    segments = [probe["segments"][t] for t in probe["unmatched_curves"] if probe["segments"][t]]
    assert len(segments) == 1 and segments[0] >= 0.5 * (len(e.points) - 1), (segments, len(e.points) - 1)
