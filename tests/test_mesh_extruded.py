"""Faces of linear extrusion (cadedge.mesh.extruded, cadedge.occt.areas.extrusion_area): a spline with
sharp valleys extruded by gmsh's OCC kernel, meshed laid flat and measured against its exact area."""

from __future__ import annotations

import math

import numpy as np
import pytest

gmsh = pytest.importorskip("gmsh")

HEIGHT = 4.0


def _valleyed_prism(depth: float = 1.0) -> tuple[int, list[int]]:
    """In the current gmsh model: a periodic spline through 120 points of ``r = 10 + depth |cos 3t|**0.3``
    (6 sharp valleys: V-shaped, their flanks about 85 degrees apart at depth 1, 33 at depth 3) extruded by
    :data:`HEIGHT`; returns its side surface and its spline curves."""
    points = []
    for k in range(120):
        t = 2.0 * math.pi * k / 120
        r = 10.0 + depth * abs(math.cos(3.0 * t)) ** 0.3
        points.append(gmsh.model.occ.addPoint(r * math.cos(t), r * math.sin(t), 0.0))
    spline = gmsh.model.occ.addSpline(points + points[:1])
    base = gmsh.model.occ.addPlaneSurface([gmsh.model.occ.addCurveLoop([spline])])
    gmsh.model.occ.extrude([(2, base)], 0.0, 0.0, HEIGHT)
    gmsh.model.occ.synchronize()
    (side,) = [s for _, s in gmsh.model.getEntities(2) if gmsh.model.getType(2, s) != "Plane"]
    splines = [c for _, c in gmsh.model.getEntities(1) if gmsh.model.occ.getMass(1, c) > 2.0 * HEIGHT]
    return side, splines


def test_a_sharp_valleyed_extrusion_is_meshed_flat_within_its_chords():
    """The side is an extrusion, meshed flat first; unrolled it meshes, matches its curves' segments (the
    seam twice), its nodes lie on it, its triangles keep gmsh's plane shapes (no angle under 20 degrees)
    and its area is under its exact one (its section's length times the height) by at most what its
    boundary chords lose."""
    from cadedge.mesh.extruded import extrusion_of, is_extrusion, mesh_unrolled
    from cadedge.mesh.generate import surface_ok
    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.quality import triangle_angles
    from cadedge.mesh.strategies import EXTRUSION_ORDER, GMSH_ORDER, face_order

    with gmsh_session():
        side, splines = _valleyed_prism()
        assert face_order(side) == EXTRUSION_ORDER
        assert all(face_order(s) == GMSH_ORDER and not is_extrusion(s)
                   for _, s in gmsh.model.getEntities(2) if s != side)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25)
        gmsh.model.mesh.generate(1)
        ext = extrusion_of(side)
        length = gmsh.model.occ.getMass(1, splines[0])
        # the section is sampled more finely where it turns fast (its valleys): those samples' trapezoids
        # no longer cancel the others' errors as a periodic section's evenly spaced ones do (3e-7 -> 4e-6)
        assert ext is not None and ext.closed and ext.length == pytest.approx(length, rel=1e-5)
        assert np.allclose(np.abs(ext.along), [0.0, 0.0, 1.0])
        assert mesh_unrolled(side, 6) is None
        assert surface_ok(side)
        tags, coords, params = gmsh.model.mesh.getNodes(2, side)
        x = np.asarray(coords, dtype=float).reshape(-1, 3)
        on = np.asarray(gmsh.model.getValue(2, side, list(params)), dtype=float).reshape(-1, 3)
        assert len(x) and np.abs(on - x).max() < 1e-9
        nodes, xyz, _ = gmsh.model.mesh.getNodes()
        where = {int(t): i for i, t in enumerate(nodes)}
        _, tri = gmsh.model.mesh.getElementsByType(2, side)
        rows = np.array([where[int(t)] for t in tri]).reshape(-1, 3)
        p = np.asarray(xyz, dtype=float).reshape(-1, 3)
        assert triangle_angles(p, rows).min() > 20.0
        t = p[rows]
        area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum()
        _, seg = gmsh.model.mesh.getElementsByType(1, splines[0])
        chords = np.linalg.norm(np.diff(p[[where[int(s)] for s in seg]].reshape(-1, 2, 3), axis=1), axis=2).sum()
        assert 0.999 * chords * HEIGHT < area < length * HEIGHT


