"""Edge splits of all-boundary triangles (cadedge/mesh/corners.py), on small planar meshes."""

from __future__ import annotations

import numpy as np

from cadedge.mesh.corners import split_corner_triangles
from cadedge.mesh.optimize import climb_nodes
from cadedge.mesh.quality import triangle_angles


def _plane(points: np.ndarray, rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    p = np.asarray(points, dtype=float)
    return p, p[:, :2]


def _corner() -> tuple[np.ndarray, np.ndarray, np.ndarray, set]:
    """A 90-degree face corner closed by one triangle between boundary segments of 2.5 and 2.0 (nodes
    0, 1, 2; 38.7 degrees), and an interior node 3 beyond its inner edge."""
    x = np.array([[0, 0, 0], [2.5, 0, 0], [0, 2, 0], [2.4, 2.2, 0]], dtype=float)
    tri = np.array([[0, 1, 2], [1, 3, 2]])
    movable = np.array([False, False, False, True])
    return x, tri, movable, {(0, 1), (0, 2)}


def test_a_corner_triangle_is_split_and_the_new_node_placed_to_beat_it():
    x, tri, movable, fixed = _corner()
    before = triangle_angles(x, tri).min()
    x2, tri2, movable2, uv = split_corner_triangles(x, tri, movable, fixed, _plane)
    assert len(x2) == 5 and len(tri2) == 4 and movable2.tolist() == [False, False, False, True, True]
    assert np.allclose(x2[:4], x) and uv.shape == (1, 2)
    # orientation kept: every new triangle's normal points the same way as before
    normals = np.cross(x2[tri2[:, 1]] - x2[tri2[:, 0]], x2[tri2[:, 2]] - x2[tri2[:, 0]])
    assert (normals[:, 2] > 0).all()
    # the boundary segments are still edges of the mesh, the corner node keeps two triangles
    edges = {tuple(sorted((int(t[i]), int(t[(i + 1) % 3])))) for t in tri2 for i in range(3)}
    assert fixed <= edges and (1, 2) not in edges
    x3, _ = climb_nodes(x2, tri2, movable2, _plane)
    assert triangle_angles(x3, tri2).min() > before + 2.5  # 38.7 -> about 41.8


def test_no_split_of_a_curve_segment_or_a_triangle_with_an_interior_node():
    x, tri, movable, fixed = _corner()
    whole = fixed | {(1, 2)}  # the inner edge is a curve segment too: nothing may change
    x2, tri2, movable2, uv = split_corner_triangles(x, tri, movable, whole, _plane)
    assert x2 is x or np.array_equal(x2, x)
    assert np.array_equal(tri2, tri) and len(uv) == 0
    inner = movable.copy()
    inner[0] = True  # the corner triangle has a node that can move: smoothing's job, not a split's
    x2, tri2, _, uv = split_corner_triangles(x, tri, inner, fixed, _plane)
    assert np.array_equal(tri2, tri) and len(uv) == 0


def test_a_strip_between_two_curves_is_split_only_where_that_lowers_nothing():
    """A strip 0.16 wide between two curves cut into 0.28 segments, filled with no interior node (what
    a collapse into the curves' nodes makes of it): 29.7 degrees, and an interior node in a quad could
    only lower that. Its triangles have one side on a curve; they are left as they are."""
    n = 6
    top = np.column_stack([0.28 * np.arange(n), np.full(n, 0.16), np.zeros(n)])
    bottom = np.column_stack([0.28 * np.arange(n), np.zeros(n), np.zeros(n)])
    x = np.vstack([bottom, top])
    tri = np.array([t for i in range(n - 1) for t in ([i, i + 1, n + i], [i + 1, n + i + 1, n + i])])
    fixed = {(i, i + 1) for i in range(n - 1)} | {(n + i, n + i + 1) for i in range(n - 1)}
    movable = np.zeros(len(x), dtype=bool)
    before = triangle_angles(x, tri).min()
    x2, tri2, _, uv = split_corner_triangles(x, tri, movable, fixed, _plane)
    assert triangle_angles(x2, tri2).min() >= before - 1e-9
    assert len(uv) == 0 and np.array_equal(tri2, tri)


def test_no_split_whose_new_triangles_fold_against_the_surface():
    """The new triangles are judged against their nodes' surface normals (the new node's where it
    lands): against a surface facing the other way, every split folds and none is made."""
    from cadedge.mesh.folds import NodeNormals

    x, tri, movable, fixed = _corner()

    def facing(z: float) -> NodeNormals:
        return NodeNormals(np.tile([0.0, 0.0, z], (len(x), 1)), lambda params: np.tile([0.0, 0.0, z], (len(params), 1)))

    assert len(split_corner_triangles(x, tri, movable, fixed, _plane, normals=facing(1.0))[3]) == 1
    x2, tri2, _, uv = split_corner_triangles(x, tri, movable, fixed, _plane, normals=facing(-1.0))
    assert len(uv) == 0 and np.array_equal(tri2, tri)


def test_a_triangle_between_all_boundary_ones_is_split_where_its_node_can_be_placed_well():
    """twisted_blade's trailing edge at 1e-2: a 21.4-degree triangle with one side on a curve, between
    two triangles whose nodes all lie on curves. Only the new node can ever move, so the split is placed
    across the two triangles it cuts (not only along the inner edge's normal) and made only if that
    gains: about 24.7 degrees."""
    xy = [[8.8478, 0.3722], [9.66, 0.1643], [10.0, 0.0], [9.5573, -0.1382], [8.5761, -0.2472]]
    x = np.column_stack([np.array(xy), np.zeros(5)])
    tri = np.array([[0, 1, 3], [1, 2, 3], [0, 3, 4]])
    fixed = {(0, 1), (1, 2), (2, 3), (3, 4)}
    x2, tri2, movable2, uv = split_corner_triangles(x, tri, np.zeros(5, dtype=bool), fixed, _plane)
    assert len(uv) == 1 and movable2.tolist() == [False] * 5 + [True]
    assert triangle_angles(x2, tri2).min() > triangle_angles(x, tri).min() + 3.0


def test_a_triangle_of_three_collinear_curve_nodes_is_split():
    """Thread.py of cadquery-contrib at 1e-3: gmsh closed three consecutive nodes of a curve, collinear
    to 1e-9, with one triangle (0.0008 degrees). Having no normal of its own, it was judged turned over
    by every split; the pair's normal judges it now, and the split gives it an interior node."""
    x = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 1.2, 0.0]])
    tri = np.array([[0, 1, 2], [0, 2, 3]])
    fixed = {(0, 1), (1, 2)}
    movable = np.array([False, False, False, True])
    x2, tri2, movable2, uv = split_corner_triangles(x, tri, movable, fixed, _plane)
    assert len(uv) == 1 and len(tri2) == 4
    assert triangle_angles(x2, tri2).min() > 20.0
    normals = np.cross(x2[tri2[:, 1]] - x2[tri2[:, 0]], x2[tri2[:, 2]] - x2[tri2[:, 0]])
    assert (normals[:, 2] > 0).all()


