"""Curve adapters: vectorisation detection, exact evaluation counts, errors that name the parameter."""

import math

import numpy as np
import pytest

import cadedge
from cadedge.curves import Evaluator, FunctionCurve, SampledCurve, as_curve


def _circle_rows(t):
    return np.column_stack([np.cos(t), np.sin(t)])


@pytest.mark.parametrize("fn, layout", [
    (_circle_rows, "rows"),
    (lambda t: (np.cos(t), np.sin(t)), "cols"),
    (lambda t: np.array([np.cos(t), np.sin(t), t]), "cols"),
    (lambda t: (math.cos(t), math.sin(t)), "scalar"),
    (lambda t: [t, 0.0], "scalar"),
    (lambda t: (t, t * t) if t < 0.5 else (t, 0.25), "scalar"),
])
def test_layout_detected_and_values_right(fn, layout):
    ev = Evaluator(as_curve(fn, (0.0, 1.0)))
    u = np.array([0.1, 0.2, 0.3, 0.45])
    pts = ev(u)
    assert ev.curve.layout == layout
    assert pts.shape == (4, 3)
    scalar = [np.asarray(fn(float(x)), dtype=float).ravel() for x in u]
    assert np.allclose(pts[:, :len(scalar[0])], scalar)


def test_square_batch_is_disambiguated_by_one_scalar_call():
    calls = []

    def fn(t):
        calls.append(np.size(t))
        return np.column_stack([np.cos(t), np.sin(t)]) if np.ndim(t) else (math.cos(t), math.sin(t))

    ev = Evaluator(FunctionCurve(fn, (0, 1)))
    pts = ev(np.array([0.0, 1.0]))
    assert ev.curve.layout == "rows"
    assert np.allclose(pts[1, :2], [math.cos(1.0), math.sin(1.0)])
    assert ev.evaluations == sum(calls) == 3  # the batch of two plus one scalar probe


def test_evaluations_count_every_point_asked():
    seen = []

    def fn(t):
        seen.append(np.size(t))
        return np.column_stack([t, t ** 2])

    g = cadedge.refine_curve(fn, (0.0, 1.0), ald=1e-4)
    assert g.evaluations == sum(seen)


def test_nan_names_the_parameter():
    def fn(t):
        return np.column_stack([t, np.where(np.abs(t - 0.5) < 0.01, np.nan, t)])

    with pytest.raises(cadedge.CurveEvaluationError, match=r"non-finite point at u=0\.5"):
        cadedge.refine_curve(fn, (0.0, 1.0))


def test_raising_black_box_names_the_parameter():
    def fn(t):
        if t > 0.7:
            raise ValueError("off the edge")
        return (t, 0.0)

    with pytest.raises(cadedge.CurveEvaluationError, match=r"ValueError: off the edge at u=0\.7"):
        cadedge.refine_curve(fn, (0.0, 1.0))


def test_wrong_shape_is_an_evaluation_error():
    with pytest.raises(cadedge.CurveEvaluationError, match="expected 2 or 3 coordinates"):
        cadedge.refine_curve(lambda t: (t, t, t, t), (0.0, 1.0))


def test_sampled_curve_interpolates_and_refines_onto_its_corners():
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], dtype=float)
    c = SampledCurve(square)
    assert c.domain == (0.0, 1.0)
    assert np.allclose(c.evaluate(np.array([0.125])), [[0.5, 0.0]])
    g = cadedge.refine_curve(c, ald=1e-6)
    assert g.length == pytest.approx(4.0, rel=1e-6)
    assert g.segments == 4


def test_sampled_curve_rejects_bad_input():
    with pytest.raises(cadedge.InputError):
        SampledCurve([[0, 0]])
    with pytest.raises(cadedge.InputError):
        SampledCurve([[0, 0], [1, 1]], params=[1, 0])


@pytest.mark.parametrize("kwargs, message", [
    (dict(ald=0), "ald must be positive"),
    (dict(ald=1.5), "below 1"),
    (dict(ald="x"), "must be a number"),
    (dict(order="sideways", local_delta=0.1), "order must be one of"),
    (dict(ald=1e-3, local_delta=0.1), "not both"),
    (dict(min_length=2.0, max_length=1.0), "exceeds"),
    (dict(max_growth=1.0), "greater than 1"),
])
def test_bad_arguments_are_input_errors(kwargs, message):
    with pytest.raises(cadedge.InputError, match=message):
        cadedge.refine_curve(_circle_rows, (0.0, 1.0), **kwargs)


@pytest.mark.parametrize("domain", [None, (1.0, 1.0), (0.0, float("inf")), (2.0, 1.0), "ab"])
def test_bad_domain_is_an_input_error(domain):
    with pytest.raises(cadedge.InputError, match="domain"):
        cadedge.refine_curve(_circle_rows, domain)


def test_a_curve_object_reused_counts_each_refinement_on_its_own():
    """A FunctionCurve counts its calls over its life; each refinement reports only its own."""
    curve = FunctionCurve(lambda u: np.c_[np.cos(u), np.sin(u), np.zeros_like(u)], (0.0, 3.0))
    first = cadedge.refine_curve(curve, ald=1e-3).evaluations
    assert first > 0 and cadedge.refine_curve(curve, ald=1e-3).evaluations == first
