"""Surface fidelity of cadedge.mesh: per-face area deficit against OCCT's B-rep areas, triangle quality,
B-rep ids as physical groups, the mesh report (real cadquery parts, real OCCT, real gmsh)."""

from __future__ import annotations

import dataclasses

import json

import numpy as np
import pytest

gmsh = pytest.importorskip("gmsh")
cq = pytest.importorskip("cadquery")

from cadedge.cli import main  # noqa: E402
from cadedge.mesh import mesh_shape  # noqa: E402
from cadedge.mesh.boundary_fit import (CONE_CREDIT, CURVED_CREDIT, _fit_boundaries, _plane_deficits,  # noqa: E402
                                       _planar_credits, _planes, _sagittas, _shortest_shares,
                                       fit_boundaries, fit_curved)
from cadedge.mesh.fidelity import AIM, brep_face_areas, meshed_kinds, not_converging, prepare, surface_types  # noqa: E402
from cadedge.mesh.quality import triangle_angles  # noqa: E402
from cadedge.mesh.report import build_report, report_of, tolerance_bands  # noqa: E402

from conftest import CORPUS, FIXTURES, stadium_cap  # noqa: E402


def _sphere():
    return cq.Workplane().sphere(10.0).val()


def _torus():
    return cq.Solid.makeTorus(10.0, 3.0)


def _filleted_cylinder():
    return cq.Workplane().cylinder(20.0, 8.0).edges().fillet(2.0).val()


def _independent_deficits(result) -> np.ndarray:
    """1 - triangle area / B-rep area per face, computed here from the raw arrays."""
    areas = brep_face_areas(result.grid.shape)
    p = result.nodes[result.triangles]
    tri = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    mesh = np.array([tri[result.triangle_faces == f].sum() for f in range(1, len(areas) + 1)])
    return 1.0 - mesh / areas


@pytest.mark.parametrize("make", [_sphere, _torus, _filleted_cylinder], ids=["sphere", "torus", "fillet"])
def test_halving_eps_about_halves_the_worst_face_deficit(make):
    shape = make()
    worst = []
    for eps in (2e-2, 1e-2):
        result = mesh_shape(shape, ald=eps)
        assert result.ok, result.problems()
        deficits = _independent_deficits(result)
        assert np.all(np.abs(deficits) <= eps), (eps, deficits)
        assert result.report.worst_deficit == pytest.approx(np.abs(deficits).max(), rel=1e-9)
        worst.append(np.abs(deficits).max())
    assert 0.3 <= worst[1] / worst[0] <= 0.75, worst


def test_boundary_polygon_is_fitted_to_the_face_target():
    """A planar disk cap inscribed at the edges' ALD loses about 4x that ALD of its area: the cap's circle
    is split (grid points kept, nodes added) until the cap's polygon is within its share of the target."""
    import cadedge

    shape = cq.Workplane().cylinder(5.0, 10.0).val()
    eps = 1e-2
    grid = cadedge.refine_shape(shape, ald=eps)
    fitted, _ = fit_boundaries(grid, eps)
    kinds = surface_types(grid.shape)
    for before, after in zip(grid.edges, fitted.edges):
        kept = {tuple(p) for p in after.points}
        assert all(tuple(p) in kept for p in before.points)  # nodes are only ever added
        if before.curve == "Circle":
            assert after.segments >= 2 * before.segments
    result = mesh_shape(shape, ald=eps)
    caps = [f for f in result.report.faces if kinds[f.face - 1] == "Plane"]
    assert caps and all(abs(f.area_deficit) <= eps for f in caps)


def test_a_grid_ending_off_its_curve_within_its_vertices_tolerance_is_fitted():
    """A grid ends on its vertices' points, which may lie as far from its curve's ends as the vertices'
    tolerances allow, not only its edge's: dlr_f6.brep's edge 278 (tolerance 2e-7, ending 3.4e-5 off its
    curve at vertices of 2e-4 and 1e-3) was taken for a grid of another curve and never fitted, and its
    face was reported at 6.3e-3 against 1e-3. Here the cylinder's circles end 5e-5 off their curves."""
    import dataclasses

    import cadedge
    from cadedge.shapegrid import with_edges

    shape = cq.Workplane().cylinder(5.0, 10.0).val()
    eps = 1e-2
    grid = cadedge.refine_shape(shape, ald=eps)
    fitted, _ = fit_boundaries(grid, eps)
    circles = [i for i, e in enumerate(grid.edges) if e.curve == "Circle"]
    moved = list(grid.edges)
    for i in circles:
        e = moved[i]
        points = e.points.copy()
        points[[0, -1]] += np.array([0.0, 0.0, 5e-5])  # a closed circle: both ends on its one vertex
        moved[i] = dataclasses.replace(e, points=points, tolerance=1e-7)
    vertices = [dataclasses.replace(v, tolerance=1e-3) for v in grid.vertices]
    off = dataclasses.replace(with_edges(grid, moved), vertices=vertices)
    refitted, _ = fit_boundaries(off, eps)
    for i in circles:
        assert refitted.edges[i].segments == fitted.edges[i].segments > grid.edges[i].segments


def test_face_grading_cuts_a_grid_ending_off_its_curve_within_its_vertices_tolerance():
    """The face-wise grading (and the wedges' and apexes' cuts, through ``grading.cut_on_curve``) took a
    grid ending further than 10 times its edge's tolerance from its curve's ends for another curve's,
    as the boundary fit did (above): here the seam of a 20 x 2 cylinder, whose one segment its circles'
    spacing grades into 21, ends 5e-5 off its line (edge tolerance 1e-7, vertices 1e-3): it was left whole."""
    import dataclasses

    import cadedge
    from cadedge.mesh.grading import grade_faces
    from cadedge.shapegrid import with_edges

    grid = cadedge.refine_shape(cq.Workplane().cylinder(20.0, 2.0).val(), ald=1e-2)
    seam = next(i for i, e in enumerate(grid.edges) if e.curve == "Line")
    assert grid.edges[seam].segments == 1
    graded = grade_faces(grid).edges[seam].segments
    moved = list(grid.edges)
    e = moved[seam]
    moved[seam] = dataclasses.replace(e, points=e.points + np.array([5e-5, 0.0, 0.0]), tolerance=1e-7)
    vertices = [dataclasses.replace(v, tolerance=1e-3) for v in grid.vertices]
    off = dataclasses.replace(with_edges(grid, moved), vertices=vertices)
    assert grade_faces(off).edges[seam].segments == graded > 1


def test_face_grading_leaves_a_vertex_gap_to_its_curve_whole():
    """A grid whose curve ends off its vertex (within the vertex's tolerance) has a last segment that is
    mostly that gap: cut by arc, its points fell at the curve's end, 1e-14 apart on a Fusion caster part,
    and the grading took them for a spacing. Here the 20 x 2 cylinder's seam ends 6 from its line's end
    (vertices' tolerance 1): the gap stays one segment, the seam is graded as before, no piece is short."""
    import dataclasses

    import cadedge
    from cadedge.mesh.grading import grade_faces
    from cadedge.shapegrid import with_edges

    grid = cadedge.refine_shape(cq.Workplane().cylinder(20.0, 2.0).val(), ald=1e-2)
    seam = next(i for i, e in enumerate(grid.edges) if e.curve == "Line")
    e = grid.edges[seam]
    (u0, u1), (p0, p1) = e.params, e.points
    gap = np.cross(p1 - p0, [0.0, 0.0, 1.0] if abs((p1 - p0)[2]) < 0.9 * np.linalg.norm(p1 - p0) else [1.0, 0, 0])
    ends = np.vstack([p0, p1, p1 + 6.0 * gap / np.linalg.norm(gap)])
    moved = list(grid.edges)
    moved[seam] = dataclasses.replace(e, params=np.array([u0, u1 - 1e-9 * (u1 - u0), u1]), points=ends)
    vertices = [dataclasses.replace(v, tolerance=1.0) for v in grid.vertices]
    off = grade_faces(dataclasses.replace(with_edges(grid, moved), vertices=vertices)).edges[seam]
    assert off.segments > 10 and off.segment_lengths.min() > 0.1
    assert np.array_equal(off.points[-1], ends[-1]) and np.linalg.norm(off.points[-2] - p1) < 1e-6


