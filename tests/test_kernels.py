"""The compiled kernels (cadedge/_kernels.c, _angles.c, _idw.c) against the numpy/scipy definitions they replace
(exact or to rounding)."""

import numpy as np
import pytest

from cadedge.kernels import de_boor, interp_sorted
from cadedge.placement import deficit_measure, equidistribute, fewest_nodes


@pytest.mark.parametrize("seed", range(20))
def test_interp_sorted_is_numpy_interp(seed):
    rng = np.random.default_rng(seed)
    xp = np.sort(rng.uniform(0, 1, 30))
    xp[5:9] = xp[5]  # flat stretches, as a deficit measure has on straight runs
    fp = np.cumsum(rng.uniform(0, 1, 30))
    x = np.sort(np.concatenate([rng.uniform(-0.2, 1.2, 50), xp[[0, 5, -1]]]))
    assert np.array_equal(interp_sorted(x, xp, fp), np.interp(x, xp, fp))


def _arc(n, turn=3.0):
    t = np.linspace(0, turn, n)
    p = np.c_[np.cos(t), np.sin(t), np.zeros(n)]
    return p, np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]


def test_fewest_nodes_meets_the_budget_keeps_forced_nodes_and_is_minimal():
    p, cum = _arc(400)
    budget = 1e-3 * cum[-1]
    nodes = fewest_nodes(p, cum, budget, forced=np.array([123]))
    length = np.linalg.norm(np.diff(p[nodes], axis=0), axis=1).sum()
    assert nodes[0] == 0 and nodes[-1] == 399 and 123 in nodes and np.all(np.diff(nodes) > 0)
    assert cum[-1] - length <= budget
    free = fewest_nodes(p, cum, budget)  # without the forced node it cannot need more
    assert len(free) <= len(nodes)
    # one node fewer is impossible: even evenly spread samples miss the budget
    k = len(free) - 1
    even = np.round(np.linspace(0, 399, k)).astype(int)
    assert cum[-1] - np.linalg.norm(np.diff(p[even], axis=0), axis=1).sum() > budget


def test_without_dropping_the_grid_meets_the_budget_with_no_fewer_nodes():
    """``drop=False`` (target mode, where the equidistributed placement competes) skips the search for a grid
    one node shorter: the same budget met, never fewer nodes than with it (here one more once)."""
    rng = np.random.default_rng(3)
    dropped = 0
    for n, turn in ((400, 3.0), (150, 5.0), (900, 1.0)):
        p, cum = _arc(n, turn)
        p[1:-1] += rng.normal(scale=1e-4, size=(n - 2, 3))  # an uneven curve: the drop can find room
        cum = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
        for share in (1e-2, 1e-3, 1e-4):
            budget = share * cum[-1]
            fast, full = (fewest_nodes(p, cum, budget, drop=d) for d in (False, True))
            for nodes in (fast, full):
                assert cum[-1] - np.linalg.norm(np.diff(p[nodes], axis=0), axis=1).sum() <= budget
            assert len(full) <= len(fast)
            dropped += len(fast) - len(full)
    assert dropped == 1


def test_equidistribution_of_a_circle_is_uniform():
    p, cum = _arc(2001, turn=2.0)
    u = np.linspace(0.0, 2.0, 2001)
    params = equidistribute(u, cum, deficit_measure(p, cum), 10)
    assert len(params) == 11 and params[0] == 0.0 and params[-1] == 2.0
    assert np.allclose(np.diff(params), 0.2, rtol=1e-6)


def test_de_boor_matches_scipy():
    scipy_interpolate = pytest.importorskip("scipy.interpolate")
    rng = np.random.default_rng(1)
    for degree in (1, 2, 3, 5):
        n = degree + 6
        inner = np.sort(rng.uniform(0, 1, n - degree - 1))
        knots = np.r_[[0.0] * (degree + 1), inner, [1.0] * (degree + 1)]
        coef = rng.normal(size=(n, 4))
        u = np.r_[0.0, np.sort(rng.uniform(0, 1, 40)), inner[2], 1.0]
        ref = scipy_interpolate.BSpline(knots, coef, degree, extrapolate=True)(u)
        assert np.allclose(de_boor(knots, coef, degree, u), ref, rtol=0, atol=1e-13)


@pytest.mark.parametrize("seed", range(5))
def test_min_angles_is_the_smallest_of_numpys_triangle_angles(seed):
    """The face optimiser's compiled smallest angle (one atan2, at the corner opposite the shortest edge)
    against numpy's three angles, on random, near-equilateral and degenerate triangles."""
    from cadedge.kernels import min_angles
    from cadedge.mesh.quality import triangle_angles

    rng = np.random.default_rng(seed)
    x = np.vstack([rng.uniform(-1, 1, (60, 3)), [[0, 0, 0], [1, 0, 0], [0.5, 3**0.5 / 2 + 1e-12, 0], [2, 0, 0]]])
    tri = np.vstack([rng.integers(0, 60, (200, 3)), [[60, 61, 62], [60, 61, 63], [60, 60, 61]]])
    got = min_angles(x, tri)
    assert np.allclose(got, triangle_angles(x, tri).min(axis=1), rtol=0, atol=1e-12)
    assert got[-3] == pytest.approx(60.0) and got[-2] == 0.0 and got[-1] == 0.0  # equilateral, flat, two nodes
    with pytest.raises(IndexError):
        min_angles(x, [[0, 1, len(x)]])