def test_a_folded_section_is_meshed_with_a_line_of_nodes_along_each_fold():
    """The deep prism's 6 valleys fold its section (it turns about 150 degrees within a sixth of a
    triangle's size, here 1): the flat mesh has a line of nodes along each (:func:`fold_lines`), pinned (not
    movable, their edges kept by the optimiser); no triangle spans a fold. The shallow prism (valleys
    turning about 95 degrees), a smooth section and a U-turn of radius 0.3 among sizes of 1 have none;
    the U-turn is a fold among sizes of 6, unless what its flanks would lose is over the budget."""
    from cadedge.mesh.creases import CREASES, fold_loss, folds
    from cadedge.mesh.extruded import extrusion_of, mesh_unrolled
    from cadedge.mesh.facemesh import read_face
    from cadedge.mesh.gmsh_model import gmsh_session

    with gmsh_session():
        side, _ = _valleyed_prism()
        assert len(folds(extrusion_of(side), np.full(4096, 0.25))[0]) == 0
    with gmsh_session():
        side, _ = _valleyed_prism(depth=3.0)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 1.0)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 12)  # curves split finely at the valleys
        gmsh.model.mesh.generate(1)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        ext = extrusion_of(side)
        at, window = folds(ext, np.full(len(ext.x), 1.0))
        bottoms = np.asarray(gmsh.model.getValue(2, side, ext.params(at, np.interp(at, ext.x, ext.base)).ravel()))
        assert window == 1.0 and len(at) == 6
        assert np.abs(np.hypot(*bottoms.reshape(-1, 3)[:, :2].T) - 10.0).max() < 0.01  # r = 10: the valleys'
        # bottoms
        assert mesh_unrolled(side, 6) is None
        column, t_folds, ends = CREASES[side]
        assert len(t_folds) == 6 and len(ends) >= 12
        mesh = read_face(side)
        t = mesh.uv[:, column]
        for t_fold in t_folds:
            on = np.abs(t - t_fold) <= 1e-9
            assert on.sum() >= HEIGHT - 1
            assert mesh.pinned[on].all() and not mesh.movable[on].any()
            corners = t[mesh.tri]  # NaN for the boundary's nodes, which are not pinned
            known = ~np.isnan(corners).any(axis=1)
            spans = (corners[known].min(axis=1) < t_fold - 1e-9) & (corners[known].max(axis=1) > t_fold + 1e-9)
            assert not spans.any()
        assert any(p in mesh.fixed and mesh.pinned[list(p)].all() for p in mesh.fixed)

        smooth = ext.__class__(*[getattr(ext, f) for f in ("swap", "along", "rate", "v0", "t", "x", "base")],
                               np.column_stack([-np.sin(ext.x / 10.0), np.cos(ext.x / 10.0), 0.0 * ext.x]),
                               ext.closed)
        assert len(folds(smooth, np.full(len(ext.x), 0.25))[0]) == 0
        x = np.linspace(0.0, 10.0, 4001)
        turn = np.pi * np.clip((x - 5.0) / (np.pi * 0.3) + 0.5, 0.0, 1.0)  # a half circle of radius 0.3
        u_turn = ext.__class__(False, ext.along, ext.rate, 0.0, x, x, x,
                               np.column_stack([np.cos(turn), np.sin(turn), 0.0 * x]), False)
        assert len(folds(u_turn, np.full(len(x), 1.0))[0]) == 0
        assert len(folds(u_turn, np.full(len(x), 6.0))[0]) == 1
        # what its flanks would lose beside a line, a quarter circle of radius 0.3 each: (pi/2 - sqrt 2) 0.3
        assert fold_loss(u_turn, 5.0, 3.0) == pytest.approx(2 * (0.5 * np.pi - np.sqrt(2)) * 0.3, rel=0.2)
        assert len(folds(u_turn, np.full(len(x), 6.0), budget=0.05)[0]) == 0


#: A key's section: square notches (90-degree corners) between straight runs.
KEY = [(0.0, 0.0), (6.0, 0.0), (6.0, -2.0), (9.0, -2.0), (9.0, 0.0), (14.0, 0.0), (14.0, -3.0), (17.0, -3.0),
       (17.0, 0.0), (30.0, 0.0)]


def _bspline_wall(section: list[tuple[float, float]], height: float = 2.5) -> int:
    """In the current gmsh model: a B-spline surface of degree 1 by 1 through ``section`` (x, y) at z = 0
    and at ``height``, a wall extruded from the polyline (a corner at each of its inner points); its tag."""
    rows = [[gmsh.model.occ.addPoint(x, y, z) for x, y in section] for z in (0.0, height)]
    wall = gmsh.model.occ.addBSplineSurface(rows[0] + rows[1], len(section), degreeU=1, degreeV=1)
    gmsh.model.occ.synchronize()
    return wall


