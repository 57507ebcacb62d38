"""The sampled DP optimum: exactness against brute force and a plain DP, consistency, curve sampling."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from cadedge.yardsticks import analytic
from cadedge.errors import InputError
from cadedge.yardsticks.optimum import dense_samples, max_length_polyline, min_segments, sampled_optimum
from cadedge.yardsticks.reference import polyline_length, reference_length


def brute_force(points: np.ndarray, k: int) -> float:
    """Longest polyline with exactly min(k, n - 1) segments over every choice of interior vertices."""
    n = len(points)
    best = -1.0
    for inner in itertools.combinations(range(1, n - 1), min(k, n - 1) - 1):
        best = max(best, polyline_length(points[[0, *inner, n - 1]]))
    return best


def plain_dp(points: np.ndarray, k_max: int) -> np.ndarray:
    """Unpruned O(k n^2) DP: row k-1 is the longest polyline to the last sample with at most k segments."""
    d = np.linalg.norm(points[:, None, :] - points[None, :, :], axis=2)
    n = len(points)
    m = np.full(n, -np.inf)
    m[0] = 0.0
    out = []
    for _ in range(k_max):
        cand = m[:, None] + np.where(np.tri(n, k=-1, dtype=bool).T, d, -np.inf)
        m = np.maximum(m, cand.max(axis=0))
        out.append(m[-1])
    return np.array(out)


def random_sets(seed: int, count: int, low: int, high: int):
    rng = np.random.default_rng(seed)
    for t in range(count):
        n = int(rng.integers(low, high))
        dim = 2 + t % 2
        if t % 3 == 0:
            yield rng.random((n, dim))  # scattered: far from any curve
        elif t % 3 == 1:
            yield np.cumsum(rng.normal(size=(n, dim)), axis=0)  # random walk
        else:
            s = np.sort(rng.random(n))
            yield np.column_stack([np.cos(7 * s), np.sin(3 * s), s][:dim])  # curve, uneven spacing


def test_max_length_matches_brute_force():
    for pts in random_sets(0, 40, 3, 10):
        for k in range(1, len(pts)):
            length, idx = max_length_polyline(pts, k)
            assert length == pytest.approx(brute_force(pts, k), rel=1e-12, abs=1e-12)
            assert idx[0] == 0 and idx[-1] == len(pts) - 1 and np.all(np.diff(idx) > 0)
            assert len(idx) - 1 <= k
            assert polyline_length(pts[idx]) == pytest.approx(length, rel=1e-12)


def test_max_length_matches_plain_dp_on_larger_sets():
    for pts in random_sets(1, 9, 60, 160):
        reference = plain_dp(pts, 25)
        for k in (1, 2, 3, 5, 8, 13, 25):
            length, idx = max_length_polyline(pts, k)
            assert length == pytest.approx(reference[k - 1], rel=1e-12)
            assert polyline_length(pts[idx]) == pytest.approx(length, rel=1e-12)


def test_more_segments_never_shorter():
    for pts in random_sets(2, 6, 20, 50):
        lengths = [max_length_polyline(pts, k)[0] for k in range(1, len(pts))]
        assert np.all(np.diff(lengths) >= -1e-12 * lengths[-1])
        assert lengths[-1] == pytest.approx(polyline_length(pts), rel=1e-12)


def test_min_segments_consistent_with_max_length():
    for pts in random_sets(3, 9, 20, 120):
        total = polyline_length(pts)
        for share in (0.6, 0.9, 0.99, 0.999):
            target = max(share * total, np.linalg.norm(pts[-1] - pts[0]) * 1.0001)
            if target > total:
                continue
            count, idx = min_segments(pts, target)
            assert len(idx) - 1 == count
            assert polyline_length(pts[idx]) >= target * (1 - 1e-12)
            assert max_length_polyline(pts, count)[0] >= target * (1 - 1e-12)
            if count > 1:
                assert max_length_polyline(pts, count - 1)[0] < target


def test_min_segments_edge_cases():
    line = np.column_stack([np.linspace(0, 1, 50), np.zeros(50)])
    assert min_segments(line, 1.0)[0] == 1
    with pytest.raises(InputError, match="exceeds the sampled polyline length"):
        min_segments(line, 1.01)
    with pytest.raises(InputError):
        max_length_polyline(line, 0)
    with pytest.raises(InputError):
        min_segments(np.zeros((1, 2)), 0.0)


def circle_count(eps: float) -> int:
    """Fewest equal chords of a circle with deficit 1 - sin(pi/N)/(pi/N) at most eps."""
    n = 1
    while 1 - math.sin(math.pi / n) / (math.pi / n) > eps:
        n += 1
    return n


@pytest.mark.parametrize("eps", [1e-2, 1e-3, 1e-4])
def test_circle_optimum_close_to_analytic(eps):
    c = analytic.circle()
    exact = circle_count(eps)
    count = sampled_optimum(c, c.domain, (1 - eps) * c.length)
    assert exact <= count <= exact + 1


def test_circle_max_length_close_to_equal_chords():
    _, pts = dense_samples(analytic.circle(), None, 2000)
    for k in (7, 40):
        equal = 2 * k * math.sin(math.pi / k)
        length, _ = max_length_polyline(pts, k)
        assert equal * (1 - 1e-5) <= length <= equal * (1 + 1e-12)


@pytest.mark.parametrize("curve", [analytic.uneven(), analytic.tricuspid(), analytic.narrow_bump(),
                                   analytic.spiral()], ids=lambda c: c.name)
def test_dense_samples_resolve_length_and_spacing(curve):
    u, pts = dense_samples(curve, None, 2000)
    true = curve.length if curve.length is not None else reference_length(curve, curve.domain)
    assert 1900 <= len(u) <= 2100
    assert u[0] == 0.0 and u[-1] == 1.0 and np.all(np.diff(u) > 0)
    assert 1 - polyline_length(pts) / true < 2e-5
    gaps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert gaps.max() < 5 * true / len(u)  # a quarter of the samples go by arc length, whatever the speed


def test_dense_samples_land_on_cusps():
    _, pts = dense_samples(analytic.tricuspid(), None, 1000)
    for t in (0.0, 2 * np.pi / 3, 4 * np.pi / 3):
        cusp = np.array([3 * np.cos(t), 3 * np.sin(t), 0.0])
        assert np.linalg.norm(pts - cusp, axis=1).min() < 1e-9


def test_include_makes_the_optimum_no_worse_than_a_grid():
    c = analytic.circle()
    params = np.linspace(0.0, 1.0, 15)  # 14 equal chords: the continuous optimum
    grid_length = polyline_length(c.evaluate(params))
    assert sampled_optimum(c, c.domain, grid_length, n=1000, include=params) == 14


def test_optimum_ignores_the_parametrisation():
    """The same half ellipse traced at speeds varying by e**10 (2e4) or barely: the same optimum."""
    true = reference_length(analytic.uneven(1.0), (0.0, 1.0))
    for eps in (1e-3, 1e-4):
        counts = {sampled_optimum(analytic.uneven(p), None, (1 - eps) * true) for p in (1.0, 10.0)}
        assert len(counts) == 1
