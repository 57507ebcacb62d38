"""Cones meshed unrolled (cadedge.mesh.developed): the development's geometry on plain arrays, a gmsh cone
meshed flat and rolled back up, and a narrow cone through the whole mesher."""

from __future__ import annotations

import numpy as np
import pytest

from cadedge.mesh import flat
from cadedge.mesh.developed import Cone, _fan


def _cone(half_angle: float) -> Cone:
    """A cone with its apex at (0, 0, 6) opening downwards."""
    return Cone(apex=np.array([0.0, 0.0, 6.0]), axis=np.array([0.0, 0.0, -1.0]), e1=np.array([1.0, 0.0, 0.0]),
                e2=np.array([0.0, -1.0, 0.0]), sin=float(np.sin(half_angle)), cos=float(np.cos(half_angle)))


def test_unrolling_keeps_distances_from_the_apex_and_angles_round_the_axis():
    cone = _cone(np.arctan(1.0 / 6.0))
    rho = np.array([0.5, 1.0, 3.0, 6.08])
    phi = np.array([0.0, 1.0, 3.0, 6.0])
    points = cone.roll_up(rho, phi)
    radius = np.hypot(points[:, 0], points[:, 1])
    assert np.allclose(radius, (6.0 - points[:, 2]) / 6.0)  # on the cone
    back_rho, back_phi = cone.unroll(points)
    assert np.allclose(back_rho, rho) and np.allclose(back_phi, phi)


def test_the_apex_fan_closes_the_sector_in_three_triangles_at_least():
    """The seam's two copies beside the apex (keys 1 and 2, at the sector's two sides) are joined by new
    points round the apex; the apex's segments are gone and the boundary still closes."""
    sector = 2.0 * np.pi * 0.1
    keys = {(0, False): (0.0, 0.0), (1, False): (1.0, 0.0), (1, True): (1.0, sector), (2, False): (5.0, 0.0),
            (2, True): (5.0, sector)}
    segments = [((0, False), (1, False)), ((1, False), (2, False)), ((2, False), (2, True)),
                ((2, True), (1, True)), ((1, True), (0, False))]
    fan, kept = _fan(keys, segments, (0, False), sector)
    assert len(fan) == 3 and all(f[0] == (0, False) for f in fan)
    assert all((0, False) not in seg for seg in kept)
    turns = [abs(keys[f[2]][1] - keys[f[1]][1]) / 0.1 for f in fan]
    assert np.allclose(turns, 2.0 * np.pi / 3.0)  # each a third of the way round the axis
    index = {k: i for i, k in enumerate(keys)}
    loops = flat.loops([(index[a], index[b]) for a, b in kept])
    assert loops is not None and len(loops) == 1 and len(loops[0]) == len(kept)


def _needle_tip(gaps: np.ndarray, sector: float):
    """Plane points of a cone face's boundary near its apex: the apex, the seam's nodes at ``cumsum(gaps)``
    from it (on both sides of the sector) and a far segment closing the boundary; with :func:`_tip` run."""
    from cadedge.mesh.developed import _tip

    cone = _cone(np.arcsin(sector / (2.0 * np.pi)))
    rho = np.cumsum(gaps)
    keys = {(0, False): (0.0, 0.0)}
    for i, r in enumerate(rho, start=1):
        keys[(i, False)], keys[(i, True)] = (float(r), 0.0), (float(r), sector)
    n = len(rho)
    segments = ([((0, False), (1, False)), ((0, False), (1, True)), ((n, False), (n, True))]
                + [((i, side), (i + 1, side)) for i in range(1, n) for side in (False, True)])
    tri, left = _tip(keys, segments, (0, False), sector, cone)
    return cone, keys, tri, left


