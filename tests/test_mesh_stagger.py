"""One side of a thin strip staggered against the other (cadedge.mesh.stagger): a thin plate's sides and
a plane with a thin tongue, built with OCP's own primitives, their grids fitted to the widths and meshed
through the whole mesher."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon  # noqa: E402
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox  # noqa: E402
from OCP.gp import gp_Pnt  # noqa: E402

from cadedge import refine_shape  # noqa: E402
from cadedge.mesh import mesh_shape, widths  # noqa: E402
from cadedge.mesh.stagger import LONGEST, stagger  # noqa: E402


def _unstaggered(monkeypatch) -> None:
    monkeypatch.setattr(widths, "stagger", lambda before, fitted, **kw: fitted)


def _tongue(width: float):
    """A 27 x 25 plane with a tongue 3 long and ``width`` wide at one side (the Koch leader arm's plane
    2747 holds one 2.87 long and 5e-5 wide)."""
    poly = BRepBuilderAPI_MakePolygon()
    for x, y in ((3, 0), (30, 0), (30, 25), (3, 25), (3, 12.5 + width), (0, 12.5 + width), (0, 12.5), (3, 12.5)):
        poly.Add(gp_Pnt(x, y, 0.0))
    poly.Close()
    return BRepBuilderAPI_MakeFace(poly.Wire(), True).Face()


def _long_sides(grid, axis: int):
    """The plate's edges along ``axis`` (0: x, 1: y), by the other axis's coordinate and z."""
    return {(round(float(e.points[0, 1 - axis]), 6), round(float(e.points[0, 2]), 6)): e for e in grid.edges
            if not e.degenerate and np.ptp(e.points[:, axis]) > 1.0 and np.ptp(e.points[:, 2]) < 1e-9}


def test_the_sides_of_a_thin_plate_are_staggered_with_the_nodes_they_had(monkeypatch):
    """A 20 x 10 plate 0.05 thick cut at 4 w: its sides' long edges are cut alike, node facing node (right
    triangles of 14.0 degrees). Staggered, on each side one edge's new nodes lie halfway between the
    other's (where the other's pieces are 2 w or longer: the pieces of w at the plate's corners are not),
    with at most two nodes more or one fewer, no segment more than LONGEST times the longest before, and
    the other edge as it was."""
    grid = refine_shape(BRepPrimAPI_MakeBox(20.0, 10.0, 0.05).Shape(), ald=1e-2)
    _unstaggered(monkeypatch)
    alike = widths.fit_to_widths(grid, ratio=4.0)
    fitted = stagger(grid, alike, curves=grid.curves, touches=widths.touching_vertices(grid))
    for axis in (0, 1):
        sides, before = _long_sides(fitted, axis), _long_sides(alike, axis)
        assert len(sides) == 4
        for y in {k[0] for k in sides}:
            bottom, top = sides[y, 0.0], sides[y, 0.05]
            a, b = np.sort(before[y, 0.0].points[:, axis]), np.sort(before[y, 0.05].points[:, axis])
            assert len(a) > 40 and np.allclose(a, b)  # cut alike
            moved = [e for e, old in ((bottom, a), (top, b)) if not np.array_equal(np.sort(e.points[:, axis]), old)]
            assert len(moved) == 1
            other = top if moved[0] is bottom else bottom
            x, o = np.sort(moved[0].points[:, axis]), np.sort(other.points[:, axis])
            assert len(o) - 1 <= len(x) <= len(o) + 2
            inner = x[1:-1]
            k = np.searchsorted(o, inner)
            wide = o[k] - o[k - 1] >= 2 * 0.05 * (1 - 1e-9)  # pieces of 2 w and more: staggered
            assert wide.mean() > 0.9
            assert np.allclose(inner[wide], 0.5 * (o[k - 1] + o[k])[wide], atol=1e-3 * np.diff(o).min())
            assert np.diff(x).max() <= LONGEST * np.diff(o).max() * (1 + 1e-9)
    assert fitted.segments <= alike.segments + 2 * 8


def test_strips_cut_finer_than_20_degree_right_triangles_are_left_alike(monkeypatch):
    """At the ratios a budget does not force (1.5 and 2, right triangles of 33.7 and 26.6 degrees) the
    sides stay as cut: the points the edges were refined with, graded towards the vertices, would break
    the stagger into short stretches with half pieces at their ends. From STAGGER_RATIO up they are
    staggered."""
    assert 2.0 < widths.STAGGER_RATIO < 4.0
    grid = refine_shape(BRepPrimAPI_MakeBox(20.0, 10.0, 0.05).Shape(), ald=1e-2, max_growth=2.0)
    cut = {r: widths.fit_to_widths(grid, ratio=r) for r in (2.0, 4.0)}
    _unstaggered(monkeypatch)
    for r, fitted in cut.items():
        alike = widths.fit_to_widths(grid, ratio=r)
        same = [np.array_equal(e.points, a.points) for e, a in zip(fitted.edges, alike.edges)]
        assert all(same) == (r < widths.STAGGER_RATIO)


def test_a_tongue_cut_at_four_times_its_width_keeps_its_triangles_over_20_degrees(monkeypatch):
    """A tongue 3 long and 0.01 wide with a split budget (``MOST_ADDED``) that only pieces of 4 w fit:
    node facing node it held right triangles of 14.0 degrees, over half the face's triangles (the leader
    arm's plane 2747: 68%). Staggered, isosceles ones of 26.6."""
    monkeypatch.setattr(widths, "MOST_ADDED", 250)
    face = _tongue(0.01)
    fitted = widths.fit_to_widths(refine_shape(face, ald=1e-2))
    tongue = [e for e in fitted.edges if abs(np.ptp(e.points[:, 0]) - 3.0) < 1e-9 and np.ptp(e.points[:, 1]) < 1e-9]
    assert len(tongue) == 2 and 2.5 * 0.01 < max(e.segment_lengths.max() for e in tongue) <= 4 * 0.01 * LONGEST
    result = mesh_shape(face, ald=1e-2, workers=1)
    assert result.ok, result.problems()
    assert result.report.min_angle > 20.0 and result.report.below_20 == 0.0
    _unstaggered(monkeypatch)
    alike = mesh_shape(face, ald=1e-2, workers=1)
    assert alike.report.min_angle < 15.0 and alike.report.below_20 > 0.3
