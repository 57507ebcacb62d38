"""Edges split on the surface where a face falls short of its B-rep area (cadedge.mesh.midpoints): the
longest-edge paths on plain arrays, and real gmsh faces split within their target."""

from __future__ import annotations

import numpy as np
import pytest

from cadedge.mesh.midpoints import _edges, _ends


def _strip():
    """Four triangles in a row over nodes 0..5 (counter-clockwise); the square's diagonal 1-4 is the
    longest edge of triangles 1 and 2, triangle 0's longest edge (0-4) leads to triangle 1."""
    x = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [0.1, 1.9, 0], [2, 1, 0]], dtype=float)
    tri = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]])
    return x, tri


def test_edges_pair_the_triangles_of_interior_edges_and_leave_curves_alone():
    x, tri = _strip()
    eid, t1, t2, a, b, c, d = _edges(tri, len(x), np.array([], dtype=np.int64))
    assert eid.shape == (4, 3) and len(t1) == 9  # 9 distinct edges
    inner = np.flatnonzero(t2 >= 0)
    pairs = {(int(min(a[e], b[e])), int(max(a[e], b[e]))) for e in inner}
    assert pairs == {(0, 4), (1, 4), (1, 5)}
    for e in inner:  # t1 runs a -> b, t2 runs b -> a; c and d are the nodes opposite
        assert c[e] in tri[t1[e]] and d[e] in tri[t2[e]] and c[e] not in (a[e], b[e])
        row = list(tri[t1[e]])
        assert row[(row.index(a[e]) + 1) % 3] == b[e]
    # an edge on a curve is never split: its second triangle is dropped
    key = 1 * (len(x) + 1) + 4
    _, _, t2_fixed, a2, b2, *_ = _edges(tri, len(x), np.array([key]))
    assert {(int(min(p, q)), int(max(p, q))) for p, q, t in zip(a2, b2, t2_fixed) if t >= 0} == {(0, 4), (1, 5)}


def test_longest_edge_paths_end_at_an_edge_longest_in_both_its_triangles():
    x, tri = _strip()
    eid, t1, t2, a, b, _, _ = _edges(tri, len(x), np.array([], dtype=np.int64))
    length = np.linalg.norm(x[a] - x[b], axis=1)
    longest = eid[np.arange(len(tri)), np.argmax(length[eid], axis=1)]
    end = _ends(longest, t1, t2)
    for t, stop in enumerate(end):
        e = longest[stop]
        other = t2[e] if t1[e] == stop else t1[e]
        # at the end the longest edge is the other triangle's longest too, or lies on the border
        assert other < 0 or longest[other] == e, (t, stop)
        # and the path only climbs: the end's longest edge is at least the start's
        assert length[e] >= length[longest[t]] - 1e-12


gmsh = pytest.importorskip("gmsh")


def _coarse_cylinder_side():
    """A unit cylinder of height 2 meshed by gmsh with 0.9 sizes: its side, well short of 4 pi."""
    from cadedge.mesh.facemesh import read_face

    gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, 2, 1.0)
    gmsh.model.occ.synchronize()
    (side,) = [s for _, s in gmsh.model.getEntities(2) if gmsh.model.getType(2, s) != "Plane"]
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.9)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.9)
    gmsh.model.mesh.generate(2)
    return side, read_face(side)


def _area(face) -> float:
    p = face.x[face.tri]
    return float(0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum())