def test_the_tip_is_meshed_in_rings_out_to_where_the_sector_is_wide_enough():
    """A 1.4-degree cone whose seam has nodes every 0.066 near the apex (a 1 x 40 cone at 1e-2): the fan
    goes on in bands of 6 triangles while the sector is narrower than TIP segments; the triangles tile the
    rings' polygon, none turns more than a third of the way round, and the boundary left for gmsh closes."""
    from cadedge.mesh.developed import TIP
    from cadedge.grid import polygon_area

    sector = 2.0 * np.pi / 40.0
    gaps = np.full(30, 0.066)
    cone, keys, tri, left = _needle_tip(gaps, sector)
    rings = int(np.ceil(TIP / sector))  # ring i (at 0.066 i) steps out while 0.066 i sector < TIP 0.066
    assert len(tri) == 3 + 6 * (rings - 1)
    plane = {k: (r * np.cos(a), r * np.sin(a)) for k, (r, a) in keys.items()}
    outer = max(r for k, (r, _) in keys.items() if k[0] < 0)
    assert outer == pytest.approx(0.066 * rings)
    ring = sorted([k for k, (r, _) in keys.items() if abs(r - outer) < 1e-12], key=lambda k: keys[k][1])
    area = abs(polygon_area(np.array([plane[(0, False)]] + [plane[k] for k in ring])))
    areas = [abs(polygon_area(np.array([plane[k] for k in t]))) for t in tri]
    assert sum(areas) == pytest.approx(area) and min(areas) > 0
    turns = [np.ptp([keys[k][1] for k in t if keys[k][0] > 0]) / cone.sin for t in tri]
    assert max(turns) <= 2.0 * np.pi / 3.0 + 1e-9
    assert all(keys[k][0] >= outer - 1e-12 for seg in left for k in seg)  # the seam inside the rings is gone
    index = {k: i for i, k in enumerate(keys)}
    assert flat.loops([(index[a], index[b]) for a, b in left]) is not None


def test_a_cone_with_long_seam_segments_keeps_the_fan_only_where_the_sector_is_wide():
    """A 30-degree cone (the sector half a turn wide): the fan alone, 3 triangles."""
    _, _, tri, _ = _needle_tip(np.full(5, 0.066), np.pi)
    assert len(tri) == 3


def test_slivers_at_a_needle_cones_apex_are_named_forced_by_it():
    """The tip of a 1.4-degree cone rolled up: the fan's triangles (2.5 degrees at the apex) and the bands'
    triangles standing on the seam's segments are forced by the cone, with the reason; a band triangle
    standing on no curve segment is not."""
    from cadedge.mesh.quality import small_angles, triangle_angles

    sector = 2.0 * np.pi / 40.0
    gaps = np.full(30, 0.066)
    cone, keys, tri, _ = _needle_tip(gaps, sector)
    order = [k for k in keys if k[1] is False]  # the seam's two copies of a node are one node on the cone
    index = {k: i for i, k in enumerate(order)}
    index.update({k: index[(k[0], False)] for k in keys if k[1] is True})
    rho = np.array([keys[k][0] for k in order])
    nodes = cone.roll_up(rho, np.array([keys[k][1] for k in order]) / cone.sin)
    rows = np.array([[index[k] for k in t] for t in tri])
    seam = cone.roll_up(np.concatenate([[0.0], np.cumsum(gaps)]), np.zeros(len(gaps) + 1))
    smalls = small_angles(nodes, rows, np.ones(len(rows), dtype=int), cone.apex[None], face_edges={1: [seam]})
    low = triangle_angles(nodes, rows).min(axis=1) < 5.0
    at_apex = low & (rows == index[(0, False)]).any(axis=1)
    on_seam = low & ~at_apex & np.array([any(a[0] > 0 and b[0] > 0 and keys[a][1] == keys[b][1] in (0.0, sector)
                                             for a, b in zip(t, t[1:] + t[:1])) for t in tri])
    assert len(smalls) == low.sum() and at_apex.sum() == 3 and on_seam.sum() > 0 and (low & ~at_apex & ~on_seam).any()
    reasons = [s.reason for s in smalls if s.forced]
    assert sum("at least 3 triangles meet there" in r for r in reasons) == 3
    assert sum("curve segment" in r for r in reasons) == on_seam.sum()
    assert sum(not s.forced for s in smalls) == (low & ~at_apex & ~on_seam).sum()


gmsh = pytest.importorskip("gmsh")


