"""Boundary segments graded into a face's narrow corners (cadedge.mesh.wedges): a hex prism whose
30-degree chamfer cone touches each flat at one point, built with OCP's own primitives, its grids graded
and the part meshed through the whole mesher."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BRepAlgoAPI import BRepAlgoAPI_Common  # noqa: E402
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon  # noqa: E402
from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism, BRepPrimAPI_MakeRevol  # noqa: E402
from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Vec  # noqa: E402

from cadedge import refine_shape  # noqa: E402
from cadedge.mesh.grading import cut_on_curve  # noqa: E402
from cadedge.mesh.narrow import from_vertex, narrow_corners, tip_length  # noqa: E402
from cadedge.mesh.wedges import MAX_JUMP, TIP_RATIO, _jump, _segment_distances, grade_wedges  # noqa: E402
from cadedge.mesh.widths import TIP_SLACK, WIDTH_RATIO, match_corners  # noqa: E402


def _polygon_face(points):
    poly = BRepBuilderAPI_MakePolygon()
    for p in points:
        poly.Add(gp_Pnt(*p))
    poly.Close()
    return BRepBuilderAPI_MakeFace(poly.Wire(), True).Face()


def _chamfered_prism(across: float = 16.0, height: float = 4.0):
    """A hex prism ``across`` its flats, its top chamfered at 30 degrees by a cone through the circle that
    touches the flats: each of the 6 cone faces ends in two cusps (circle and hyperbola tangent)."""
    r = across / 2 / math.cos(math.pi / 6)
    hexagon = _polygon_face([(r * math.cos(k * math.pi / 3), r * math.sin(k * math.pi / 3), 0.0) for k in range(6)])
    prism = BRepPrimAPI_MakePrism(hexagon, gp_Vec(0.0, 0.0, height)).Shape()
    r0, big = across / 2, r + 0.5
    rise = (big - r0) * math.tan(math.radians(30.0))
    profile = _polygon_face([(0, 0, 0), (big, 0, 0), (big, 0, height - rise), (r0, 0, height), (0, 0, height)])
    keep = BRepPrimAPI_MakeRevol(profile, gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 2 * math.pi).Shape()
    return BRepAlgoAPI_Common(prism, keep).Shape()


def _even(grid, pieces: int):
    """``grid`` with every curved edge cut in ``pieces`` equal parameter steps on its curve, as the cone
    faces' area target cuts them before the corners are seen (refined alone, a 60-degree arc has 3)."""
    from cadedge.mesh.grading import split_on_curve
    from cadedge.mesh.proximity import _LazyCurves
    from cadedge.shapegrid import end_tolerances, with_edges

    curves, ends = _LazyCurves(grid), end_tolerances(grid)
    edges = [split_on_curve(e, curves, np.full(e.segments, max(1, pieces // e.segments)), ends=ends[e.id])
             if e.curve in ("Circle", "Hyperbola") else e for e in grid.edges]
    return with_edges(grid, edges)


def test_the_cusps_of_a_chamfer_are_found_and_graded_with_equal_tips_and_their_points_kept():
    grid = _even(refine_shape(_chamfered_prism(), ald=1e-2), 12)
    corners = narrow_corners(list(grid.edges))
    assert len(corners) == 12  # two cusps on each of the 6 cone faces
    assert all(c.angle < 5.0 for c in corners)
    graded = grade_wedges(grid)
    for before, after in zip(grid.edges, graded.edges):
        assert {tuple(p) for p in before.points.round(12)} <= {tuple(p) for p in after.points.round(12)}
    assert graded.segments > grid.segments + 12 * 2 * 5
    for c in narrow_corners(list(graded.edges)):
        one, two = (from_vertex(graded.edges[k], s) for k, s in c.sides)
        tips = [np.linalg.norm(one[1] - one[0]), np.linalg.norm(two[1] - two[0])]
        assert max(tips) <= TIP_RATIO * min(tips) * 1.001  # the longer tip cut at the shorter's length
        for mine, other in ((one, two), (two, one)):
            width = _segment_distances(mine[1:-1], other[:-1], other[1:])
            length = np.linalg.norm(np.diff(mine[1:], axis=0), axis=1)
            assert tips[0] / (WIDTH_RATIO * width[0]) <= MAX_JUMP
            assert np.all(length <= WIDTH_RATIO * width * 1.25)  # graded by the width along each piece
    again = grade_wedges(graded)  # graded once is graded for good
    assert again.segments <= graded.segments * 1.02


def _jumps(grid):
    return [_jump(*(from_vertex(grid.edges[k], s) for k, s in c.sides), WIDTH_RATIO)
            for c in narrow_corners(list(grid.edges))]


def test_tips_too_short_to_grade_are_lengthened_by_dropping_only_the_points_the_fits_added():
    """Cut as finely as the cone faces' area target cuts them at 1e-3, the tips stand beside graded pieces
    over MAX_JUMP times shorter: such corners were left as they were. The points added since the edges
    were refined may go, so the tips are lengthened until they are graded; the refined points stay."""
    from cadedge.mesh.fidelity import brep_face_areas

    refined = refine_shape(_chamfered_prism(), ald=1e-2)
    fitted = _even(refined, 48)
    assert min(_jumps(fitted)) > MAX_JUMP
    ungraded = grade_wedges(fitted)
    assert ungraded.segments <= fitted.segments + 12  # only the tips made equal
    areas = brep_face_areas(refined.shape)
    graded = grade_wedges(fitted, keep=refined, areas=areas, target=1e-2)
    assert max(_jumps(graded)) <= MAX_JUMP
    assert graded.segments > fitted.segments  # the sides graded after the tips
    for kept, after in zip(refined.edges, graded.edges):
        assert {tuple(p) for p in kept.points.round(12)} <= {tuple(p) for p in after.points.round(12)}
    for c in narrow_corners(list(graded.edges)):
        tips = [tip_length(graded.edges[k], s) for k, s in c.sides]
        assert max(tips) <= TIP_RATIO * min(tips)
        assert min(tips) > 2 * min(tip_length(fitted.edges[k], s) for k, s in c.sides)
    # where the faces' area target leaves no room for the longer tips' chords, none is lengthened
    tight = grade_wedges(fitted, keep=refined, areas=areas, target=1e-7)
    assert tight.segments == ungraded.segments


def test_corner_matching_never_halves_a_narrow_corners_tip_below_the_other_tip():
    """Halving the longer tip at a cusp (as at any other corner) made the triangle on both tips, which
    the cusp forces, narrower: 1.59 -> 1.25 degrees on an M10 nut at 1e-2."""
    grid = _even(refine_shape(_chamfered_prism(), ald=1e-2), 12)
    matched = match_corners(grid)
    uneven = 0
    for c in narrow_corners(list(grid.edges)):
        before = [tip_length(grid.edges[k], s) for k, s in c.sides]
        after = [tip_length(matched.edges[k], s) for k, s in c.sides]
        assert min(after) >= (1.0 - TIP_SLACK) * min(before)
        uneven += 1.5 < max(before) / min(before) < 2.0 and max(after) == pytest.approx(max(before))
    assert uneven  # where plain matching would have halved the longer tip below the shorter


def test_a_chamfer_touching_its_flats_leaves_only_the_cusps_forced_triangles_thin():
    """At 1e-2 every triangle near a cusp spanned the wedge: 3.15% of the part's triangles were under
    20 degrees (cadedge before wedges.py), 6 or more at each cusp."""
    from cadedge.mesh import mesh_shape

    result = mesh_shape(_chamfered_prism(), ald=1e-2)
    assert result.ok, result.problems()
    report = result.report
    assert report.unforced_slivers == 0
    assert report.below_20 < 0.01
    assert report.triangles * report.below_20 <= 2 * 12  # the tip's triangle, at most one more, per cusp
    assert report.worst_deficit <= 1e-2


def test_at_1e_3_the_chamfers_cusps_have_their_tips_lengthened_and_graded():
    """At 1e-3 the cone faces' area target cuts the cusps' sides so finely that their tips could not be
    graded: 1.68% of the triangles were under 20 degrees (cadedge before the tips were lengthened), down
    to 0.36 degrees."""
    from cadedge.mesh import mesh_shape

    result = mesh_shape(_chamfered_prism(), ald=1e-3)
    assert result.ok, result.problems()
    report = result.report
    assert report.unforced_slivers == 0
    assert report.triangles * report.below_20 <= 2 * 12
    assert report.min_angle > 1.0
    assert report.worst_deficit <= 1e-3


def _plate_with_hole_touching_a_fillet():
    """A 40 x 30 x 5 plate with 6 mm corner fillets and a 2.5 mm hole inside one fillet, touching it: the
    top and bottom faces' outline passes the tangent vertex twice (four edge ends, two cusps)."""
    cq = pytest.importorskip("cadquery")
    plate = cq.Workplane("XY").box(40, 30, 5).edges("|Z").fillet(6)
    d = 6 - 2.5
    hole = cq.Workplane("XY").center(14 + d / math.sqrt(2), -9 - d / math.sqrt(2)).circle(2.5).extrude(5, both=True)
    return plate.cut(hole).val().wrapped


def test_a_hole_touching_the_outline_has_both_its_cusps_graded():
    """At the tangent vertex each face has four edge ends: they pair into two cusps, each a fillet arc with
    the hole's circle. They were left ungraded (a corner had to have exactly two ends): four triangles
    under 20 degrees on each face there, two on the tips and two beside them (with more holes, at 1e-2:
    1.08% of the triangles under 20 degrees and two 4.1-degree ones not forced by the B-rep)."""
    from cadedge.mesh.quality import min_angles
    from cadedge.mesh import mesh_shape

    grid = refine_shape(_plate_with_hole_touching_a_fillet(), ald=1e-2)
    corners = [c for c in narrow_corners(list(grid.edges))
               if np.allclose(grid.vertices[c.vertex - 1].point[:2], [14 + 6 / math.sqrt(2), -9 - 6 / math.sqrt(2)])]
    assert len(corners) == 4 and len({(c.face, c.vertex) for c in corners}) == 2
    for c in corners:
        assert c.angle < 2.0 and {grid.edges[i].curve for i, _ in c.sides} == {"Circle"}
        assert len({grid.edges[i].id for i, _ in c.sides}) == 2
    result = mesh_shape(grid, workers=1)
    assert result.ok, result.problems()
    assert result.report.below_20 <= 0.01
    assert all(s.forced for s in result.report.small_angles)
    angles = min_angles(result.nodes, result.triangles)
    for c in corners:  # under 20 degrees, only the triangles on the two cusps' tips
        assert np.sum(angles[result.triangle_faces == c.face] < 20.0) <= 2


def test_a_wedge_beside_a_loose_edge_is_graded_on_both_sides():
    """A 25-long prism on a 1.7-degree triangle whose long sides' top and bottom edges carry a tolerance
    of 0.005 (as B-spline edges of OCCT's sample CrankArm.brep do beside its planar slivers). Splits leave
    an edge whole where its tolerance is over a thousandth of a piece; the wedge's loose side kept its one
    segment, and 19% of the wedge faces' triangles were under 20 degrees, down to 1.0 (under the corner's
    own 1.7). Its pieces are now cut down to 20 tolerances (``LOOSE_SHARE``)."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.ShapeFix import ShapeFix_ShapeTolerance
    from OCP.TopAbs import TopAbs_EDGE
    from cadedge.occt.compat import TopoDS

    from cadedge.mesh import mesh_shape
    from cadedge.occt.topology import indexed

    length, opening = 25.0, 1.7
    tip = (length, length * math.tan(math.radians(opening)), 0.0)
    prism = BRepPrimAPI_MakePrism(_polygon_face([(0, 0, 0), (length, 0, 0), tip]), gp_Vec(0, 0, 2)).Shape()
    fix, loosened, edges = ShapeFix_ShapeTolerance(), 0, indexed(prism, TopAbs_EDGE)
    for i in range(1, edges.Size() + 1):
        edge = TopoDS.Edge_s(edges.FindKey(i))
        curve = BRepAdaptor_Curve(edge)
        a, b = curve.Value(curve.FirstParameter()), curve.Value(curve.LastParameter())
        if abs(a.X() - b.X()) > 1.0 and abs(a.Y() - b.Y()) > 0.1:  # the slanted side, top and bottom
            fix.SetTolerance(edge, 0.005, TopAbs_EDGE)
            loosened += 1
    assert loosened == 2
    report = mesh_shape(prism, ald=1e-2).report
    wedges = [f for f in report.faces if abs(f.brep_area - 0.5 * length * tip[1]) < 1e-6]
    assert len(wedges) == 2
    for f in wedges:
        assert f.min_angle > opening - 0.05 and f.below_20 < 0.05, (f.min_angle, f.below_20)
    assert not [a for a in report.small_angles if a.angle < 5 and not a.forced]


@pytest.mark.corpus
def test_tips_that_a_later_area_fit_cut_are_matched_again_before_meshing():
    """build123d's M6 countersunk screw at 1e-3: after its narrow corners were graded, the curved faces'
    second fit cut the head cone's circle in thirds, and the two corners at its end were left with tips
    of 0.059 and 0.019 (KiCad's USB-C receptacle: the planar fit cut one tip of a strip 0.0004 wide,
    and the triangles on the other, 25 times the strip's width, had 4.6 degrees). The grids imposed as
    boundary nodes have every narrow corner's tips matched again."""
    from cadedge.mesh import DEFAULT_GROWTH
    from cadedge.mesh.fidelity import prepare
    from cadedge.mesh.jobclock import JobClock
    from cadedge.mesh.node_grids import fit_node_grids
    from cadedge.mesh.sizes import SizeField
    from conftest import CORPUS

    refined = refine_shape(CORPUS / "gumyr__build123d__M6-1x12-countersunk-screw.step", ald=1e-3)
    fitted, fidelity = prepare(refined, 1e-3)
    grid, _, notes = fit_node_grids(fitted, refined, fidelity, 1e-3, growth=DEFAULT_GROWTH,
                                    make_field=lambda g: SizeField(g, growth=DEFAULT_GROWTH), cap=None,
                                    clock=JobClock(600.0))
    assert not notes
    corners = narrow_corners(grid.edges)
    assert len(corners) >= 2
    for c in corners:
        tips = [tip_length(grid.edges[i], s) for i, s in c.sides]
        assert max(tips) <= TIP_RATIO * min(tips), (c, tips)


def _rim_hole():
    """A disk of radius 10, 5 thick, with a hole of radius 4 touching its rim from inside: its top and bottom
    faces narrow to two cusps at the touching point (two circles of radii 10 and 4, tangent)."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Ax2

    disk = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 10.0, 5.0).Shape()
    hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(6, 0, 0), gp_Dir(0, 0, 1)), 4.0, 5.0).Shape()
    return BRepAlgoAPI_Cut(disk, hole).Shape()


def test_a_cusps_tips_reach_the_points_the_edges_were_refined_with_where_the_areas_allow():
    """A cusp's forced triangle is as wide as its tips are long (its sides part as the square of the
    distance). The planar faces' area fit cut the rim_hole's circles into 0.96 pieces where the edges as
    refined had 1.9, and the tips were lengthened only to a jump of 20 over the graded pieces beside them:
    4.2-degree triangles at 1e-2, where gmsh alone has 11.6. Given the area the faces' fits leave them,
    the tips reach the first refined points (the fits' points dropped, the refined ones kept): 8.3
    degrees, every face within the target, the triangles under 5 degrees only the cusps' own."""
    from cadedge.mesh import mesh_shape
    from cadedge.mesh.boundary_fit import fit_boundaries
    from cadedge.mesh.fidelity import brep_face_areas, meshed_kinds

    refined = refine_shape(_rim_hole(), ald=1e-2)
    areas = brep_face_areas(refined.shape)
    fitted = fit_boundaries(refined, 1e-2, brep_areas=areas, kinds=meshed_kinds(refined.shape))[0]
    corners = narrow_corners(list(fitted.edges))
    assert len(corners) == 4
    plain = grade_wedges(fitted, keep=refined, areas=areas, target=1e-2)
    wide = grade_wedges(fitted, keep=refined, areas=areas, target=1e-2, spare=lambda: np.full(len(areas), np.inf))
    for c in corners:
        first = [float(np.linalg.norm(from_vertex(refined.edges[k], s)[1] - from_vertex(refined.edges[k], s)[0]))
                 for k, s in c.sides]
        before = [tip_length(plain.edges[k], s) for k, s in c.sides]
        after = [tip_length(wide.edges[k], s) for k, s in c.sides]
        assert max(after) <= TIP_RATIO * min(after)
        assert min(after) > 1.5 * max(before) and min(after) <= min(first) * (1 + 1e-9)
    for kept, now in zip(refined.edges, wide.edges):
        assert {tuple(p) for p in kept.points.round(12)} <= {tuple(p) for p in now.points.round(12)}

    result = mesh_shape(_rim_hole(), ald=1e-2, workers=1)
    assert result.ok, result.problems()
    assert result.report.worst_deficit <= 1e-2 and result.report.unforced_slivers == 0
    assert result.report.min_angle > 8.0


def _ringed_hole(width: float = 0.01):
    """A disk of radius 3 and 2 thick whose top and bottom are each split into a ring ``width`` wide round a
    disk face (a disk and a ring fused, not cleaned), with a hole of radius 1.2 touching the ring's inner
    circle from inside: the disk faces narrow to cusps on that circle, the thin ring across it."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Ax2

    def cylinder(x: float, radius: float):
        return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(x, 0, 0), gp_Dir(0, 0, 1)), radius, 2.0).Shape()

    inner = 3.0 - width
    ring = BRepAlgoAPI_Cut(cylinder(0.0, 3.0), cylinder(0.0, inner)).Shape()
    body = BRepAlgoAPI_Fuse(cylinder(0.0, inner), ring).Shape()
    return BRepAlgoAPI_Cut(body, cylinder(inner - 1.2, 1.2)).Shape()


def test_a_cusps_tips_leave_the_thin_faces_across_them_no_sliver():
    """A cusp's tips reach the points the edges were refined with only as far as the faces across them
    keep triangles of ACROSS_DEG: the ring 0.01 wide across the cusps' circle had that circle's tips
    lengthened past its width splits, and 7 triangles under 5 degrees (4.3), none forced by the B-rep
    (the Fusion pump's plane 12 of *Files from elsewhere*: 24, the ring 0.05 wide, the tip 2.4). Now
    only the cusps' own forced triangles are under 5 degrees, every face within the target."""
    from cadedge.mesh import mesh_shape
    from cadedge.mesh.wedges import ACROSS_DEG

    assert ACROSS_DEG >= 5.0
    result = mesh_shape(_ringed_hole(), ald=1e-2, workers=1)
    assert result.ok, result.problems()
    report = result.report
    assert report.worst_deficit <= 1e-2 and report.unforced_slivers == 0
    assert {a.face for a in report.small_angles} == {c.face for c in narrow_corners(list(result.grid.edges))}


def test_a_cusps_tips_drop_the_points_the_growth_limit_put_there_within_the_edges_slack():
    """The refiner's growth limit grades an edge's segments from the shortest edge at each vertex: a fan's
    shroud, a cylinder band whose seam is cut 0.2 above the cusps where its circle touches the square's
    sides, had the circle and the sides cut from 0.4 up, doubling, and the cusps' tips stopped there: 0.19
    degrees, gmsh's 7.5. Such points may go where the edge keeps half its slack below its target (and the
    tips stay within 20 times the vertex's shortest other edge and twice the faces' widths across): here
    the rim_hole's circles are cut at one cusp as the growth limit would (the points then in the grid the
    tips keep), and its tips still reach those of the other cusp, every edge within its target. With no
    slack left, the points stay."""
    from cadedge.mesh.boundary_fit import fit_boundaries
    from cadedge.mesh.fidelity import brep_face_areas, meshed_kinds
    from cadedge.mesh.wedges import _growth_points, _Near, _reach
    from cadedge.shapegrid import end_tolerances, with_edges

    refined = refine_shape(_rim_hole(), ald=1e-2)
    areas = brep_face_areas(refined.shape)
    kinds = meshed_kinds(refined.shape)
    top = [c for c in narrow_corners(list(refined.edges)) if c.face == narrow_corners(list(refined.edges))[0].face]
    assert len(top) == 2
    growth, other = [c for c in top if all(s for _, s in c.sides)], [c for c in top if not any(s for _, s in c.sides)]
    assert len(growth) == len(other) == 1
    edges, ends = list(refined.edges), end_tolerances(refined)
    for k, _ in growth[0].sides:  # each circle's first segment cut at 0.2 and 0.5 of it, as from a short edge
        edges[k] = cut_on_curve(edges[k], refined.curves, {0: np.array([0.2, 0.5])}, ends=ends[edges[k].id])
    grown = with_edges(refined, edges)
    fitted = fit_boundaries(grown, 1e-2, brep_areas=areas, kinds=kinds)[0]
    graded = grade_wedges(fitted, keep=grown, areas=areas, target=1e-2, spare=lambda: np.full(len(areas), np.inf))
    tips = [min(tip_length(graded.edges[k], s) for k, s in c.sides) for c in (growth[0], other[0])]
    first = min(tip_length(grown.edges[k], s) for k, s in growth[0].sides)
    assert tips[0] > 2.0 * first and tips[0] >= tips[1] / TIP_RATIO
    for now, kept in zip(graded.edges, refined.edges):
        if not now.degenerate:
            assert 1.0 - now.length / (kept.length / (1.0 - kept.ald_estimate)) <= 1e-2

    c = growth[0]
    sides, reach, _ = _reach(list(fitted.edges), c, list(grown.edges), WIDTH_RATIO)
    for target, freed in ((0.0, False), (1e-2, True)):  # a target no polyline meets: no slack
        targets = {e.id: target for e in grown.edges}
        out, _ = _growth_points(list(fitted.edges), c, sides, reach, list(grown.edges), targets, WIDTH_RATIO,
                                _Near.of(list(fitted.edges)))
        assert any((after[1] & ~before[1]).any() for after, before in zip(out, reach)) == freed


def test_tips_are_not_lengthened_past_what_a_thin_face_across_them_allows():
    """The thin faces' splits cut the ring's inner circle, 0.003 across to its outer one, into pieces of
    about 0.003, and the disk faces' cusps on that circle had their tips lengthened to 0.11 by dropping
    those points: each tip then spanned the ring (the Ultimaker 2 feeder's cylinder band 0.001 wide: 62
    triangles of 0.09-5 degrees that nothing forced). A corner whose tips would span a face across them
    over WIDTH_RATIO times its width is left as the splits made it."""
    from cadedge.mesh.boundary_fit import fit_boundaries
    from cadedge.mesh.fidelity import brep_face_areas, meshed_kinds
    from cadedge.mesh.widths import fit_to_widths

    width = 0.003
    refined = refine_shape(_ringed_hole(width), ald=1e-2)
    areas = brep_face_areas(refined.shape)
    fitted = fit_to_widths(fit_boundaries(refined, 1e-2, brep_areas=areas, kinds=meshed_kinds(refined.shape))[0])
    graded = grade_wedges(fitted, keep=refined, areas=areas, target=1e-2)
    corners = narrow_corners(list(graded.edges))
    assert len(corners) == 4
    ring = {f for f in range(1, len(areas) + 1) if areas[f - 1] < 2 * math.pi * 3.0 * width * 1.01}
    assert len(ring) == 2  # the top and bottom rings
    for c in corners:
        for k, s in c.sides:
            if set(graded.edges[k].faces) & ring:  # the ring's inner circle, the ring across its tip
                assert tip_length(graded.edges[k], s) <= WIDTH_RATIO * width
        tips = [tip_length(graded.edges[k], s) for k, s in c.sides]
        assert max(tips) <= TIP_RATIO * min(tips)
