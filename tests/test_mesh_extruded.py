"""Faces of linear extrusion (cadedge.mesh.extruded, cadedge.occt.areas.extrusion_area): a spline with
sharp valleys extruded by gmsh's OCC kernel, meshed laid flat and measured against its exact area."""

from __future__ import annotations

import math

import numpy as np
import pytest

gmsh = pytest.importorskip("gmsh")

HEIGHT = 4.0


def _valleyed_prism() -> tuple[int, list[int]]:
    """In the current gmsh model: a periodic spline through 120 points of ``r = 10 + |cos 3t|**0.3`` (3
    sharp valleys) extruded by :data:`HEIGHT`; returns its side surface and its spline curves."""
    points = []
    for k in range(120):
        t = 2.0 * math.pi * k / 120
        r = 10.0 + abs(math.cos(3.0 * t)) ** 0.3
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
    from cadedge.mesh.generate import EXTRUSION_ORDER, GMSH_ORDER, face_order, surface_ok
    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.quality import triangle_angles

    with gmsh_session():
        side, splines = _valleyed_prism()
        assert face_order(side) == EXTRUSION_ORDER
        assert all(face_order(s) == GMSH_ORDER and not is_extrusion(s)
                   for _, s in gmsh.model.getEntities(2) if s != side)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25)
        gmsh.model.mesh.generate(1)
        ext = extrusion_of(side)
        length = gmsh.model.occ.getMass(1, splines[0])
        assert ext is not None and ext.closed and ext.length == pytest.approx(length, rel=1e-6)
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
    ext = Extrusion(False, along, along, 0.0, x, x, np.zeros_like(x), True)
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