def test_a_narrow_gmsh_cone_is_meshed_unrolled_on_its_curves():
    """A cone of radius 1 and height 6 (gmsh's OCC kernel): gmsh's own mesh of it is not conforming (its
    triangles overlap beside the seam near the apex); unrolled, every node is on the cone, the curves'
    segments bound it as they should (the seam twice) and its area is within the chords' of the cone's."""
    from cadedge.mesh.developed import cone_of, mesh_unrolled
    from cadedge.mesh.generate import clear, surface_ok
    from cadedge.mesh.gmsh_model import gmsh_session

    with gmsh_session():
        gmsh.model.occ.addCone(0, 0, 0, 0, 0, 6, 1.0, 0.0)
        gmsh.model.occ.synchronize()
        (side,) = [s for _, s in gmsh.model.getEntities(2) if gmsh.model.getType(2, s) == "Cone"]
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.05)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.2)
        gmsh.model.mesh.generate(2)
        assert not surface_ok(side)  # gmsh alone
        clear([(2, side)])
        cone = cone_of(side)
        assert cone is not None and cone.sin == pytest.approx(1.0 / np.hypot(1.0, 6.0))
        assert np.allclose(cone.apex, [0.0, 0.0, 6.0])
        assert mesh_unrolled(side, cone, 1) is None
        assert surface_ok(side)
        tags, coords, _ = gmsh.model.mesh.getNodes(2, side, includeBoundary=True)
        x = np.asarray(coords, dtype=float).reshape(-1, 3)
        assert np.allclose(np.hypot(x[:, 0], x[:, 1]), (6.0 - x[:, 2]) / 6.0, atol=1e-9)
        _, tri = gmsh.model.mesh.getElementsByType(2, side)
        nodes, xyz, _ = gmsh.model.mesh.getNodes()
        where = {int(t): i for i, t in enumerate(nodes)}
        p = np.asarray(xyz, dtype=float).reshape(-1, 3)[[where[int(t)] for t in tri]].reshape(-1, 3, 3)
        area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()
        assert 0.98 * np.pi * np.hypot(1.0, 6.0) < area < np.pi * np.hypot(1.0, 6.0)
        assert cone_of(next(s for _, s in gmsh.model.getEntities(2) if s != side)) is None  # its base


def test_a_narrow_cone_meshes_within_the_target(tmp_path):
    """A solid cone of radius 1 and height 6 at 1e-2: its cone face failed in every gmsh strategy (the
    last ones hung); unrolled it is meshed and within the target, with no folded triangle."""
    cq = pytest.importorskip("cadquery")
    from cadedge.mesh import mesh_shape

    result = mesh_shape(cq.Solid.makeCone(1.0, 0.0, 6.0), ald=1e-2)
    assert result.ok, result.problems()
    assert not result.failures
    assert all(abs(f.area_deficit) <= 1e-2 for f in result.report.faces)
    assert result.report.folded == 0


def test_a_hung_unrolled_meshadapt_leaves_the_unrolled_frontal_delaunay_to_try():
    """Strategies on the same sizes are skipped once one hangs; in an unrolled sector MeshAdapt's time grows
    faster than Frontal-Delaunay's, and a 1 x 200 cone at 1e-3 failed when the one hanging barred the
    other (Frontal-Delaunay meshes it in 49 s)."""
    from cadedge.mesh.strategies import NARROW_CONE_ORDER, STRATEGIES

    unrolled = [STRATEGIES[k] for k in NARROW_CONE_ORDER if STRATEGIES[k].unrolled == "cone"]
    assert [s.algorithm for s in unrolled] == [1, 6]  # MeshAdapt first: fewer triangles where it is in time
    assert unrolled[0].sizes != unrolled[1].sizes
    gmsh_own = [STRATEGIES[k] for k in NARROW_CONE_ORDER if not STRATEGIES[k].unrolled]
    assert len({s.sizes for s in gmsh_own if s.size_factor == 1.0 and not s.split and not s.own_curves
                and not s.uniform}) == 1  # on the cone's own face one hang still bars the others