def test_every_face_and_edge_is_a_physical_group(tmp_path):
    out = tmp_path / "bracket.msh"
    result = mesh_shape(FIXTURES / "bracket.step", ald=1e-2, output=out)
    assert result.ok and out.exists()
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(out))
        groups = gmsh.model.getPhysicalGroups()
        faces = sorted(t for d, t in groups if d == 2)
        edges = sorted(t for d, t in groups if d == 1)
        assert faces == list(range(1, result.grid.faces + 1))
        assert edges == [e.id for e in result.grid.edges if not e.degenerate]
        for fid in faces:
            assert gmsh.model.getPhysicalName(2, fid) == f"face {fid}"
            (surface,) = gmsh.model.getEntitiesForPhysicalGroup(2, fid)
            n = len(gmsh.model.mesh.getElementsByType(2, surface)[0])
            assert n == int(np.sum(result.triangle_faces == fid))  # the group holds that face's triangles
        assert gmsh.model.getPhysicalName(1, edges[0]) == f"edge {edges[0]}"
    finally:
        gmsh.finalize()


def test_report_per_face_and_json(tmp_path):
    result = mesh_shape(FIXTURES / "cylinder.step", ald=1e-2)
    rep = result.report
    assert [f.face for f in rep.faces] == list(range(1, result.grid.faces + 1))
    assert sorted(f.surface for f in rep.faces) == ["Cylinder", "Plane", "Plane"]
    assert sum(f.triangles for f in rep.faces) == len(result.triangles)
    assert all(f.status == "ok" for f in rep.faces)
    np.testing.assert_allclose([f.area_deficit for f in rep.faces], _independent_deficits(result), atol=1e-12)
    angles = triangle_angles(result.nodes, result.triangles).min(axis=1)
    assert rep.min_angle == pytest.approx(angles.min())
    assert rep.below_20 == pytest.approx(np.mean(angles < 20.0))
    assert any("worst |area deficit|" in line for line in result.lines())
    data = json.loads(rep.write(tmp_path / "r.json").read_text())
    assert data["schema"] == "cadedge.meshreport/1" and len(data["faces"]) == 3


def test_faces_over_target_are_named_with_their_deficit():
    """The same mesh judged against a target it was not made for: every face over it is named."""
    result = mesh_shape(FIXTURES / "cylinder.step", ald=1e-2)
    rep = build_report(result.nodes, result.triangles, result.triangle_faces,
                       brep_areas=brep_face_areas(result.grid.shape), surface_types=surface_types(result.grid.shape),
                       surface_ald=1e-6)
    assert {f.face for f in rep.over_target} == {1, 2, 3}
    assert all(f.note for f in rep.over_target)
    assert sum("over the target" in line for line in rep.lines()) == 3
    # a face beside an edge whose grid gmsh's own curve mesh replaced is named for that edge
    rep = build_report(result.nodes, result.triangles, result.triangle_faces,
                       brep_areas=brep_face_areas(result.grid.shape), surface_types=surface_types(result.grid.shape),
                       surface_ald=1e-6, gmsh_curves={2: [1]})
    assert [f.reason == "gmsh's curves" for f in rep.faces] == [False, True, False]
    assert "beside edge(s) 1, whose grids gmsh's own curve mesh replaced" in rep.faces[1].note
    # a face that failed while held at a size floor is named with its sharp ridge, the likely cause
    keep = result.triangle_faces != 1
    rep = build_report(result.nodes, result.triangles[keep], result.triangle_faces[keep],
                       brep_areas=brep_face_areas(result.grid.shape), surface_types=surface_types(result.grid.shape),
                       surface_ald=1e-2, failed={1: "hung"}, floored={1: 0.03, 2: 0.5})
    first, second = rep.faces[0], rep.faces[1]
    assert first.status == "failed" and first.note.startswith("hung; its surface has a sharp ridge")
    assert "0.03 or more" in first.note and "sharp ridge" not in second.note  # meshed: no failure to explain


def test_a_gapped_box_meshes_to_its_closed_face_areas_and_names_its_tolerances(gapped_box_step):
    """Every face of a box read back with 0.02 gaps between its faces' pcurves: measured against the
    face areas with those gaps closed, each planar face's mesh is within the target (OCCT's own
    integrations, which leave the gaps out, put one face 0.3% off). Judged against a target no mesh
    can meet, the faces are named as within what their edges' 0.014-0.028 tolerances allow."""
    result = mesh_shape(gapped_box_step, ald=1e-3)
    assert result.ok, result.problems()
    assert result.report.worst_deficit <= 1e-3
    bands = tolerance_bands(result.grid, brep_face_areas(result.grid.shape))
    assert sorted(bands) == list(range(1, 7)) and all(0.013 < tol < 0.029 for tol, _ in bands.values())
    rep = build_report(result.nodes, result.triangles, result.triangle_faces,
                       brep_areas=brep_face_areas(result.grid.shape), surface_types=surface_types(result.grid.shape),
                       surface_ald=1e-9, tolerances=bands)
    assert len(rep.over_target) == 6 and all("tolerances allow" in f.note for f in rep.over_target)
    assert {f.reason for f in rep.over_target} == {"tolerances"}
    # edges meshed with pcurves rebuilt in step (MeshResult.restepped) are judged by their new tolerances
    tight = tolerance_bands(result.grid, brep_face_areas(result.grid.shape), {e.id: 1e-9 for e in result.grid.edges})
    assert sorted(tight) == list(range(1, 7)) and {tol for tol, _ in tight.values()} == {1e-9}
    rep = build_report(result.nodes, result.triangles, result.triangle_faces,
                       brep_areas=brep_face_areas(result.grid.shape), surface_types=surface_types(result.grid.shape),
                       surface_ald=1e-9, tolerances=tight)
    assert {f.reason for f in rep.over_target} == {"planar"}
    rep = build_report(result.nodes, result.triangles, result.triangle_faces,
                       brep_areas=brep_face_areas(result.grid.shape), surface_types=surface_types(result.grid.shape),
                       surface_ald=1e-9, tolerances=bands, folded={2: 3, 5: 1})
    assert rep.folded == 4 and [f.folded for f in rep.faces] == [0, 3, 0, 0, 1, 0]
    (line,) = [line for line in rep.lines() if "folded" in line]
    assert line.startswith("  4 triangles folded") and "[2, 5]; 4 of them on faces named above" in line
    rep = build_report(result.nodes, result.triangles, result.triangle_faces,
                       brep_areas=brep_face_areas(result.grid.shape), surface_types=surface_types(result.grid.shape),
                       surface_ald=1e-9)
    assert not any("tolerances allow" in f.note for f in rep.over_target)
    assert {f.reason for f in rep.over_target} == {"planar"}  # a box: every face a plane
    # edges stated tight but lying off their faces (a camera module's near-planar face, edges 0.13 off with
    # tolerances of 8e-7): the report measures every face over target, and names the edges' distance
    tight_grid = dataclasses.replace(result.grid, edges=[dataclasses.replace(e, tolerance=1e-9)
                                                          for e in result.grid.edges])
    opts = {"brep_areas": brep_face_areas(result.grid.shape), "surface_types": surface_types(result.grid.shape),
            "surface_ald": 1e-9, "curved_faces": []}
    rep = report_of(dataclasses.replace(result, grid=tight_grid), opts)
    assert len(rep.over_target) == 6 and {f.reason for f in rep.over_target} == {"tolerances"}
    assert all("from its boundary (their pcurves on its surface), beyond their tolerance (1e-09)" in f.note
               for f in rep.over_target)


def test_a_face_meshed_finer_into_its_target_is_never_taken_for_not_converging():
    # boxed_sphere's hemispheres at 1e-3: 1.06e-3 -> 8.7e-4 once finer kept its finer mesh
    assert not not_converging(8.7e-4, 1.06e-3, 1e-3)
    assert not_converging(1.0e-3 * 1.5, 1.6e-3, 1e-3)  # still over, and finer bought little
    assert not not_converging(1.2e-3, 2.0e-3, 1e-3)  # still over, but going down: another pass
    assert not_converging(-0.028, None, 1e-3) and not not_converging(0.009, None, 1e-3)  # met once: 10x off
    assert not not_converging(0.0101, None, 1e-3)  # 10x off but within 2%: a lobed gear's side, meshed finer