def test_a_bspline_wall_is_laid_flat_only_where_its_section_has_a_corner():
    """gmsh names B-spline surfaces "BSpline surface": straight along one parameter, they are laid flat
    where their section has a corner (gmsh's own mesh cuts across it), not where it is straight or smooth
    (gmsh meshes those as well with fewer triangles). The corners are placed to within a hair (the
    section sampled finely where its heading jumps), so its length is the polyline's and a corner's fold
    loses nothing beside its line, where the table's step alone read each as a round 0.01 wide."""
    from cadedge.mesh.creases import CORNER_TURN, fold_loss, folds, has_corner
    from cadedge.mesh.extruded import extrusion_of, is_extrusion
    from cadedge.mesh.gmsh_model import gmsh_session

    length = sum(math.dist(p, q) for p, q in zip(KEY[:-1], KEY[1:]))
    with gmsh_session():
        keyed = _bspline_wall(KEY)
        flat = _bspline_wall([(0.0, 5.0), (30.0, 5.0)])
        blunt = _bspline_wall([(0.0, 10.0), (15.0, 10.0), (30.0, 10.0 + 30.0 * math.tan(math.radians(CORNER_TURN / 2)))])
        assert {gmsh.model.getType(2, s) for s in (keyed, flat, blunt)} == {"BSpline surface"}
        assert is_extrusion(keyed) and not is_extrusion(flat) and not is_extrusion(blunt)
        ext = extrusion_of(keyed)
        assert has_corner(ext) and ext.length == pytest.approx(length, rel=1e-9)
        at, _ = folds(ext, np.full(len(ext.x), 1.0))
        inner = np.cumsum([math.dist(p, q) for p, q in zip(KEY[:-1], KEY[1:])])[:-1]
        assert np.abs(at - inner).max() < 1e-6 * length
        assert max(fold_loss(ext, xf, 0.125) for xf in at) < 1e-6


def test_a_bspline_walls_corners_get_lines_no_triangle_crosses():
    """Laid flat, the keyed wall (1 high) has a line of nodes at each of its 8 corners (its curves split
    every 1 along their length, so at the corners too, as edge grids are), kept by the face optimiser's
    rules (:func:`crease_nodes`) down to the lines' ends on the boundary: among sizes of 3 each line is a
    single edge between two boundary nodes, which the optimiser once swapped across the corner (a key
    blade's notch spanned, 10.6 degrees). No triangle spans a corner: the mesh's area is the wall's, each
    triangle flat on one flank."""
    from cadedge.mesh.creases import CREASES
    from cadedge.mesh.extruded import mesh_unrolled
    from cadedge.mesh.facemesh import read_face
    from cadedge.mesh.gmsh_model import gmsh_session

    length = sum(math.dist(p, q) for p, q in zip(KEY[:-1], KEY[1:]))  # 40: the corners at whole lengths
    with gmsh_session():
        wall = _bspline_wall(KEY, height=1.0)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 1.0)
        gmsh.model.mesh.generate(1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 3.0)
        assert mesh_unrolled(wall, 6) is None
        creases = CREASES[wall]
        assert len(creases.at) == 8 and len(creases.ends) == 16
        mesh = read_face(wall)
        rows = {int(t): i for i, t in enumerate(mesh.tags)}
        lines: dict[int, list[int]] = {}
        for tag, k in creases.ends.items():
            lines.setdefault(k, []).append(rows[tag])
        assert not mesh.pinned.any()  # no node inside a line
        assert all(tuple(sorted(ends)) in mesh.fixed for ends in lines.values())
        t = mesh.x[mesh.tri]
        area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum()
        assert area == pytest.approx(length, rel=1e-7)


def test_a_folds_spike_of_curvature_is_replaced_by_its_flanks():
    """Within half the window of a fold, the curvature (or sizes) take the value at that span's ends, the
    flanks' (the lower curvature, the larger size); elsewhere they stay."""
    from cadedge.mesh.creases import across_folds

    x = np.linspace(0.0, 10.0, 101)
    k = 0.1 + 0.01 * x
    k[50] = 1e4
    flat = across_folds(x, k, np.array([5.0]), 1.0, np.minimum)
    assert flat.max() <= 0.2 and np.all(flat[44:56] == k[44])  # the span 4.5-5.5 and the sample before
    assert np.array_equal(np.delete(flat, range(44, 56)), np.delete(k, range(44, 56)))
    sizes = across_folds(x, 1.0 / k, np.array([5.0]), 1.0, np.maximum)
    assert np.all(sizes[44:56] == 1.0 / k[44]) and sizes[56] == 1.0 / k[56]


