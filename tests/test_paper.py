"""Paper mode (Algorithms 1 and 2) and the reproduction of the paper's Tables 1 and 2."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from cadedge import CadedgeWarning, FunctionCurve, refine_curve
from cadedge.yardsticks.analytic import circle, lissajous, paper_curves, point
from cadedge.curves import Evaluator
from cadedge.paper import MAX_SEGMENTS, refine_paper
from cadedge.search import DEFAULT_SEARCH_TOL, best_split, golden_search, search_evaluations

# The paper's Tables 1 and 2: (local delta, printed count = vertices, polyline length, evaluations).
TABLE = {
    "lissajous": [(0.1, 8, 12.7123, 1599), (0.01, 21, 12.884, 4797), (0.001, 121, 13.04, 29397)],
    "tricuspid": [(0.1, 4, 15.5885, 615), (0.01, 7, 15.87, 1353), (0.001, 25, 15.99, 5781)],
    "cochleoid": [(0.1, 11, 2.7916, 2337), (0.01, 27, 2.916, 6273), (0.001, 86, 2.939, 20787)],
}
CELLS = [(c, *row) for c in TABLE for row in TABLE[c]]
CURVES = {c.name: c for c in paper_curves()}


@pytest.mark.parametrize("name,delta,count,length,evals", CELLS)
def test_table_cell(name, delta, count, length, evals):
    g = refine_curve(CURVES[name], (0.0, 1.0), local_delta=delta)
    assert abs(g.segments - (count - 1)) <= 1
    assert abs(g.length / length - 1.0) <= 0.005
    assert 3 * g.evaluations <= evals


def test_search_costs_one_evaluation_per_iteration():
    # Every popped segment is searched once: 2 end points + (2 * segments - 1) searches.
    g = refine_curve(lissajous(), (0.0, 1.0), local_delta=0.01)
    assert g.evaluations == 2 + search_evaluations(DEFAULT_SEARCH_TOL) * (2 * g.segments - 1)


def test_golden_search_finds_the_arc_midpoint():
    ev = Evaluator(circle())
    pa, pb = ev(np.array([0.0, 0.25]))
    u, p, two = best_split(ev, 0.0, 0.25, pa, pb, tol=1e-6)
    assert abs(u - 0.125) < 1e-6
    assert np.array_equal(p, ev(np.array([u]))[0])
    assert abs(two - 2 * np.sqrt(2 - np.sqrt(2))) < 1e-9  # two chords of a 45-degree arc
    assert ev.evaluations == 2 + search_evaluations(1e-6) + 1


def test_golden_search_batch_equals_single():
    ev = Evaluator(lissajous())
    ua, ub = np.array([0.0, 0.2, 0.5]), np.array([0.2, 0.5, 0.9])
    pa, pb = ev(ua), ev(ub)
    before = ev.evaluations
    us, ps, twos = golden_search(ev, ua, ub, pa, pb)
    assert ev.evaluations - before == 3 * search_evaluations(DEFAULT_SEARCH_TOL)
    for k in range(3):
        u, p, two = best_split(ev, ua[k], ub[k], pa[k], pb[k])
        assert (u, two) == (us[k], twos[k]) and np.array_equal(p, ps[k])
        assert ua[k] < u < ub[k]


@pytest.mark.parametrize("curve", [lissajous(), circle()], ids=lambda c: c.name)
def test_breadth_and_depth_terminate_and_agree_without_global(curve):
    b = refine_curve(curve, (0.0, 1.0), local_delta=0.001, order="breadth")
    d = refine_curve(curve, (0.0, 1.0), local_delta=0.001, order="depth")
    # Without the global criterion each decision depends only on its segment, so order is irrelevant.
    assert np.array_equal(b.params, d.params) and b.evaluations == d.evaluations


def test_order_matters_with_global_delta():
    kw = dict(local_delta=0.05, global_delta=2e-4)
    b = refine_curve(lissajous(), (0.0, 1.0), order="breadth", **kw)
    d = refine_curve(lissajous(), (0.0, 1.0), order="depth", **kw)
    for g in (b, d):
        assert g.segments > 1 and np.all(np.diff(g.params) > 0)
    assert b.segments != d.segments or not np.array_equal(b.params, d.params)


def test_global_delta_refines_more():
    local = refine_curve(lissajous(), (0.0, 1.0), local_delta=0.05)
    both = refine_curve(lissajous(), (0.0, 1.0), local_delta=0.05, global_delta=1e-4)
    only = refine_curve(lissajous(), (0.0, 1.0), global_delta=1e-4)
    assert both.segments > local.segments and both.length > local.length
    assert only.segments > 1
    # Each kept segment's best split gains at most global_delta of the polyline length, so the
    # estimate (4/3 of the summed gains) is bounded by the criterion.
    assert only.ald_estimate <= 4 / 3 * 1e-4 * only.segments


def test_min_length_respected():
    free = refine_curve(circle(), (0.0, 1.0), local_delta=1e-4)
    g = refine_curve(circle(), (0.0, 1.0), local_delta=1e-4, min_length=0.3)
    assert g.segments < free.segments
    assert g.segment_lengths.min() >= 0.3


def test_max_length_respected_on_a_straight_line():
    line = lambda u: np.column_stack([u, 2 * u])  # noqa: E731
    alone = refine_curve(line, (0.0, 1.0), local_delta=0.01)
    g = refine_curve(line, (0.0, 1.0), local_delta=0.01, max_length=0.1)
    assert alone.segments == 1
    assert g.segments >= 23 and g.segment_lengths.max() <= 0.1


def test_min_length_wins_over_max_length():
    g = refine_curve(circle(), (0.0, 1.0), local_delta=0.01, min_length=0.5, max_length=0.5)
    assert g.segment_lengths.min() >= 0.5


def test_closed_circle():
    g = refine_curve(circle(), (0.0, 1.0), local_delta=0.01)
    assert np.allclose(g.points[0], g.points[-1])  # the zero-length first chord was split
    assert g.segments >= 8
    true = 2 * np.pi
    assert 1 - g.length / true < 0.01
    assert abs(g.ald_estimate - (1 - g.length / true)) < 0.05 * (1 - g.length / true)


def test_closed_circle_global_only():
    g = refine_curve(circle(), (0.0, 1.0), global_delta=1e-3)
    assert g.segments >= 4 and np.all(np.isfinite(g.params))


@pytest.mark.parametrize("order", ["breadth", "depth"])
def test_degenerate_point_curve_terminates(order):
    with warnings.catch_warnings():
        warnings.simplefilter("error", CadedgeWarning)
        g = refine_curve(point(), (0.0, 1.0), local_delta=0.01, global_delta=0.01, order=order)
    assert g.segments == 1 and g.length == 0.0 and g.ald_estimate == 0.0


def test_fractal_curve_hits_the_safety_cap_with_a_note():
    def takagi(u):  # the blancmange curve: every piece is as bumpy as the whole
        y = np.zeros_like(u)
        for n in range(40):
            x = 2.0 ** n * u
            y += np.abs(x - np.round(x)) / 2.0 ** n
        return np.column_stack([u, y])
    with pytest.warns(CadedgeWarning, match="safety cap"):
        g = refine_curve(takagi, (0.0, 1.0), local_delta=0.01)
    assert g.segments == MAX_SEGMENTS and np.all(np.diff(g.params) > 0)


def test_deterministic():
    runs = [refine_curve(CURVES["cochleoid"], (0.0, 1.0), local_delta=0.001) for _ in range(2)]
    assert np.array_equal(runs[0].params, runs[1].params)
    assert np.array_equal(runs[0].points, runs[1].points)
    assert runs[0].evaluations == runs[1].evaluations


@pytest.mark.parametrize("name", list(CURVES))
@pytest.mark.parametrize("order", ["breadth", "depth"])
def test_params_increase_and_points_are_the_curve(name, order):
    curve = CURVES[name]
    g = refine_curve(curve, (0.0, 1.0), local_delta=0.01, order=order)
    assert g.params[0] == 0.0 and g.params[-1] == 1.0
    assert np.all(np.diff(g.params) > 0)
    expected = curve.evaluate(g.params)
    assert np.array_equal(g.points[:, :2], expected) and np.all(g.points[:, 2] == 0.0)


def test_refine_paper_directly_on_a_3d_curve():
    helix = FunctionCurve(lambda u: np.column_stack([np.cos(6 * u), np.sin(6 * u), u]), (0.0, 2.0))
    params, points, estimate, notes = refine_paper(Evaluator(helix), 0.0, 2.0, local_delta=0.001)
    assert notes == [] and 0 < estimate < 0.002
    assert np.array_equal(points, helix.evaluate(params))


def test_bad_order_or_tolerance_is_an_input_error():
    from cadedge import InputError
    with pytest.raises(InputError, match="order"):
        refine_paper(Evaluator(circle()), 0.0, 1.0, local_delta=0.1, order="sideways")
    with pytest.raises(InputError, match="search_tol"):
        refine_paper(Evaluator(circle()), 0.0, 1.0, local_delta=0.1, search_tol=1.5)