def test_a_face_over_its_target_at_its_triangle_budget_is_not_meshed_finer():
    """A filleted cylinder at 1e-3 with a budget of 2 000 triangles a face: gmsh's curvature sizes on the
    fillets are held to it (31 per 2 pi instead of 57), and they come out over their target. Meshed finer
    they would pass the budget (a long thin torus fillet's finer mesh hung gmsh for 60 s, and its edge
    splits ran into the time's cut), so they are left as meshed, not split either, and reported with the
    reason."""
    from cadedge.mesh.report import AFTER_MESH_HOOK

    result = mesh_shape(_filleted_cylinder(), ald=1e-3, hooks={"before_generate": ["mesh_probes:small_budget"]})
    done = result.extras[AFTER_MESH_HOOK]
    assert result.ok and done["budget"] == [2, 3] and done["refined"] == {} and done["split"] == []
    fillets = [f for f in result.report.faces if f.surface == "Torus"]
    assert [f.face for f in fillets] == [2, 3] and all(f.triangles < 4_000 for f in fillets)
    for face in fillets:
        assert face.status == "over target" and face.reason == "triangle budget"
        assert face.note.startswith(f"its {face.triangles} triangles hold the face's budget")
    assert all(f.status == "ok" for f in result.report.faces if f.surface != "Torus")


def test_a_longer_attempt_bound_raises_the_triangle_budget():
    """400 000 triangles a face at the default bound on one attempt (60 s) or less, in proportion above it:
    a longer --timeout buys finer faces where the budget holds them. The gmsh job holds its own budget and
    gives the process's back."""
    import cadedge.mesh.budget as budget
    from cadedge.mesh.report import AFTER_MESH_HOOK

    assert [budget.job_budget(b) for b in (None, 6.0, 60.0, 120.0, 180.0)] == [400_000] * 3 + [800_000, 1_200_000]
    for bound, held in ((None, 400_000), (120.0, 800_000)):
        result = mesh_shape(FIXTURES / "cylinder.step", ald=1e-2, face_timeout=bound)
        assert result.ok and result.extras[AFTER_MESH_HOOK]["budget_triangles"] == held
    assert budget.MAX_FACE_TRIANGLES == 400_000
    with budget.held(1_000):
        assert budget.MAX_FACE_TRIANGLES == 1_000 and budget.job_budget(120.0) == 2_000
    assert budget.MAX_FACE_TRIANGLES == 400_000


def test_a_sharp_face_corner_is_named_as_forcing_a_small_angle():
    """A prism on a triangle with a 2.9-degree corner: its end faces must hold a triangle that thin."""
    shape = cq.Workplane().polyline([(0, 0), (10, 0), (10, 0.5)]).close().extrude(1.0).val()
    result = mesh_shape(shape, ald=1e-2)
    assert result.ok, result.problems()
    small = result.report.small_angles
    assert small and all(s.forced for s in small)
    assert any("corner" in line and "forced" in line for line in result.report.lines())


def test_a_cusp_beside_wider_corners_at_one_vertex_is_a_corner_of_its_own():
    """A face's corners at a B-rep vertex are its fans of triangles round the node, parted by boundary
    segments: where a slot's tangent sides meet a face's outline (gmsh's PeriodicFaceWithLargeTolerance.brep)
    a cusp lies between two wider corners, and the sum of all three (here 93 degrees) hid the cusp's 3; the
    triangle spanning the cusp was named unforced. Here corners of 45, 3 and 45 degrees meet at node 0."""
    from cadedge.mesh.quality import corner_angles, small_angles, triangle_angles

    def at(degrees, r=1.0):
        return [r * np.cos(np.radians(degrees)), r * np.sin(np.radians(degrees)), 0.0]

    nodes = np.array([[0.0, 0, 0], at(0), at(45), at(90), at(93), at(100), at(145)])
    tris = np.array([[0, 1, 2], [0, 3, 4], [0, 5, 6]])
    angles = triangle_angles(nodes, tris)
    sides = {(0, 1), (0, 2), (0, 3), (0, 4), (0, 5), (0, 6)}
    assert sorted(corner_angles(tris, angles, 0, sides)) == pytest.approx([3.0, 45.0, 45.0])
    fan = np.array([[0, 1, 2], [0, 3, 4], [0, 4, 6]])  # (0, 4) an inner edge: 90-145 one corner
    assert sorted(corner_angles(fan, triangle_angles(nodes, fan), 0, sides - {(0, 4), (0, 5)})) == \
        pytest.approx([45.0, 55.0])
    small = small_angles(nodes, tris, np.ones(3, dtype=int), nodes[[0]], angles)
    assert [s.forced for s in small] == [True]  # before: not forced (93 degrees at the vertex)


def test_strip_width_is_the_distance_to_the_second_nearest_boundary_edge():
    from cadedge.mesh.quality import strip_width

    side = np.array([[0.0, 0, 0], [10.0, 0, 0]])
    other = side + [0.0, 1e-6, 0]
    far = side + [0.0, 5.0, 0]
    sliver = np.array([[1.0, 0, 0], [3.0, 1e-6, 0], [2.0, 0.5e-6, 0]])
    assert strip_width(sliver, [side, other, far]) == pytest.approx(1e-6, rel=1e-6)
    assert strip_width(sliver, [side, far]) == pytest.approx(5.0, rel=1e-6)
    assert strip_width(sliver, [side]) == np.inf


def test_strip_width_finds_the_two_sides_of_one_closed_edge():
    """A thin lens bounded by one closed polyline (an airfoil's end cap): its upper and lower sides are
    parts of one edge, 0.1 apart in the middle; a round disk's boundary is nowhere that close to itself."""
    from cadedge.mesh.quality import strip_width

    x = np.linspace(-10.0, 10.0, 21)
    half = 0.05 * (1.0 - (x / 10.0) ** 2)
    lens = np.vstack([np.column_stack([x, half, 0 * x]), np.column_stack([x[::-1], -half[::-1], 0 * x])[1:]])
    assert np.allclose(lens[0], lens[-1])
    sliver = np.array([[-1.0, half[9], 0], [1.0, half[11], 0], [0.0, -0.05, 0]])
    assert strip_width(sliver, [lens]) == pytest.approx(0.1, rel=0.05)
    t = np.linspace(0.0, 2.0 * np.pi, 65)
    disk = np.column_stack([np.cos(t), np.sin(t), 0 * t])
    assert strip_width(np.array([[0.0, 0, 0], [0.5, 0, 0], [0, 0.5, 0]]), [disk]) > 0.5
    assert strip_width(disk[[3, 4]], [disk]) > 1.5  # on the boundary: the far side is across the disk


def test_a_zero_width_strip_is_named_as_forcing_small_angles():
    """A helical flight fused to a longer shaft: the flight's end line lies on the shaft cylinder's seam, so
    the shaft face has a strip of no width between the two, and whatever fills it is a sliver."""
    pitch, height, r = 20.0, 60.0, 6.0
    section = cq.Workplane("XZ").center(r + 4.5, 0).rect(9.0, 2.0)
    flight = section.sweep(cq.Workplane().add(cq.Wire.makeHelix(pitch, height, r)), isFrenet=True)
    shaft = cq.Workplane("XY").circle(r + 0.5).extrude(height + 20).translate((0, 0, -10))
    result = mesh_shape(shaft.union(flight).val(), ald=1e-2)
    assert result.ok, result.problems()
    small = result.report.small_angles
    strip = [s for s in small if s.forced and "wide there, between two sides of its boundary" in s.reason]
    assert len(strip) >= 3  # before the strip rule: none recognised (the strip has no corner)
    # MeshAdapt's mesh of the shaft face (gmsh's switch, on a fold) had 83 triangles under 5 degrees, 79 of
    # them in the strip; Frontal-Delaunay's, kept once unfolded, 6. At the strip's ends a vertex lies 2.3e-6
    # off a seam segment that passes it (the segment is not cut there): the triangle on that segment is
    # forced by the pinch. Not forced: one of 4 degrees (before: 4 not forced, 0.16-3.2 degrees).
    pinch = [s for s in small if s.forced and s.reason.startswith("the face's boundary passes 2.3e-06 from itself")]
    assert len(pinch) == 2
    assert len(small) <= 10 and len(small) - len(strip) - len(pinch) <= 2


