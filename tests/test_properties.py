"""Property tests (hypothesis) for both refinement modes on random smooth and rough curves."""

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import cadedge
from cadedge.yardsticks.reference import reference_length

SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@st.composite
def fourier_curves(draw):
    """Random closed or open trigonometric curves in 2-D or 3-D, some with tiny or huge coefficients."""
    dim = draw(st.sampled_from([2, 3]))
    terms = draw(st.integers(1, 6))
    coef = np.array(draw(st.lists(st.floats(-3, 3, allow_nan=False), min_size=2 * dim * terms,
                                  max_size=2 * dim * terms))).reshape(dim, terms, 2)
    freq = np.arange(1, terms + 1)
    scale = draw(st.sampled_from([1e-3, 1.0, 1e3]))

    def curve(t):
        t = np.atleast_1d(t)
        ang = np.outer(t, freq) * 2 * np.pi
        return scale * np.stack([(np.cos(ang) * coef[d, :, 0] + np.sin(ang) * coef[d, :, 1]).sum(axis=1)
                                 for d in range(dim)], axis=1)
    return curve


MODES = st.sampled_from([dict(ald=1e-2), dict(ald=1e-3), dict(local_delta=0.01), dict(local_delta=0.001),
                         dict(global_delta=1e-3), dict(local_delta=0.01, order="depth")])


def _check(curve, g, kwargs):
    assert np.all(np.diff(g.params) > 0)
    assert g.params[0] == 0.0 and g.params[-1] == 1.0
    assert np.array_equal(g.points, np.column_stack([curve(g.params), np.zeros(len(g.params))])[:, :3]
                          if curve(g.params).shape[1] == 2 else curve(g.params))
    ref = reference_length(curve, (0.0, 1.0), n=2 ** 16)
    assert g.length <= ref * (1 + 1e-9) + 1e-12
    if "ald" in kwargs and ref > 0:
        assert 1 - g.length / ref <= kwargs["ald"] * 1.001 or g.warnings
    assert g.evaluations < 400_000


@SETTINGS
@given(curve=fourier_curves(), kwargs=MODES)
def test_grid_invariants(curve, kwargs):
    g = cadedge.refine_curve(curve, (0.0, 1.0), **kwargs)
    _check(curve, g, kwargs)


@SETTINGS
@given(curve=fourier_curves(), kwargs=MODES)
def test_deterministic(curve, kwargs):
    a = cadedge.refine_curve(curve, (0.0, 1.0), **kwargs)
    b = cadedge.refine_curve(curve, (0.0, 1.0), **kwargs)
    assert np.array_equal(a.params, b.params) and a.evaluations == b.evaluations


@st.composite
def rough_curves(draw):
    """Pathological black boxes: piecewise constant jumps, noise, spikes, constant points."""
    kind = draw(st.sampled_from(["steps", "noise", "spike", "constant", "zigzag"]))
    seed = draw(st.integers(0, 2 ** 16))
    rng = np.random.default_rng(seed)
    if kind == "steps":
        levels = rng.normal(size=(17, 2))
        return lambda t: levels[np.minimum((np.atleast_1d(t) * 16).astype(int), 16)]
    if kind == "noise":
        table = rng.normal(size=(1025, 3))
        return lambda t: table[np.minimum((np.atleast_1d(t) * 1024).astype(int), 1024)]
    if kind == "spike":
        at = rng.uniform(0.1, 0.9)
        return lambda t: np.column_stack([t, 1.0 / (1e-6 + np.abs(np.atleast_1d(t) - at))])
    if kind == "zigzag":
        return lambda t: np.column_stack([t, np.abs(((np.atleast_1d(t) * 200) % 2) - 1)])
    return lambda t: np.tile([3.0, -1.0, 2.0], (len(np.atleast_1d(t)), 1))


@settings(max_examples=15, deadline=None)
@given(curve=rough_curves(), kwargs=MODES)
def test_bounded_work_on_pathological_curves(curve, kwargs):
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        g = cadedge.refine_curve(curve, (0.0, 1.0), **kwargs)
    assert np.all(np.diff(g.params) > 0)
    assert g.params[0] == 0.0 and g.params[-1] == 1.0
    assert g.evaluations <= 1_000_000
    assert np.isfinite(g.length)