def test_each_trial_position_is_projected_from_its_nearest_node():
    """The new node's trial positions are projected from the parameters of the nearest of the two
    triangles' nodes (a walk, not a search over the whole surface: on the Thread's helical B-spline
    faces the searches took 220 of its 240 s)."""
    x, tri, movable, fixed = _corner()
    calls = []

    def project(points: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        calls.append((np.array(points), np.array(rows)))
        return _plane(points)

    split_corner_triangles(x, tri, movable, fixed, project)
    assert calls
    for points, rows in calls:
        distance = np.linalg.norm(points[:, None] - x[None], axis=2)
        assert np.allclose(distance[np.arange(len(rows)), rows], distance.min(axis=1))


def test_candidates_judged_in_batches_split_as_when_judged_one_by_one(monkeypatch):
    """Every candidate split is judged first, a batch of them at a time (gmsh's SlenderSurface.brep, a
    strip filled with 26 000 all-boundary triangles, spent 57 s judging them one by one): the splits are
    those made judging each alone. A strip of uneven width between two curves, closed at its ends."""
    from cadedge.mesh import corners

    n = 30
    rng = np.random.default_rng(1)
    top = np.column_stack([0.28 * np.arange(n) + rng.uniform(-0.1, 0.1, n), 0.3 + rng.uniform(-0.15, 0.15, n),
                           np.zeros(n)])
    x = np.vstack([np.column_stack([0.28 * np.arange(n), np.zeros(n), np.zeros(n)]), top])
    tri = np.array([t for i in range(n - 1) for t in ([i, i + 1, n + i], [i + 1, n + i + 1, n + i])])
    fixed = ({(i, i + 1) for i in range(n - 1)} | {(n + i, n + i + 1) for i in range(n - 1)}
             | {(0, n), (n - 1, 2 * n - 1)})
    movable = np.zeros(len(x), dtype=bool)
    batched = split_corner_triangles(x, tri, movable, fixed, _plane)
    monkeypatch.setattr(corners, "_BATCH", 1)
    alone = split_corner_triangles(x, tri, movable, fixed, _plane)
    assert 0 < len(batched[3]) < len(tri) // 2  # some split, some not
    assert all(np.array_equal(p, q) for p, q in zip(batched, alone))
    assert triangle_angles(batched[0], batched[1]).min() > triangle_angles(x, tri).min()