def test_a_sliver_on_a_boundary_segment_that_passes_a_boundary_node_is_forced_by_the_pinch():
    """A triangle on a boundary segment whose third node, on the boundary too, lies 1e-4 from it, 0.3 from
    its nearer end: every triangle on that segment leaves the node out, so none gets over atan(1e-4 / 0.3).
    The same triangle with an interior node there (one the optimiser could move) is the mesher's."""
    from cadedge.mesh.quality import small_angles

    nodes = np.array([[0.0, 0, 0], [1, 0, 0], [0.3, 1e-4, 0]])
    tris = np.array([[0, 1, 2]])
    side, stem = nodes[[0, 1]], np.array([[0.3, 1e-4, 0], [0.3, 1.0, 0]])

    def one(polylines):
        (s,) = small_angles(nodes, tris, [1], np.zeros((0, 3)), face_edges={1: polylines})
        return s

    pinched = one([side, stem])
    assert pinched.forced and pinched.reason.startswith("the face's boundary passes 0.0001 from itself")
    assert "0.3 from its nearer end" in pinched.reason and "0.019 degrees" in pinched.reason
    assert not one([side, stem + [0.0, 1e-3, 0]]).forced  # the node on no grid: not a pinch
    assert not one([side[::-1] * [1, 0, 0] + [0, 2, 0], stem]).forced  # the segment on no grid


def test_a_sliver_on_an_edge_off_its_face_is_forced_only_when_the_gap_is_near_its_size():
    """An edge that lies ``d`` off its face's boundary (an OCCT offset of a loft: 1-2.3 mm) makes the
    triangles that join it to the face span the gap: one no longer than OFF_REACH times ``d`` is forced;
    a longer one, or one with no node on that edge, is the mesher's."""
    from cadedge.mesh.quality import OFF_REACH, small_angles

    nodes = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 0.01, 0], [5, 0, 0], [6, 0, 0], [5.5, 0.01, 0]])
    tris = np.array([[0, 1, 2], [3, 4, 5]])
    edge = np.array([[-1.0, 0, 0], [0, 0, 0]])  # through node 0 only

    def forced(off: float) -> list[bool]:
        smalls = small_angles(nodes, tris, np.ones(2, dtype=int), np.zeros((0, 3)), offsets={1: [(edge, off)]})
        return [s.forced for s in sorted(smalls, key=lambda s: s.reason)]

    assert forced(1.0 / OFF_REACH) == [True, False]  # the first is 1.0 long; the second has no node on it
    assert forced(0.9 / OFF_REACH) == [False, False]
    (smalls,) = [small_angles(nodes, tris[:1], [1], np.zeros((0, 3)), offsets={1: [(edge, 0.5)]})]
    assert smalls[0].reason.startswith("a node of it is on an edge that lies 0.5 off the face's boundary")


def test_a_face_of_no_area_does_not_ask_its_edges_for_billions_of_segments():
    """Gs001 of the dodgy-STEP catalogue (3.9 KB) holds a face of area 2.3e-13 inside 14 mm of edges: the
    boundary fit cut its segments to that area's budget, asked 780 million pieces of one, and the caller's
    process grew to 24 GB and was killed. Such a face is degenerate (no area target), and no edge is cut
    into more than MAX_PIECES segments whatever a face asks. A face narrower than its edges' tolerance is
    not cut for either: OCCT's Alias test file trj3_s1-al-214.stp has faces of 1.6e-7 mm2 inside one edge
    2.6 mm long of tolerance 0.046, whose edges took 58 000 segments each (466 592 in all at 1e-2)."""
    import dataclasses

    from cadedge import refine_shape
    from cadedge.mesh.boundary_fit import MAX_PIECES
    from cadedge.mesh.fidelity import without_degenerate
    from cadedge.shapegrid import with_edges

    grid = refine_shape(FIXTURES / "cylinder.step", ald=1e-2)
    areas = brep_face_areas(grid.shape)
    tiny = areas.copy()
    tiny[1] = 1e-13 * areas[1]  # an end face: a plane, whose segments the fit cuts to its area budget
    assert list(without_degenerate(grid, tiny) == 0) == [False, True, False]
    assert np.array_equal(without_degenerate(grid, areas), areas)
    kinds = meshed_kinds(grid.shape)
    assert all(e.tolerance >= 1e-7 for e in grid.edges)  # the face, 1e-12 wide, is within them: not cut for
    within, _ = fit_boundaries(grid, 1e-2, brep_areas=tiny, kinds=kinds)
    assert max(e.segments for e in within.edges) < 1000
    tight = with_edges(grid, [dataclasses.replace(e, tolerance=1e-15) for e in grid.edges])
    fitted, _ = fit_boundaries(tight, 1e-2, brep_areas=tiny, kinds=kinds)  # 1e-12 wide, held to 1e-15
    cut = {e.id: e.segments for e in fitted.edges}
    assert 0.5 * MAX_PIECES < max(cut.values()) <= MAX_PIECES + max(e.segments for e in grid.edges)
    degenerate, _ = fit_boundaries(tight, 1e-2, brep_areas=without_degenerate(grid, tiny), kinds=kinds)
    assert max(e.segments for e in degenerate.edges) < 1000  # no area target on the face: nothing asked


def test_cli_surface_ald_and_report(tmp_path, capsys):
    out, rep = tmp_path / "cyl.msh", tmp_path / "cyl.json"
    code = main(["mesh", str(FIXTURES / "cylinder.step"), "--ald", "1e-2", "--surface-ald", "2e-3",
                 "-o", str(out), "--report", str(rep)])
    assert code == 0
    data = json.loads(rep.read_text())
    assert data["surface_ald"] == 2e-3
    assert max(abs(f["area_deficit"]) for f in data["faces"]) <= 2e-3
    assert "worst |area deficit|" in capsys.readouterr().out


def test_planar_boundary_polygon_area_is_the_meshed_area():
    """A planar face's triangles cover exactly its boundary polygon (holes subtracted): the area known
    before meshing is the area measured after."""
    from cadedge.mesh.areas import face_mesh_areas
    from cadedge.mesh.planar import planar_polygon_areas

    result = mesh_shape(FIXTURES / "bracket.step", ald=1e-2)
    assert result.ok, result.problems()
    kinds = surface_types(result.grid.shape)
    planes = [i + 1 for i, k in enumerate(kinds) if k == "Plane"]
    polygon = planar_polygon_areas(result.grid.shape, result.grid, planes)
    assert sorted(polygon) == planes
    meshed = face_mesh_areas(result.nodes, result.triangles, result.triangle_faces, len(kinds))
    np.testing.assert_allclose([polygon[f] for f in planes], [meshed[f - 1] for f in planes], rtol=1e-9)


def test_a_ring_cap_is_split_for_its_net_deficit_not_its_gross_slivers():
    """A ring's planar cap loses along its outer circle much of what it gains along its inner one: the
    boundary fit credits that (checked on the exact polygon) instead of splitting both circles for the sum
    of their slivers, and every face still meets the target."""
    import cadedge

    shape = cq.Workplane().circle(20.0).circle(16.0).extrude(3.0).val()
    eps = 1e-2
    grid = cadedge.refine_shape(shape, ald=eps)
    kinds = surface_types(grid.shape)
    areas = brep_face_areas(grid.shape)
    unsigned = _fit_boundaries(grid, eps, brep_areas=areas, kinds=kinds, ratio=2.0, credit={})[0]
    fitted, _ = fit_boundaries(grid, eps)
    circles = [i for i, e in enumerate(grid.edges) if e.curve == "Circle"]
    assert sum(fitted.edges[i].segments for i in circles) < 0.75 * sum(unsigned.edges[i].segments for i in circles)
    result = mesh_shape(shape, ald=eps)
    assert result.ok, result.problems()
    assert np.all(np.abs(_independent_deficits(result)) <= eps)
    assert result.report.below_20 == 0.0