def test_a_folds_line_is_split_as_the_sizes_grow_from_its_ends():
    """Split evenly at the flanks' size, a fold's line met boundary segments 400 times shorter at its ends
    (0.1-degree fans there): its pieces start at its ends' sizes and grow by the job's rate, up to the
    size."""
    from cadedge.mesh.creases import graded_points

    p, q = np.array([3.0, 0.0]), np.array([3.0, 10.0])
    between = graded_points(p, q, 0.01, 0.02, 1.0, 0.25)
    y = np.concatenate([[0.0], between[:, 1], [10.0]])
    pieces = np.diff(y)
    assert np.allclose(between[:, 0], 3.0) and (pieces > 0).all()
    assert pieces[0] < 0.03 and pieces[-1] < 0.05 and pieces.max() <= 1.05
    assert (pieces[:-1] / pieces[1:])[: len(pieces) // 3].max() < 1.0  # growing from the first end
    assert len(graded_points(p, q, 1.0, 1.0, 1.0, 0.25)) == 9  # 10 pieces of the size


def test_an_extrusions_area_is_its_sections_length_times_its_height(tmp_path):
    """OCCT's surface integrations sample a face of extrusion as any surface (on a gear's sharp-valleyed
    side they were 7% and 13% over); :func:`extrusion_area` integrates it span by span of its section:
    the section's length (OCCT's edge length) times the height, and :func:`face_area` takes it. Faces of
    other surfaces get None."""
    pytest.importorskip("OCP")
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.occt.areas import extrusion_area, face_area
    from cadedge.occt.reader import load_shape
    from cadedge.occt.topology import Topology

    path = tmp_path / "valleys.step"
    with gmsh_session():
        _valleyed_prism()
        gmsh.write(str(path))
    topo = Topology(load_shape(path).shape)
    lengths = []
    for edge in topo.edges:
        props = GProp_GProps()
        BRepGProp.LinearProperties_s(edge, props)
        lengths.append(props.Mass())
    section = max(lengths)
    swept = [extrusion_area(face) for face in topo.faces]
    assert sum(a is not None for a in swept) == 1
    (area,) = [a for a in swept if a is not None]
    assert area == pytest.approx(section * HEIGHT, rel=1e-9)
    assert face_area(topo.faces[swept.index(area)]) == area


def test_the_size_field_of_a_long_thin_extrusion_keeps_few_squat_cells():
    """A rod 2 mm round and 1 000 mm long: its table of sizes, 54 816 samples, was one cell per step over
    the whole height (0.0001 wide, 1 000 tall), and gmsh's search through those cells hung the face. The
    field keeps the samples where its sizes vary (a cylinder's: two), in cells no taller than
    ``CELL_ASPECT`` times their column's width (past ``FIELD_CELLS`` cells taller, but still a small part
    of the height), and still gives the table's sizes."""
    from cadedge.mesh.extruded import CELL_ASPECT, FIELD_CELLS, SIZE_STEP, Extrusion, _kept_samples, _size_field
    from cadedge.mesh.gmsh_model import gmsh_session

    x = np.linspace(0.0, 2.0 * math.pi, 54_816)
    along = np.array([0.0, 0.0, 1.0])
    ext = Extrusion(False, along, along, 0.0, x, x, np.zeros_like(x), np.zeros((len(x), 3)), True)
    assert list(_kept_samples(np.full(len(x), 0.17))) == [0, len(x) - 1]
    wavy = 0.2 + 0.1 * np.sin(3.0 * x) ** 2
    keep = _kept_samples(wavy)
    assert len(keep) < len(x) / 50
    assert np.abs(np.interp(x, x[keep], wavy[keep]) / wavy - 1.0).max() <= SIZE_STEP
    for table, aspect in ((np.full(len(x), 0.17), CELL_ASPECT), (wavy, np.inf)):
        with gmsh_session():
            view = _size_field(ext, table, -500.0, 500.0, None)
            _, _, data = gmsh.view.getListData(view)
            cells = np.asarray(data[0]).reshape(-1, 12)  # per triangle: 3 x, 3 y, 3 z, 3 sizes
            widths = np.ptp(cells[:, 0:3], axis=1)
            assert len(cells) <= FIELD_CELLS
            assert (np.ptp(cells[:, 3:6], axis=1) <= aspect * widths * (1 + 1e-9)).all()
            assert np.isclose(np.ptp(cells[:, 3:6]), 1020.0)  # the whole height, padded
            assert np.ptp(cells[:, 3:6], axis=1).max() < 1020.0 / 20
            assert np.abs(cells[:, 9:12].min() / table.min() - 1.0) < 1e-9