def test_climb_trials_keep_each_nodes_best_trial_position():
    """The local search's trials in one call: each node with incidences tried at ``x + step h (cos u +
    sin v)`` for every step and direction, its smallest angle there with every other node in place; the
    best over the trials kept where it beats the node's start by more than 1e-9 (the first of equals),
    the start kept elsewhere. As numpy computes each trial, to the last bit."""
    from cadedge.kernels import climb_trials
    from cadedge.mesh.moves import STEPS
    from cadedge.mesh.quality import triangle_angles

    rng = np.random.default_rng(7)
    x = rng.uniform(-1, 1, (40, 3))
    tri = np.array([rng.choice(40, 3, replace=False) for _ in range(90)])
    u, v = rng.normal(0, 1, x.shape), rng.normal(0, 1, x.shape)
    h = rng.uniform(0.05, 0.2, len(x))
    node, slot, t = tri.ravel(), np.tile(np.arange(3), len(tri)), np.repeat(np.arange(len(tri)), 3)
    keep = node % 3 != 0  # only some nodes try a move
    node, slot, t = node[keep], slot[keep], t[keep]
    keep_nodes = np.unique(node)
    phi = np.arange(8) * np.pi / 4
    cosines, sines = np.array([np.cos(a) for a in phi]), np.array([np.sin(a) for a in phi])
    start = np.full(len(x), np.inf)  # each node's worst angle where it is
    for nd, tt in zip(node, t):
        start[nd] = min(start[nd], triangle_angles(x[tri[tt]], [[0, 1, 2]]).min())
    start[np.isinf(start)] = 30.0
    start[keep_nodes[::2]] = 90.0  # no trial beats these
    want, want_pos = start.copy(), x.copy()
    for step in STEPS:
        for c, s in zip(cosines, sines):
            pos = x + step * h[:, None] * (c * u + s * v)
            q = np.full(len(x), np.inf)
            for nd, sl, tt in zip(node, slot, t):
                p = x[tri[tt]].copy()
                p[sl] = pos[nd]
                q[nd] = min(q[nd], triangle_angles(p, [[0, 1, 2]]).min())
            better = np.isfinite(q) & (q > want + 1e-9)
            want[better], want_pos[better] = q[better], pos[better]
    best, best_pos = start.copy(), x.copy()
    climb_trials(x, tri, node, slot, t, u, v, h, np.asarray(STEPS), cosines, sines, best, best_pos)
    assert (want[::3] == 30.0).all() and (want > start).sum() > 10 and (want[keep_nodes[::2]] == 90.0).all()
    assert np.allclose(best, want, rtol=0, atol=1e-12) and np.array_equal(best_pos, want_pos)
    with pytest.raises(IndexError):
        climb_trials(x, tri, node, slot + 1, t, u, v, h, np.asarray(STEPS), cosines, sines, best, best_pos)
    with pytest.raises(ValueError):
        climb_trials(x, tri, node, slot, t, u, v, h, np.asarray(STEPS), cosines, sines, best, best_pos.T)


def test_tri_normals_is_numpys_cross_product_of_two_edges():
    """The optimiser's compiled triangle normals: ``(b - a) x (c - a)`` as numpy computes it, twice the
    triangle's area long, zero for a degenerate one; an index past the nodes is refused."""
    from cadedge.kernels import tri_normals

    rng = np.random.default_rng(3)
    x = np.vstack([rng.uniform(-1, 1, (50, 3)), [[0, 0, 0], [2, 0, 0], [0, 3, 0]]])
    tri = np.vstack([rng.integers(0, 50, (120, 3)), [[50, 51, 52], [50, 51, 51]]])
    p = x[tri]
    assert np.array_equal(tri_normals(x, tri), np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]))
    assert tri_normals(x, tri)[-2].tolist() == [0.0, 0.0, 6.0] and not tri_normals(x, tri)[-1].any()
    assert tri_normals(x, np.zeros((0, 3), dtype=np.int64)).shape == (0, 3)
    with pytest.raises(IndexError):
        tri_normals(x, [[0, 1, len(x)]])


def test_idw_size_is_the_inverse_distance_mean_of_the_nearest_samples():
    """gmsh's size callback's compiled lookup against scipy's k-d tree and the weighted mean, to the
    bit (the nearest summed first); at a sample the sample's own size; bad shapes refused."""
    from scipy.spatial import cKDTree

    from cadedge.kernels import idw_size

    rng = np.random.default_rng(11)
    pts, sizes = rng.random((300, 3)), rng.random(300)
    tree = cKDTree(pts)
    for q in rng.uniform(-0.2, 1.2, (200, 3)):
        d, i = tree.query(q, k=4)
        num = den = 0.0
        for dj, ij in zip(d.tolist(), i.tolist()):  # in order, as the kernel sums (np.dot's order is BLAS's)
            w = 1.0 / (dj + 1e-12)
            num, den = num + w * float(sizes[ij]), den + w
        assert idw_size(pts, sizes, *q, 4) == num / den
    assert idw_size(pts, sizes, *pts[7], 4) == pytest.approx(sizes[7], rel=1e-9)
    with pytest.raises(ValueError):
        idw_size(pts, sizes[:-1], 0.0, 0.0, 0.0, 4)
    with pytest.raises(ValueError):
        idw_size(pts[:3], sizes[:3], 0.0, 0.0, 0.0, 4)