def test_the_signed_sliver_estimate_matches_a_planar_rings_exact_polygon():
    """The boundary fit's signed sliver sum (chords of a curve bulging out of the face cut it short, those
    of a curve bulging in add to it) tells the face's side of each edge from its pcurve: on a ring's
    planar cap it is the exact polygon's deficit within 1%, the outer circle's loss less the hole's gain,
    where the unsigned sum is 4.5 times that. (The fit tells sides on curved faces only, a plane's polygon
    being measured exactly: here the caps are passed as curved.)"""
    import cadedge

    grid = cadedge.refine_shape(cq.Workplane().circle(20.0).circle(16.0).extrude(3.0).val(), ald=1e-2)
    areas, kinds = brep_face_areas(grid.shape), meshed_kinds(grid.shape)
    caps = _planes(areas, kinds)
    curved = ["BSplineSurface" if k == "Plane" else k for k in kinds]
    _, gross, signed = _fit_boundaries(grid, 1e-2, brep_areas=areas, kinds=curved, ratio=2.0, credit={})
    assert len(caps) == 2
    for f, exact in _plane_deficits(grid, caps, areas).items():
        assert signed[f - 1] / areas[f - 1] == pytest.approx(exact, rel=0.01)
        assert gross[f - 1] > 4 * signed[f - 1]


def test_a_helical_bands_edges_are_split_for_its_net_deficit():
    """A flat coil's helicoidal band (``flat_coil`` of ``scripts/hard_models.py``, two turns) loses along its
    outer helix much of what it gains along its inner one. Split for the sum of their slivers, its helices
    took 182-208 segments at 1e-2 and the coil 5 096 triangles, its bands at 2.6% of the target;
    credited with the cancellation its signed slivers measure (5x), 78-104, and every face still within
    the target."""
    import cadedge

    coil = _hard_models().flat_coil(turns=2)
    grid = cadedge.refine_shape(coil, ald=1e-2)
    areas, kinds = brep_face_areas(grid.shape), meshed_kinds(grid.shape)
    unsigned = _fit_boundaries(grid, 1e-2, brep_areas=areas, kinds=kinds, ratio=2.0, credit={})[0]
    fitted, credits = fit_boundaries(grid, 1e-2)
    assert len(credits) == 2 and all(4.0 < c < CURVED_CREDIT[1] for c in credits.values())
    helices = [i for i, e in enumerate(grid.edges) if e.length > 100]
    assert len(helices) == 4
    assert sum(fitted.edges[i].segments for i in helices) < 0.5 * sum(unsigned.edges[i].segments for i in helices)
    result = mesh_shape(coil, ald=1e-2)
    assert result.ok, result.problems()
    assert np.all(np.abs(_independent_deficits(result)) <= 1e-2)
    assert result.report.below_20 == 0.0
    assert len(result.triangles) < 2500


def test_a_chamfer_rings_cone_is_credited_no_more_than_a_cone_may_be():
    """A tube 62 mm across, 20 mm bore, its outer top edge chamfered 1 mm at 45 degrees: the chamfer's
    cone ring, 1.4 mm wide, has its chords half off its surface (the facets' tilt, which no cancellation
    offsets). Credited 25 (the most a curved face gets) it came out at 1.58 times the target at 1e-3
    and was excused as not converging (as io1-ug-214.stp's chamfer ring was); a cone now gets at most
    ``CONE_CREDIT``."""
    import cadedge

    tube = (cq.Workplane("XY").circle(31.0).circle(20.0).extrude(4.0).faces(">Z")
            .edges(cq.selectors.RadiusNthSelector(1)).chamfer(1.0).val())
    grid = cadedge.refine_shape(tube, ald=1e-3)
    kinds = meshed_kinds(grid.shape)
    credits = fit_boundaries(grid, 1e-3)[1]
    assert [kinds[f - 1] for f in credits] == ["Cone"] and max(credits.values()) == CONE_CREDIT
    result = mesh_shape(tube, ald=1e-3)
    assert result.ok, result.problems()
    assert all(f.status == "ok" for f in result.report.faces)
    assert np.all(np.abs(_independent_deficits(result)) <= 1e-3)


def test_a_credited_thin_faces_splits_hold_to_the_thin_faces_budget(monkeypatch):
    """A credited planar face's edges are cut to twice its width (``THIN_RATIO``) only where that fits the
    thin faces' budget of :mod:`cadedge.mesh.widths`: NX's piattello plate has twelve planar strips 0.001
    wide along 14 mm arcs, whose arcs took 7 000 segments each at 1e-2, the cylinders beside them 92 000
    triangles each, and 69 of its 313 faces ran out of time. Here a tube's 0.05-wide end rings: cut to
    their width within the budget; past it (the budget made 100 segments) left to the widths' splits,
    which hold to it as well, and every face still within the target, its slivers named as forced."""
    import cadedge
    import cadedge.mesh.widths as widths

    tube = cq.Workplane("XY").circle(10.0).circle(9.95).extrude(2.0).val()
    grid = cadedge.refine_shape(tube, ald=1e-2)
    circles = [i for i, e in enumerate(grid.edges) if e.curve == "Circle"]
    fitted, _ = fit_boundaries(grid, 1e-2)
    assert min(fitted.edges[i].segments for i in circles) > 0.9 * 2 * np.pi * 10.0 / (2 * 0.05)
    monkeypatch.setattr(widths, "MOST_ADDED", 100)
    fitted, _ = fit_boundaries(grid, 1e-2)
    assert max(fitted.edges[i].segments for i in circles) < 100
    result = mesh_shape(tube, ald=1e-2)
    assert result.ok, result.problems()
    assert np.all(np.abs(_independent_deficits(result)) <= 1e-2)
    assert result.report.small_angles and all(s.forced for s in result.report.small_angles)


def test_a_planar_face_whose_slivers_could_split_no_segment_gets_no_credit():
    """A planar face's cancellation credit (its unsigned sliver sum over its exact polygon's deficit) is
    for faces the unsigned rule could split: a face bounded by lines has slivers of rounding only, and
    a KiCad barrel jack's 2e-6 ribbons were credited on that noise (1.6e-16 over 9e-11 of 3.4e-7), then
    cut to their width in 93 385 pieces an edge. A face whose slivers together are within its shortest
    segment's share of its budget gets none; one whose slivers are within its whole budget but may be
    over a segment's share keeps its credit."""
    areas = np.array([3.4e-7, 2.0, 2.0])
    gross = np.array([1.6e-16, 0.1, 0.01])  # the ribbon's rounding; curved outlines' slivers
    deficits = {1: 9e-11, 2: 0.004, 3: 0.0004}
    share = np.array([2.2e-6 / 0.6, 0.01, 0.01])  # shortest segment over perimeter
    credits = _planar_credits(gross, deficits, areas, AIM * 1e-2, share)
    assert credits == {2: pytest.approx(0.5 * 0.1 / (0.004 * 2.0)), 3: pytest.approx(0.5 * 0.01 / (0.0004 * 2.0))}
    assert 0.01 < AIM * 1e-2 * areas[2]  # face 3's slivers are within its budget, but not a segment's share


def test_a_faces_shortest_segment_share_leaves_out_its_degenerate_edges():
    """A cone's apex is a degenerate edge of two points at one place: counted, its segment of length 0
    made the cone face's shortest share 0, and any rounding of its slivers would have earned a credit."""
    import cadedge

    grid = cadedge.refine_shape(cq.Solid.makeCone(5, 0, 10), ald=1e-2)
    shares = _shortest_shares(grid, 2)
    lengths = [e.segment_lengths.min() for e in grid.edges if 1 in e.faces and not e.degenerate]
    perimeter = sum(e.length for e in grid.edges if 1 in e.faces)
    assert any(e.degenerate for e in grid.edges)
    assert shares[0] == pytest.approx(min(lengths) / perimeter)


