"""Target mode: the achieved deficit against a high-accuracy reference, counts near the optimum, robustness."""

import math
import warnings

import numpy as np
import pytest

import cadedge
from cadedge.yardsticks import analytic
from cadedge.yardsticks.reference import reference_length

CURVES = {c.name: c for c in analytic.paper_curves() + analytic.family()}
REFERENCE = {}


def true_length(c):
    if c.length is not None:
        return c.length
    if c.name not in REFERENCE:
        REFERENCE[c.name] = reference_length(c)
    return REFERENCE[c.name]


@pytest.mark.parametrize("eps", [1e-2, 1e-3, 1e-4])
@pytest.mark.parametrize("name", sorted(CURVES))
def test_achieved_deficit_meets_target(name, eps):
    c = CURVES[name]
    g = cadedge.refine_curve(c, c.domain, ald=eps)
    achieved = 1.0 - g.length / true_length(c)
    assert 0.0 <= achieved <= eps
    assert g.ald_estimate == pytest.approx(achieved, rel=0.05, abs=eps * 0.02)
    assert g.params[0] == 0.0 and g.params[-1] == 1.0
    assert np.all(np.diff(g.params) > 0)


@pytest.mark.parametrize("eps", [1e-2, 1e-3, 1e-4])
def test_circle_count_close_to_equal_chord_optimum(eps):
    optimum = next(n for n in range(3, 10_000) if 1 - math.sin(math.pi / n) / (math.pi / n) <= eps)
    g = cadedge.refine_curve(analytic.circle(), ald=eps)
    assert optimum <= g.segments <= math.ceil(1.05 * optimum) + 1


def test_cusps_get_nodes():
    """The astroid's four cusps (t = 0, 1/4, 1/2, 3/4) are grid nodes, so a coarse target needs few segments."""
    g = cadedge.refine_curve(analytic.astroid(), ald=1e-2)
    for cusp in (0.25, 0.5, 0.75):
        assert np.min(np.abs(g.params - cusp)) < 1e-6
    assert g.segments <= 16


def test_oscillation_missed_by_a_chord_is_found():
    """A two-point chord sees a straight line; the grid must follow 20 periods."""
    c = analytic.oscillatory(periods=20, amplitude=0.05)
    g = cadedge.refine_curve(c, ald=1e-3)
    assert 1 - g.length / true_length(c) <= 1e-3
    assert g.segments >= 4 * 20


def test_narrow_bump_on_straight_run_is_found():
    c = analytic.narrow_bump()
    g = cadedge.refine_curve(c, ald=1e-4)
    assert 1 - g.length / true_length(c) <= 1e-4
    near = np.abs(g.params - 0.37) < 0.02
    assert near.sum() >= 3


def test_uneven_parametrisation():
    c = analytic.uneven(power=12.0)  # speed varies by e**12, about 160,000
    g = cadedge.refine_curve(c, ald=1e-3)
    assert 1 - g.length / true_length(c) <= 1e-3
    assert g.segments < 60


def test_closed_curve_with_zero_first_chord():
    g = cadedge.refine_curve(lambda t: (np.cos(t), np.sin(t)), (0.0, 2 * np.pi), ald=1e-3)
    assert 1 - g.length / (2 * np.pi) <= 1e-3
    assert np.allclose(g.points[0], g.points[-1])


def test_degenerate_curve_warns_and_stops():
    with pytest.warns(cadedge.CadedgeWarning, match="zero length"):
        g = cadedge.refine_curve(analytic.point(), ald=1e-3)
    assert g.segments == 1 and g.evaluations < 1000
    assert g.warnings


def test_three_d_helix_and_two_d_padding():
    g = cadedge.refine_curve(analytic.helix(), ald=1e-3)
    assert g.points.shape[1] == 3 and np.ptp(g.points[:, 2]) > 1
    g2 = cadedge.refine_curve(analytic.circle(), ald=1e-3)
    assert np.all(g2.points[:, 2] == 0.0)


def test_max_length_respected():
    g = cadedge.refine_curve(analytic.circle(), ald=1e-2, max_length=0.1)
    assert g.segment_lengths.max() <= 0.1 + 1e-12
    assert 1 - g.length / (2 * np.pi) <= 1e-2


def test_min_length_wins_over_target_with_a_warning():
    with pytest.warns(cadedge.CadedgeWarning, match="not reached"):
        g = cadedge.refine_curve(analytic.circle(), ald=1e-5, min_length=0.5)
    assert g.segment_lengths.min() >= 0.5 - 1e-12


@pytest.mark.parametrize("growth", [1.5, 2.0])
@pytest.mark.parametrize("name", ["narrow_bump", "tricuspid", "lissajous", "astroid", "uneven"])
def test_max_growth_bounds_adjacent_ratio_and_keeps_target(name, growth):
    c = CURVES[name]
    g = cadedge.refine_curve(c, ald=1e-3, max_growth=growth)
    s = g.segment_lengths
    assert np.max(np.maximum(s[1:] / s[:-1], s[:-1] / s[1:])) <= growth * (1 + 1e-9)
    assert 1 - g.length / true_length(c) <= 1e-3


def test_max_growth_too_tight_warns_instead_of_looping():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        g = cadedge.refine_curve(CURVES["lissajous"], ald=1e-3, max_growth=1.05)
    s = g.segment_lengths
    worst = np.max(np.maximum(s[1:] / s[:-1], s[:-1] / s[1:]))
    assert worst <= 1.05 or any("max_growth" in str(w.message) for w in caught)
    assert g.segments < 20_000


def test_a_closed_curve_keeps_a_polygon_whatever_the_options(fixtures_dir):
    """One segment on a closed curve has no length and two retrace each other: neither bounds a face.
    A closed curve keeps at least 3 segments, whether min_length or a coarse target would leave fewer
    (with min_length, a note says so), in the per-edge and the compiled path alike."""
    circle = lambda u: np.c_[np.cos(u), np.sin(u), np.zeros_like(u)]  # noqa: E731
    grid = cadedge.refine_curve(circle, (0.0, 2 * np.pi), ald=1e-2, min_length=5.0)
    assert len(grid.params) == 4 and np.allclose(np.diff(grid.params), 2 * np.pi / 3, rtol=1e-3)
    assert any("fewer than 3 segments" in w for w in grid.warnings)
    assert len(cadedge.refine_curve(circle, (0.0, 2 * np.pi), ald=0.5).params) == 4
    pytest.importorskip("OCP")
    from cadedge import refine_shape

    for opts in (dict(ald=0.5), dict(ald=1e-2, min_length=20.0)):
        shape = refine_shape(fixtures_dir / "cylinder.step", **opts)
        assert [e.segments for e in shape.edges if e.closed] == [3, 3]