def test_a_short_cylinder_side_is_split_within_its_target_on_its_surface():
    """The side meshed at 0.9 is well short of 4 pi; split to within 1e-2, every new node on the cylinder, the curves' nodes and segments as they were, no triangle folded and
    the side still a closed band (every interior edge in two triangles)."""
    from cadedge.mesh.facemesh import read_face
    from cadedge.mesh.folds import folded, orientation, reference_normals, surface_normals
    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.midpoints import split_short_face

    brep = 4.0 * np.pi
    with gmsh_session():
        side, before = _coarse_cylinder_side()
        short = 1.0 - _area(before) / brep
        assert short > 1e-2
        assert split_short_face(side, brep, 1e-2)
        after = read_face(side)
        deficit = 1.0 - _area(after) / brep
        assert 0.0 <= deficit <= 1e-2 and len(after.tri) > len(before.tri)
        radius = np.linalg.norm(after.x[:, :2], axis=1)
        assert np.allclose(radius, 1.0, atol=1e-9)  # every node on the surface
        boundary = ~before.movable
        keep = {tuple(np.round(p, 12)) for p in before.x[boundary]}
        assert keep == {tuple(np.round(p, 12)) for p in after.x[~after.movable]}
        assert len(before.fixed) == len(after.fixed)
        up = surface_normals(side, after.x, after.uv, after.tags)
        assert not folded(after.x, after.tri, reference_normals(up, after.tri, orientation(up, after.tri, after.x))).any()
        edges = np.sort(np.concatenate([after.tri[:, [0, 1]], after.tri[:, [1, 2]], after.tri[:, [2, 0]]]), axis=1)
        pairs, count = np.unique(edges, axis=0, return_counts=True)
        assert count.max() == 2 and {tuple(e) for e in pairs[count == 1].tolist()} <= after.fixed
        # within its target already: nothing to do, the mesh stays
        assert not split_short_face(side, brep, 0.5)
        assert np.array_equal(read_face(side).tri, after.tri)


def test_a_face_read_back_holds_each_seam_node_once_with_its_parameters():
    """gmsh lists a cylinder side's seam nodes twice (the seam bounds the side on both sides): read back,
    each node is one row used by a triangle, and every node finds its parameters without a projection
    (``getParametrization``, 2 ms a node on a B-spline face, was run on every unused copy)."""
    from unittest import mock

    from cadedge.mesh.folds import node_params
    from cadedge.mesh.gmsh_model import gmsh_session

    with gmsh_session():
        side, face = _coarse_cylinder_side()
        listed = gmsh.model.mesh.getNodes(2, side, includeBoundary=True)[0]
        assert len(listed) > len(set(listed))  # gmsh's own list has the seam's nodes twice
        assert len(np.unique(face.tags)) == len(face.tags) == len(set(listed))
        assert np.all(np.bincount(face.tri.ravel(), minlength=len(face.tags)) > 0)
        projected: list[int] = []
        real = gmsh.model.getParametrization
        with mock.patch.object(gmsh.model, "getParametrization",
                               lambda dim, tag, x: projected.append(len(x) // 3) or real(dim, tag, x)):
            uv = node_params(side, face.x, face.uv, face.tags)
        assert not np.isnan(uv).any() and sum(projected) <= 2  # the curves' end points at most


def test_middles_across_a_seam_are_taken_the_short_way_round_only_where_the_surface_closes_up():
    """A cylinder's side closes up across its seam (u = 0 and 2 pi give the same points): the middle of
    an edge from u = 0.1 to u = 2 pi - 0.1 lies on the seam, not at u = pi across the cylinder. A box's
    face does not close up: its middles are the plain parametric ones, however long the edge."""
    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.midpoints import _periods, _seam_middles

    with gmsh_session():
        gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, 2, 1.0)
        gmsh.model.occ.addBox(5, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        side = next(s for _, s in gmsh.model.getEntities(2) if gmsh.model.getType(2, s) == "Cylinder")
        plane = next(s for _, s in gmsh.model.getEntities(2) if gmsh.model.getType(2, s) == "Plane"
                     and gmsh.model.getBoundingBox(2, s)[0] >= 5 - 1e-9)
        low, span = _periods(side)
        (k,) = np.flatnonzero(np.isfinite(span))  # one direction closes up: the one around the axis
        uv = np.zeros((4, 2))
        uv[:, 1 - k] = low[1 - k] + 1.0
        uv[:, k] = low[k] + np.array([0.1, span[k] - 0.1, 1.0, 2.0])
        mid = _seam_middles(side, uv, np.array([0, 1, 2]), np.array([1, 0, 3]))
        for m in mid[:2, k]:  # either way round: on the seam, at one end of the range or the other
            assert min(abs(m - low[k]), abs(m - low[k] - span[k])) < 1e-12
        assert mid[2, k] == pytest.approx(low[k] + 1.5) and np.allclose(mid[:, 1 - k], low[1 - k] + 1.0)
        assert not np.isfinite(_periods(plane)[1]).any()
        lo, hi = gmsh.model.getParametrizationBounds(2, plane)
        ends = np.array([[lo[0] + 0.01, lo[1]], [hi[0] - 0.01, hi[1]]])
        assert np.allclose(_seam_middles(plane, ends, np.array([0]), np.array([1])), ends.mean(axis=0))