def test_a_cone_rings_credit_is_halved_where_a_neighbour_cut_one_circle_finer():
    """A can whose top is a nearly flat cone ring (0.34 mm wide, rising 0.003 mm) between its wall and a
    0.15 mm round: the ring's two circles are cut alike before the fit, so its slivers cancel and it is
    credited ``CONE_CREDIT``; the round's curvature then cuts the inner circle far finer, and the outer
    one's loss stood alone: the ring was meshed at 1.03 times the target at 1e-3 (KiCad's TO-18-3.step:
    1.04). Checked again on its fitted segments, its credit is halved until its signed slivers are within
    ``AIM`` of the target, and every face is within it."""
    import math

    import cadedge

    c = math.cos(math.pi / 4)
    can = (cq.Workplane("XZ").moveTo(0, 0).lineTo(2.92, 0).lineTo(2.92, 5).lineTo(2.58, 5.003)
           .threePointArc((2.43 + 0.15 * c, 5.003 + 0.15 * c), (2.43, 5.153)).lineTo(0, 5.153).close()
           .revolve(360, (0, 0, 0), (0, 1, 0)).val())
    grid = cadedge.refine_shape(can, ald=1e-3)
    areas, kinds = brep_face_areas(grid.shape), meshed_kinds(grid.shape)
    ring = kinds.index("Cone") + 1
    first, credits = fit_boundaries(grid, 1e-3)
    assert credits[ring] == CONE_CREDIT
    signed = _fit_boundaries(first, 1e-3, brep_areas=areas, kinds=kinds, ratio=2.0, credit={})[2]
    assert signed[ring - 1] > AIM * 1e-3 * areas[ring - 1]  # uncancelled: what the credit left
    fitted, lowered = fit_curved(first, 1e-3, brep_areas=areas, kinds=kinds, credit=credits)
    assert 1.0 < lowered[ring] < CONE_CREDIT
    signed = _fit_boundaries(fitted, 1e-3, brep_areas=areas, kinds=kinds, ratio=2.0, credit={})[2]
    assert abs(signed[ring - 1]) <= AIM * 1e-3 * areas[ring - 1]
    result = mesh_shape(can, ald=1e-3)
    assert result.ok, result.problems()
    assert all(f.status == "ok" for f in result.report.faces)
    assert np.all(np.abs(_independent_deficits(result)) <= 1e-3)


def test_a_planar_cap_whose_segments_span_its_bends_is_fitted_again_to_its_target():
    """The caps of a 20 mm stadium outline with 0.3 mm round ends (one spline, 4 segments for 41 mm at
    first): the boundary fit, which divides a segment's sliver by k**2 when it cuts it in k, left them at
    5.5% at 1e-2 (most pieces fall on the straight sides). Fitted again on their finer segments, their
    polygons are within the 0.7% aimed at."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.gp import gp_Vec

    from cadedge import refine_shape

    shape = BRepPrimAPI_MakePrism(stadium_cap(radius=0.3)[0], gp_Vec(0.0, 0.0, 6.0)).Shape()
    grid = refine_shape(shape, ald=1e-2)
    areas, kinds = brep_face_areas(shape), meshed_kinds(shape)
    caps = _planes(areas, kinds)
    assert len(caps) == 2
    once = _fit_boundaries(grid, 1e-2, brep_areas=areas, kinds=kinds, ratio=2.0, credit={})[0]
    assert min(_plane_deficits(once, caps, areas).values()) > 5 * AIM * 1e-2
    fitted, _ = prepare(grid, 1e-2)
    assert max(_plane_deficits(fitted, caps, areas).values()) <= AIM * 1e-2


def test_bracket_uses_fewer_triangles_than_gmsh_tuned_to_its_worst_face():
    """gmsh alone (Mesh.MeshSizeFromCurvature tuned until its worst face is within cadedge's, 0.0055)
    takes 5364 triangles on the bracket at 1e-2 (scripts/bench_mesh_fidelity.py); face interiors that
    keep their finest boundary spacing far inside took cadedge 5934."""
    result = mesh_shape(FIXTURES / "bracket.step", ald=1e-2)
    assert result.ok, result.problems()
    assert result.report.worst_deficit <= 1e-2
    assert len(result.triangles) < 5364
    assert result.report.min_angle >= 20.0


def test_an_offset_face_is_measured_against_its_true_area():
    """A thickened wavy plate: OCCT's adaptive integration put its offset face's area 0.42% too high, and
    the face was reported over the 1e-3 target at 0.0043 while its mesh was within 1.3e-4 of the face.
    Measured against the cross-checked area (cadedge.occt.areas), every face is within the target."""
    pts = [[cq.Vector(5.0 * i, 5.0 * j, 2.0 * np.sin(0.9 * i) * np.cos(0.7 * j)) for j in range(9)] for i in range(9)]
    shape = cq.Face.makeSplineApprox(pts).thicken(1.5)
    result = mesh_shape(shape, ald=1e-3)
    assert result.ok, result.problems()
    offset = [f for f in result.report.faces if f.surface == "OffsetSurface"]
    assert len(offset) == 1 and abs(offset[0].area_deficit) <= 1e-3, offset
    assert result.report.worst_deficit <= 1e-3 and not result.report.over_target


def test_a_sagitta_is_the_height_across_the_chord_whatever_the_parameter_speed():
    def line(u):  # x = u**3: the mid-parameter point lies far along the chord, not off it
        u = np.asarray(u, dtype=float)
        return np.c_[u ** 3, np.zeros_like(u), np.zeros_like(u)]

    u = np.array([0.1, 0.6, 1.0])
    assert np.allclose(_sagittas(u, line(u), line), 0.0, atol=1e-15)

    def arc(u):  # a unit circle run at a varying speed: angle = u**2
        u = np.asarray(u, dtype=float)
        return np.c_[np.cos(u ** 2), np.sin(u ** 2), np.zeros_like(u)]

    u = np.array([0.0, 1.0])
    height = np.linalg.norm(_sagittas(u, arc(u), arc)[0])
    assert 0.9 * (1 - np.cos(0.5)) < height <= 1 - np.cos(0.5) + 1e-12  # the arc's own sagitta, nearly


@pytest.mark.corpus
def test_a_face_whose_deficit_hardly_moves_is_coarsened_again():
    """mesh_T106_V3 at 1e-3: its large blade face's deficit comes from its loose boundary more than from
    its triangles (3.35e-4 at 4 604 triangles after one coarsening pass, 3.6e-4 at 2 902 after three):
    8 961 triangles in all with one pass, 6 611 with three, every face within the target. gmsh alone,
    swept over its curvature sizes, gets no closer than 3.7e-4 with 24 455."""
    from cadedge.mesh.report import AFTER_MESH_HOOK

    result = mesh_shape(CORPUS / "live-clones__gmsh__mesh_T106_V3.step", ald=1e-3)
    assert result.ok, result.problems()
    assert np.all(np.abs(_independent_deficits(result)) <= 1e-3)
    assert 2 in result.extras[AFTER_MESH_HOOK]["coarsened"]
    assert len(result.triangles) < 7500


def test_a_face_sized_by_its_boundary_is_not_coarsened():
    """A disc with an annular groove whose top edges are filleted 0.3 at 1e-2: the groove's walls and the
    disc's side are far under the worst face, but their triangles follow their boundary spacings (the
    fillets' and the rim's), not their curvature sizes, so a lower count per 2 pi changes nothing; they
    were meshed again, twice, for nothing."""
    body = cq.Workplane("XY").circle(10).extrude(4)
    body = body.cut(cq.Workplane("XY").workplane(offset=1).circle(8).circle(6).extrude(3))
    rims = [e for e in body.edges().vals()
            if abs(e.Center().z - 4) < 1e-6 and e.geomType() == "CIRCLE" and e.radius() < 9]
    steps: list[str] = []
    result = mesh_shape(body.val().fillet(0.3, rims), ald=1e-2, progress=steps.append)
    assert result.ok, result.problems()
    walls = [f.face for f in result.report.faces if f.surface == "Cylinder"]
    assert len(walls) == 3 and all(abs(f.area_deficit) < 1e-3 for f in result.report.faces if f.face in walls)
    assert not [s for s in steps if "again" in s]
    assert result.report.worst_deficit <= 1e-2


def test_a_chamfer_cone_sized_by_its_circles_is_not_coarsened():
    """A plate with a hole chamfered 0.2 at 1e-3: the chamfer's narrow cone is far under the worst face,
    but its triangles follow its circles' spacings, and a lower count per 2 pi would hardly change them; it
    was meshed again three times for the same triangles (240 such holes: 36 s of a 160 s job)."""
    plate = cq.Workplane("XY").box(4, 4, 2).faces(">Z").workplane().hole(1.2).faces(">Z").edges("%CIRCLE").chamfer(0.2)
    steps: list[str] = []
    result = mesh_shape(plate.val(), ald=1e-3, progress=steps.append)
    assert result.ok, result.problems()
    cones = [f for f in result.report.faces if f.surface == "Cone"]
    assert len(cones) == 1 and abs(cones[0].area_deficit) < 0.75e-3
    assert not [s for s in steps if "again" in s], steps
    assert result.report.worst_deficit <= 1e-3


@pytest.mark.corpus
def test_loose_bspline_model_meshes_on_its_own_grids_with_good_angles():
    """mesh_T106_V3 (unsewn faces, B-spline curves of uneven parameter speed): splitting by parameter
    and mid-parameter sagittas once split its boundaries to 0.02 mm; faces then failed boundary
    recovery and fell back to gmsh's curve meshes, down to 2.1 degrees."""
    result = mesh_shape(CORPUS / "live-clones__gmsh__mesh_T106_V3.step", ald=1e-2)
    assert len(result.faces) == 8  # its faces of extrusion laid flat, but two whose curves lie off them
    # (a plane Frontal-Delaunay fanned may keep gmsh's Delaunay mesh: its loose edges are cut further)
    assert all(f.strategy in ("Frontal-Delaunay", "unrolled extrusion, Frontal-Delaunay", "Delaunay")
               for f in result.faces)
    assert not result.own_mesh_edges
    assert result.report.worst_deficit <= 1e-2 and result.report.min_angle > 10.0


