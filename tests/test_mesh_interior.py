"""Interiors of faces whose curvature varies are sized as k**-1/2 (cadedge.mesh.interior)."""

from __future__ import annotations

import numpy as np
import pytest

gmsh = pytest.importorskip("gmsh")
cq = pytest.importorskip("cadquery")

from cadedge.mesh import interior, mesh_shape  # noqa: E402
from cadedge.mesh.areas import triangle_areas  # noqa: E402
from cadedge.mesh.gmsh_model import gmsh_session  # noqa: E402

#: A truncated cone of radii 2 and 20 over a height of 30: its curvature cos(a) / r varies tenfold along
#: a generator.
R1, R2, HEIGHT = 2.0, 20.0, 30.0


def _cone_point(r: float) -> tuple[float, float, float]:
    """The point of the cone's side at radius ``r`` (in the x-z plane)."""
    return r, 0.0, HEIGHT * (r - R1) / (R2 - R1)


def test_sizes_follow_the_inverse_square_root_of_the_curvature():
    """Sizes at radii 4 and 16 of the cone are 2x apart (k**-1/2), not 4x (curvature sizing's k**-1);
    the face's mean curvature gets gmsh's curvature size 2 pi / (N k); the smaller of the callback's size
    and gmsh's own wins; flat faces, unsampled faces and curves are left to gmsh."""
    with gmsh_session():
        gmsh.model.occ.addCone(0, 0, 0, 0, 0, HEIGHT, R1, R2)
        gmsh.model.occ.synchronize()
        kinds = {s: gmsh.model.getType(2, s) for _, s in gmsh.model.getEntities(2)}
        (side,) = [s for s, k in kinds.items() if k != "Plane"]
        caps = [s for s, k in kinds.items() if k == "Plane"]
        assert interior.install([side] + caps) == [side]  # planar caps: nothing to sample
        interior.use_per_circle(side, 50.0)
        assert gmsh.option.getNumber("Mesh.MeshSizeFromCurvature") == 0  # gmsh's own sizes off for it
        size = {r: interior.SIZES(2, side, *_cone_point(r), 1e9) for r in (4.0, 16.0)}
        assert size[16.0] / size[4.0] == pytest.approx(2.0, rel=0.1)
        k_mean = np.cos(np.arctan((R2 - R1) / HEIGHT)) * (R2 - R1) / (0.5 * (R2 ** 2 - R1 ** 2))  # int k dA / A
        r_mean = np.cos(np.arctan((R2 - R1) / HEIGHT)) / k_mean  # where k is the mean
        assert interior.SIZES(2, side, *_cone_point(r_mean), 1e9) == pytest.approx(
            2 * np.pi / (50.0 * k_mean), rel=0.1)
        assert interior.SIZES(2, side, *_cone_point(4.0), 0.01) == 0.01
        assert interior.SIZES(1, side, *_cone_point(4.0), 7.0) == 7.0
        assert interior.SIZES(2, caps[0], 0.0, 0.0, 0.0, 7.0) == 7.0
        interior.use_per_circle(side, 50.0, uniform=True)  # the one-size strategy reads gmsh's option
        assert gmsh.option.getNumber("Mesh.MeshSizeFromCurvature") == 50.0
        assert interior.SIZES(2, side, *_cone_point(4.0), 7.0) == 7.0


def test_cone_interior_is_sized_as_inverse_square_root_of_curvature():
    """Meshed at a surface target, the cone side's interior triangles grow as r**0.5 along it (fitted on
    those away from its circles), where curvature sizing gave r**1; every face within the target."""
    cone = cq.Solid.makeCone(R1, R2, HEIGHT)
    result = mesh_shape(cone, ald=2e-3)
    assert result.ok, result.problems()
    assert result.report.worst_deficit <= 2e-3
    assert result.report.min_angle >= 20.0
    side = [f.face for f in result.report.faces if f.surface == "Cone"]
    assert len(side) == 1
    mine = result.triangle_faces == side[0]
    p = result.nodes[result.triangles[mine]]
    z = p[:, :, 2].mean(axis=1)
    r = R1 + (R2 - R1) * z / HEIGHT
    h = np.sqrt(triangle_areas(result.nodes, result.triangles[mine]))
    inside = (r > 5.0) & (r < 15.0)
    slope = np.polyfit(np.log(r[inside]), np.log(h[inside]), 1)[0]
    assert 0.3 <= slope <= 0.7, slope


def test_scale_spends_the_designed_deficit_within_the_size_bounds():
    """Unbounded, alpha is 2 pi / (N sqrt(k_mean)); where sizes are capped at ``hi`` over a flatter part,
    the deficit that leaves is spent on coarser sizes where the face is curved (the designed deficit
    (2 pi / N)**2 of the area is met), not left unused."""
    rng = np.random.default_rng(1)
    k = np.concatenate([rng.uniform(0.001, 0.01, 200), rng.uniform(0.05, 0.1, 200)])
    da = rng.uniform(0.5, 1.5, 400)
    n = 50.0
    alpha = interior.matched_scale(k, da, n, 1e-6, 1e6)
    assert alpha == pytest.approx(2 * np.pi / (n * np.sqrt(np.sum(k * da) / da.sum())), rel=1e-9)
    hi = 4.0  # the flat half would take sizes over 5
    capped = interior.matched_scale(k, da, n, 1e-6, hi)
    goal = (2 * np.pi / n) ** 2 * da.sum()
    assert interior.predicted(np.minimum(capped / np.sqrt(k), hi), k, da) == pytest.approx(goal, rel=1e-9)
    assert capped > alpha


def test_a_face_with_a_sharp_ridge_gets_a_size_floor_and_a_cylinder_does_not():
    """A thin elliptic tube (semi-axes 10 and 0.05: curvature 4 000 at its ends, 5e-4 at its sides) would
    be sized down to the smallest size along its ends; its floor fills it with about
    MAX_FACE_TRIANGLES triangles, and the callback holds its sizes at it. A cylinder's curvature is even:
    no floor."""
    from cadedge.mesh.budget import MAX_FACE_TRIANGLES

    with gmsh_session():
        tube = gmsh.model.occ.extrude([(1, gmsh.model.occ.addEllipse(0, 0, 0, 10.0, 0.05))], 0, 0, 5.0)
        pipe = gmsh.model.occ.addCylinder(30, 0, 0, 0, 0, 5.0, 2.0)
        gmsh.model.occ.synchronize()
        (ridged,) = [t for d, t in tube if d == 2]
        side = next(s for _, s in gmsh.model.getBoundary([(3, pipe)]) if gmsh.model.getType(2, s) != "Plane")
        areas = {s: gmsh.model.occ.getMass(2, s) for s in (ridged, side)}
        floors = interior.size_floors(areas, 1e-4)
        assert list(floors) == [ridged]
        assert floors[ridged] == pytest.approx(np.sqrt(2.3 * areas[ridged] / MAX_FACE_TRIANGLES))
        assert interior.size_floors(areas, 1.0) == {}  # the floor under the smallest size: nothing to hold
        interior.install([], floors)
        assert interior.SIZES(2, ridged, 10.0, 0.0, 1.0, 1e-4) == floors[ridged]
        assert interior.SIZES(2, ridged, 10.0, 0.0, 1.0, 7.0) == 7.0
        assert interior.SIZES(2, side, 32.0, 0.0, 1.0, 1e-4) == 1e-4
