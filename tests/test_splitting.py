"""cadedge.splitting: points are only added, grids are never edited in place."""

import numpy as np
import pytest

from cadedge.splitting import insert_points, limit_growth, point_at_arc, points_at_distances, split_evenly


def _circle(u):
    u = np.asarray(u, dtype=float)
    return np.c_[np.cos(u), np.sin(u), np.zeros_like(u)]


def test_insert_points_merges_by_parameter_keeps_old_samples_and_copies():
    u, p = np.array([0.0, 1.0, 2.0]), _circle([0.0, 1.0, 2.0])
    u0, p0 = u.copy(), p.copy()
    nu, np_ = insert_points(u, p, np.array([1.5, 1.0, 0.5]), np.full((3, 3), 7.0))
    assert np.array_equal(nu, [0.0, 0.5, 1.0, 1.5, 2.0])
    assert np.array_equal(np_[2], p[1])  # the repeated parameter keeps the old point
    assert np.array_equal(u, u0) and np.array_equal(p, p0)


def test_split_evenly_cuts_equal_parameter_steps():
    assert np.allclose(split_evenly(np.array([0.0, 1.0, 3.0]), np.array([2, 4])), [0.5, 1.5, 2.0, 2.5])
    assert len(split_evenly(np.array([0.0, 1.0]), np.array([1]))) == 0


def test_point_at_arc_measures_from_either_end():
    u, p, n = point_at_arc(_circle, 0.0, 1.0, _circle([0.0])[0], 0.25, dense=129)
    assert abs(u - 0.25) < 1e-4 and n == 130 and np.allclose(p, _circle([u])[0])
    u, _, _ = point_at_arc(_circle, 0.0, 1.0, _circle([1.0])[0], 0.25, from_start=False, dense=129)
    assert abs(u - 0.75) < 1e-4


def test_points_at_distances_bisects_chord_distance():
    ua, ub = np.array([0.0, 0.0]), np.array([1.0, 1.0])
    ref = _circle([0.0, 1.0])
    u, p = points_at_distances(_circle, ua, ub, ref, np.array([0.3, 0.3]), from_start=np.array([True, False]))
    assert np.allclose(np.linalg.norm(p - ref, axis=1), 0.3, atol=1e-6)
    assert u[0] < 0.5 < u[1]


def test_limit_growth_returns_a_new_graded_grid():
    u = np.array([0.0, 0.01, 3.0])
    p = _circle(u)
    u0, p0 = u.copy(), p.copy()
    nu, np_, notes = limit_growth(_circle, u, p, 1.5)
    seg = np.linalg.norm(np.diff(np_, axis=0), axis=1)
    assert not notes and np.all(np.diff(nu) > 0)
    assert np.max(np.maximum(seg[1:], seg[:-1]) / np.minimum(seg[1:], seg[:-1])) <= 1.5 + 1e-9
    assert np.array_equal(u, u0) and np.array_equal(p, p0)


def test_vertex_grading_keeps_parameters_increasing_on_a_loose_edge(corpus_dir):
    """917_fusee's edge 351 has a vertex off its curve: a split there once landed on the vertex's own
    parameter (two nodes at one parameter). Grading now stops there and says so."""
    pytest.importorskip("OCP")
    from cadedge import refine_shape

    grid = refine_shape(corpus_dir / "live-clones__gmsh__917_fusee.stp", ald=1e-3, max_growth=1.5)
    assert all(np.all(np.diff(e.params) > 0) for e in grid.edges if not e.degenerate)
    assert any(w.startswith("edge 351: max_growth") for w in grid.warnings)


def test_fit_to_sizes_reuses_the_grid_curves_or_builds_them_once(fixtures_dir):
    pytest.importorskip("OCP")
    import dataclasses

    from cadedge import refine_shape
    from cadedge.mesh.proximity import fit_to_sizes

    grid = refine_shape(fixtures_dir / "cylinder.step", ald=1e-2)
    field = lambda g: (lambda xyz: np.full(len(xyz), 0.5))  # noqa: E731
    kept = fit_to_sizes(grid, field)
    built = fit_to_sizes(dataclasses.replace(grid, curves=None), field)
    assert sum(e.segments for e in kept.edges) > grid.segments
    for a, b, e in zip(kept.edges, built.edges, grid.edges):
        assert np.array_equal(a.params, b.params) and np.array_equal(a.points, b.points)
        assert np.all(np.diff(a.params) > 0) and len(e.params) <= len(a.params)