def _face_mesh(surface: int) -> list:
    """The triangles of one gmsh surface as corner coordinates, to compare meshes exactly (tags may
    differ)."""
    from cadedge.mesh.facemesh import element_corners

    return element_corners(2, surface).tolist()


def test_a_floored_face_keeps_the_better_of_frontal_delaunay_and_delaunay():
    """A face held at a size floor and over its target is meshed again by gmsh's Delaunay: kept when its
    deficit is smaller (the outcome names Delaunay), else the first mesh comes back node for node, every
    triangle on nodes of the face or its curves."""
    from cadedge.mesh.floored import try_delaunay
    from cadedge.mesh.generate import mesh_faces
    from cadedge.mesh.gmsh_model import gmsh_session

    with gmsh_session():
        gmsh.model.occ.addCone(0, 0, 0, 0, 0, 10, 1.0, 4.0)
        gmsh.model.occ.synchronize()
        (side,) = [s for _, s in gmsh.model.getEntities(2) if gmsh.model.getType(2, s) != "Plane"]
        gmsh.option.setNumber("Mesh.MeshSizeMax", 1.0)
        gmsh.model.mesh.generate(1)
        outcomes = mesh_faces([side], {side: 1})
        first = _face_mesh(side)
        assert outcomes[side].strategy == "Frontal-Delaunay"
        # Delaunay's mesh judged worse (deficit 0.5 against the first's 0.1): the first is put back
        assert try_delaunay(side, 20.0, 0.1, outcomes, lambda area: 0.5) == 0.1
        assert _face_mesh(side) == first and outcomes[side].strategy == "Frontal-Delaunay"
        # judged better: Delaunay's mesh stays
        assert try_delaunay(side, 20.0, 0.1, outcomes, lambda area: 0.01) == 0.01
        assert outcomes[side].strategy == "Delaunay" and _face_mesh(side) != first
        assert outcomes[side].triangles == len(gmsh.model.mesh.getElementsByType(2, side)[0]) > 0
        # put back once more, then every other face meshed again: no triangle of the side holds their nodes
        try_delaunay(side, 20.0, 0.001, outcomes, lambda area: 0.5)
        others = [s for _, s in gmsh.model.getEntities(2) if s != side]
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.clear([(2, s) for s in others])
        gmsh.model.mesh.generate(2)
        tags = set(gmsh.model.mesh.getNodes(2, side, includeBoundary=True)[0].tolist())
        assert set(gmsh.model.mesh.getElementsByType(2, side)[1].tolist()) <= tags


def test_a_blade_with_a_sharp_edge_is_meshed_within_the_target(tmp_path):
    """A blade lofted from a 5 x 0.8 ellipse to a 2.4 x 0.3 one turned by 50 degrees (one blade of the
    propeller of ``scripts/hard_models.py``): its edges are sharp (radius 0.02 at the tip), its faces
    held at a size floor. Frontal-Delaunay joined the two sides of the blade through the solid there (a
    face 2.4e-2 short at 1e-2); that face is now meshed by Delaunay, and every face is within 1e-2. Its
    face 2, within the target but past half of it, has its edges split on the surface
    (:data:`cadedge.mesh.fidelity.RIDGE_SPLIT`), which leaves the optimiser room: 24.7 degrees."""
    blade = (cq.Workplane("YZ").ellipse(2.5, 0.4).workplane(offset=14).transformed(rotate=(0, 0, 50))
             .ellipse(1.2, 0.15).loft())
    path = tmp_path / "blade.step"  # as read back from STEP: meshed from the shape itself, gmsh's
    cq.exporters.export(blade, str(path))  # Frontal-Delaunay happened to stay clear of the ridge
    result = mesh_shape(path, ald=1e-2)
    assert result.ok, result.problems()
    deficits = _independent_deficits(result)
    assert np.all(np.abs(deficits) <= 1e-2), deficits
    from cadedge.mesh.report import AFTER_MESH_HOOK

    floored = result.extras[AFTER_MESH_HOOK]["floored"]
    assert floored and any(o.strategy == "Delaunay" for o in result.faces if o.face in floored)
    assert result.extras[AFTER_MESH_HOOK]["split"] == [2]
    assert result.report.min_angle >= 20.0


def _hard_models():
    """The module ``scripts/hard_models.py``."""
    import sys

    from conftest import ROOT

    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        import hard_models
    finally:
        sys.path.remove(str(ROOT / "scripts"))
    return hard_models


def _hard_model(name: str, folder):
    """``scripts/hard_models.py``'s model ``name`` written as STEP into ``folder``; its path."""
    _hard_models().write_model(name, folder)
    return folder / f"{name}.step"


def test_an_extrusion_notched_to_a_fold_is_within_its_target_and_keeps_its_angles(tmp_path):
    """notched_block of ``scripts/hard_models.py`` at 1e-3: its top, a spline extruded, folds at a V notch
    (flanks 16 degrees apart). Laid flat without a line of nodes along the fold, triangles spanned the
    notch: 1.3e-2 short, 9.2 degrees. With it, every face within the target, no triangle under 20
    degrees, none folded."""
    result = mesh_shape(_hard_model("notched_block", tmp_path), ald=1e-3)
    assert result.ok, result.problems()
    assert "unrolled extrusion, Frontal-Delaunay" in {o.strategy for o in result.faces}
    assert np.abs(_independent_deficits(result)).max() <= 1e-3
    assert result.report.min_angle >= 20.0 and result.report.folded == 0


def test_a_key_blade_of_bspline_faces_is_laid_flat_with_lines_at_its_corners(tmp_path):
    """key_blade of ``scripts/hard_models.py`` at 1e-3, every face a B-spline surface: its top wall, one
    B-spline extruded through square notches, was meshed by gmsh in its own parameters, its triangles
    across the corners: 3.2e-2 short, named as not converging. Laid flat with a line of nodes at each of
    its 11 corners, every face is within the target, no triangle under 20 degrees; the flat B-spline faces
    (no corner) stay gmsh's."""
    result = mesh_shape(_hard_model("key_blade", tmp_path), ald=1e-3)
    assert result.ok, result.problems()
    kinds = {o.face: o.strategy for o in result.faces}
    assert kinds[4] == "unrolled extrusion, Frontal-Delaunay"
    assert all(not k.startswith("unrolled") for f, k in kinds.items() if f != 4)
    assert np.abs(_independent_deficits(result)).max() <= 1e-3
    assert result.report.min_angle >= 20.0 and result.report.folded == 0


