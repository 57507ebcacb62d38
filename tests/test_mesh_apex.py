"""Boundary segments graded into a narrow cone's apex (cadedge.mesh.apex, cadedge.occt.cones): real OCCT
cones, their refined grids split, and a needle cone meshed through the whole mesher."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BRepPrimAPI import BRepPrimAPI_MakeCone  # noqa: E402
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt  # noqa: E402

from cadedge import refine_shape  # noqa: E402
from cadedge.mesh.apex import grade_to_apexes  # noqa: E402
from cadedge.mesh.developed import WRAP  # noqa: E402
from cadedge.occt.cones import apex_cones  # noqa: E402


def _cone(r1: float, r2: float, height: float):
    """A solid cone (OCP's own primitive) on the z axis from radius ``r1`` at z = 0 to ``r2``."""
    return BRepPrimAPI_MakeCone(gp_Ax2(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0)), r1, r2, height).Shape()


def _needle():
    """A cone of radius 1 and length 60 (a 1-degree half-angle), apex at (0, 0, 60)."""
    return _cone(1.0, 0.0, 60.0)


def test_cones_closing_at_an_apex_are_found_with_their_apex_and_half_angle():
    needle = refine_shape(_needle(), ald=1e-2)
    found = apex_cones(needle.shape)
    assert len(found) == 1 and needle.faces == 2  # the cone, not its base
    (face, (apex, sine)), = found.items()
    assert 1 in next(e for e in needle.edges if e.curve == "Line").faces and face == 1
    assert np.allclose(apex, [0.0, 0.0, 60.0], atol=1e-9)
    assert sine == pytest.approx(1.0 / np.hypot(1.0, 60.0))
    frustum = _cone(2.0, 1.0, 5.0)  # a cone face that does not reach its apex
    assert apex_cones(refine_shape(frustum, ald=1e-2).shape) == {}


def _even_seam(grid, pieces: int):
    """``grid`` with its seam (a line from the base to the apex) cut in ``pieces`` equal segments, as the
    face's curvature size cuts it before the apex is seen."""
    import dataclasses

    from cadedge.shapegrid import with_edges

    edges = []
    for e in grid.edges:
        if e.curve == "Line":
            t = np.linspace(0.0, 1.0, pieces + 1)
            e = dataclasses.replace(e, params=e.params[0] + t * (e.params[-1] - e.params[0]),
                                    points=e.points[0] + t[:, None] * (e.points[-1] - e.points[0]))
        edges.append(e)
    return with_edges(grid, edges)


def _from_apex(edge, apex) -> float:
    """The length of ``edge``'s segment that ends at ``apex``."""
    rho = np.linalg.norm(edge.points - apex, axis=1)
    return float(edge.segment_lengths[np.argmin(np.minimum(rho[:-1], rho[1:]))])


def test_the_seam_shrinks_into_the_apex_as_the_cone_narrows_and_keeps_its_points():
    grid = _even_seam(refine_shape(_needle(), ald=1e-2), 40)
    cones = apex_cones(grid.shape)
    graded = grade_to_apexes(grid, cones)
    apex, sine = next(iter(cones.values()))
    for before, after in zip(grid.edges, graded.edges):
        assert {tuple(p) for p in before.points.round(12)} <= {tuple(p) for p in after.points.round(12)}
        if before.curve != "Line":
            assert len(after.points) == len(before.points)  # the base circle does not reach the apex
            continue
        rho = np.linalg.norm(after.points - apex, axis=1)
        near = np.minimum(rho[:-1], rho[1:])
        away = near > 1e-9
        assert _from_apex(after, apex) == pytest.approx(_from_apex(before, apex))  # kept whole
        assert np.all(after.segment_lengths[away] <= 2.0 * np.pi * sine * near[away] / WRAP * (1 + 1e-6))
        assert len(after.points) > 2 * len(before.points)
    again = grade_to_apexes(graded, cones)  # graded once is graded for good
    assert [len(e.points) for e in again.edges] == [len(e.points) for e in graded.edges]


def test_a_needle_cone_has_no_sliver_but_its_apex_fan():
    """A 1 x 60 cone at 1e-2: the seam's segments (0.105 by the curvature size of its base) made
    triangles under 5 degrees beside it that its apex did not force (7 here, 16 from its STEP file) and
    nearly 1% under 20 degrees."""
    from cadedge.mesh import mesh_shape

    result = mesh_shape(_needle(), ald=1e-2)
    assert result.ok, result.problems()
    report = result.report
    assert report.unforced_slivers == 0
    assert all("apex" in s.reason for s in report.small_angles)
    assert report.below_20 < 1e-3
    assert report.worst_deficit <= 1e-2