@pytest.mark.parametrize("name, eps", [("sphere_sector", 1e-2), ("revolved_sector", 1e-3)])
def test_a_face_meshed_on_the_wrong_side_of_its_boundary_gets_gmshs_other_algorithms(tmp_path, name, eps):
    """sphere_sector and revolved_sector of ``scripts/hard_models.py``: one face spanning 270 degrees between
    two poles, which Frontal-Delaunay meshed on the other side of its boundary (the missing quarter, 73%
    short, watertight with the flat faces: only the area tells). Over 10 times the target on one mesh, the
    face was named as not converging and left so, exit 0; gmsh's Delaunay meshes the face itself."""
    result = mesh_shape(_hard_model(name, tmp_path), ald=eps, workers=1)
    assert result.ok, result.problems()
    assert np.abs(_independent_deficits(result)).max() <= eps
    assert not result.report.over_target and result.report.min_angle >= 20.0


def test_a_strip_whose_parameters_stretch_one_way_is_not_left_a_lantern_over_its_area(tmp_path):
    """vanishing_fillet of ``scripts/hard_models.py`` at 1e-2: a fillet dying out along 162 mm, its length over
    0.16 of ``u``. Frontal-Delaunay and Delaunay fanned from its wide end's nodes to the far side (25% over
    its area, no triangle folded) and it was named as not converging; MeshAdapt meshes it within the target,
    and it is neither coarsened nor meshed finer by Frontal-Delaunay afterwards."""
    result = mesh_shape(_hard_model("vanishing_fillet", tmp_path), ald=1e-2)
    assert result.ok, result.problems()
    assert np.abs(_independent_deficits(result)).max() <= 1e-2
    assert not result.report.over_target


def test_a_blade_face_meshed_by_delaunay_keeps_its_mesh_through_the_optimiser(tmp_path):
    """sharp_blade of ``scripts/hard_models.py`` at 1e-2: its face 3, held at a size floor, is 2.6e-2
    short as Frontal-Delaunay meshes it and 4.4e-3 as Delaunay does. Written back by the face optimiser
    under tags of its own choosing, a face's nodes once shared tags with nodes gmsh later made for another
    face; a triangle of face 3 then held a node of a face meshed again (a dangling one), the face was found
    broken, meshed anew by Frontal-Delaunay and left at 2.6e-2. Face 1 (7.0e-3 on the
    boundaries of :func:`cadedge.mesh.widths.fit_to_widths`) is lifted from gmsh's 12.7 degrees only
    by the optimiser's focused retry, to 15.9: every pass over the whole face overshot its deficit."""
    result = mesh_shape(_hard_model("sharp_blade", tmp_path), ald=1e-2)
    assert result.ok, result.problems()
    assert not [n for n in result.notes if "meshed again" in n], result.notes
    face3 = next(o for o in result.faces if o.face == 3)
    assert face3.strategy == "Delaunay"
    deficits = _independent_deficits(result)
    assert abs(deficits[2]) <= 1e-2 and np.all(np.abs(deficits) <= 2e-2), deficits
    assert result.report.folded == 0  # 3 folded triangles before the moves refused to fold one
    assert result.report.min_angle >= 15.0


def test_a_wing_hooked_beside_its_seam_is_split_within_the_target_across_the_seam(tmp_path):
    """hooked_wing of ``scripts/hard_models.py`` at 1e-2: its sections' splines hook 0.3 mm past the
    trailing edge and back to the seam, a ridge the lofted face's triangles span. Edges across the seam
    were split at the parametric middle of the other way round, and the face stayed at 1.33e-2; split
    the short way round it is within its target."""
    from cadedge.mesh.report import AFTER_MESH_HOOK

    result = mesh_shape(_hard_model("hooked_wing", tmp_path), ald=1e-2)
    assert result.ok, result.problems()
    deficits = _independent_deficits(result)
    assert np.all(np.abs(deficits) <= 1e-2), deficits
    assert result.extras[AFTER_MESH_HOOK]["split"] == [1]
    assert result.report.folded == 0 and result.report.min_angle >= 10.0


def test_a_razor_thin_wing_is_split_on_its_ridges_within_the_target(tmp_path):
    """razor_wing (``scripts/hard_models.py``, 0.12 mm thick over a 20 mm chord) at 1e-3: its lofted face
    folds over ridges narrower than its triangles (held at a size floor) and came out 3.1e-2 short, 31
    times the target. Splits at edges' middles reached 7.5e-3 in their 12 sets; split where each split
    adds the most area (on the ridge) it is within the target."""
    from cadedge.mesh.report import AFTER_MESH_HOOK

    result = mesh_shape(_hard_model("razor_wing", tmp_path), ald=1e-3)
    assert result.ok, result.problems()
    deficits = _independent_deficits(result)
    assert np.all(np.abs(deficits) <= 1e-3), deficits
    assert result.extras[AFTER_MESH_HOOK]["split"] == [1]
    assert result.report.folded == 0


def test_a_twisted_blade_is_left_with_no_folded_triangle_and_every_face_within_the_target(tmp_path):
    """twisted_blade of ``scripts/hard_models.py`` at 1e-2: gmsh's Delaunay mesh of its blade face folds a
    triangle, whose area counted twice: the face read 8.4e-3, within the target, and stayed so meshed.
    Measured once unfolded it is over (1.16e-2: its trailing edge's ridge, 0.013 mm in radius, spanned
    by triangles at every size gmsh was given), and its edges are split on the surface until it is
    within (:mod:`cadedge.mesh.midpoints`); it was named at 1.22e-2 before."""
    from cadedge.mesh.report import AFTER_MESH_HOOK

    result = mesh_shape(_hard_model("twisted_blade", tmp_path), ald=1e-2)
    assert result.ok, result.problems()
    assert result.report.folded == 0
    deficits = _independent_deficits(result)
    for face in result.report.faces:
        assert face.area_deficit == pytest.approx(deficits[face.face - 1], abs=1e-9)
    assert np.all(np.abs(deficits) <= 1e-2), deficits
    assert result.extras[AFTER_MESH_HOOK]["split"] == [1]
    assert result.report.min_angle >= 20.0


def test_a_plane_frontal_delaunay_fans_is_meshed_by_delaunay():
    """A 70 mm disk whose circle is cut in 7 682 segments of 0.029 mm (as a torus grid's parallel is):
    gmsh's Frontal-Delaunay joins them to a few nodes far inside (triangles of a few degrees);
    ``keep_better_angles`` meshes it by Delaunay, which grades them inwards (23.7 degrees before the face
    optimiser), and keeps that."""
    from cadedge.mesh.facemesh import triangle_min_angles
    from cadedge.mesh.floored import DELAUNAY
    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.outcomes import FaceOutcome
    from cadedge.mesh.remesh import keep_better_angles

    with gmsh_session():
        gmsh.model.occ.addDisk(0, 0, 0, 34.8, 34.8)
        gmsh.model.occ.synchronize()
        ((_, curve),) = gmsh.model.getEntities(1)
        gmsh.model.mesh.setTransfiniteCurve(curve, 7683)
        for name, value in (("Mesh.MeshSizeFromCurvature", 0), ("Mesh.MeshSizeFromPoints", 0),
                            ("Mesh.MeshSizeExtendFromBoundary", 0), ("Mesh.MeshSizeMax", 1.8)):
            gmsh.option.setNumber(name, value)
        grown = gmsh.model.mesh.field.add("Extend")
        gmsh.model.mesh.field.setNumbers(grown, "CurvesList", [curve])
        gmsh.model.mesh.field.setNumber(grown, "SizeMax", 1.8)
        gmsh.model.mesh.field.setNumber(grown, "DistMax", 3.5)
        gmsh.model.mesh.field.setAsBackgroundMesh(grown)
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.model.mesh.generate(2)
        ((_, disk),) = gmsh.model.getEntities(2)
        fan = float(triangle_min_angles(disk).min())
        assert fan < 10.0
        outcomes = {disk: FaceOutcome(face=1, surface=disk, strategy="Frontal-Delaunay", triangles=1)}
        best = keep_better_angles(disk, DELAUNAY, 10.0, outcomes, fan)
        assert best == pytest.approx(float(triangle_min_angles(disk).min())) and best >= 20.0
        assert outcomes[disk].strategy == DELAUNAY and outcomes[disk].triangles > 30_000
