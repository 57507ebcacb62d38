"""Edge collapses: remove an interior node where a face's triangles crowd around one point.

Node moves and edge swaps keep a face's node count. Where gmsh's frontal mesher leaves one node too
many, neither can help: a 90-degree face corner fanned out in three 30-degree wedges (two interior
nodes where one would give two 45-degree wedges) stays at 30 degrees whatever the nodes do. Collapsing
the interior edge between the two nodes into one node fixes it; so does it for the 36-degree fans beside
a cylinder's seam.

An edge of a triangle under the angle bound, with both ends interior (movable), is collapsed when the
smallest angle of the triangles around it stays above what it was less :data:`MIN_GAIN`'s slack (the
smoothing that follows settles the ring; the caller keeps the result only if the face's smallest angle
rose: see :func:`cadedge.mesh.optimize.smooth_face`), checked exactly on a few candidate positions for
the merged node: the midpoint, either end, and the centroid of the merged node's neighbours, each
projected onto the surface first. An edge from an interior node to a node on a curve or a point merges
the interior node into the other, which stays where it is (every edge grid node stays, so neighbours
stay conforming), and only where that raises the smallest angle around it (:data:`CURVE_GAIN`) and
keeps the area there (:data:`CURVE_AREA`): a
strip between two curves narrower than their segments is best filled without interior nodes, where
gmsh puts one in the middle of every other quad. An edge between two nodes on curves never collapses.
A collapse must keep the mesh a manifold (the two ends share exactly the two nodes across the edge),
turn no triangle over and fold none against the surface (:mod:`cadedge.mesh.folds`). Worst triangles
go first; each node takes part in at most one collapse per call, so every decision is judged on the
triangles it changes.
"""

from __future__ import annotations

import numpy as np

from .folds import NodeNormals, reference_normals
from .quality import SLIVER_DEG, cross, min_angles

#: Edges of triangles whose smallest angle is under this many degrees are tried (42 lifted two_solids'
#: and red_cube_blue_cylinder's cylinder faces 1-1.5 degrees over 38; 45 collapsed too much).
COLLAPSE_BELOW = 42.0
#: A collapse may lower the smallest angle around it by up to this many degrees (a negative gain): the
#: ring right after a collapse is not yet smoothed. On red_cube_blue_cylinder's seam (1e-2) 0 and -3 left
#: its 36-degree fans in place, -8 gave 39.6 after smoothing, -15 38.3.
MIN_GAIN = -8.0
#: A node merged into a node on a curve must raise the smallest angle around it by this many degrees:
#: most of the merged ring lies on curves, where no smoothing settles it (sphere_box's spherical face at
#: 1e-2 between two fillets 0.17 apart: with :data:`MIN_GAIN`'s slack the merges took it from 26.3 to
#: 22.6 degrees).
CURVE_GAIN = 0.0
#: ... and change the area of the triangles around it by at most this share: on a curved face a merge
#: flattens the surface it removes a node from (LLNL boxed_sphere's cylinder face 115 at 1e-3 lost 0.2% of
#: its area to merges, past its target, and its optimised stages were refused: 19.7 degrees, 29.5 before
#: merges). A narrow strip loses next to nothing; a planar face nothing.
CURVE_AREA = 1e-4
#: ... or, where the ring holds a sliver (under :data:`~cadedge.mesh.quality.SLIVER_DEG`), which no smoothing
#: removes, by at most this share of the whole face's area: Voron 0's Manta DIN mount has B-spline faces
#: closing to a 9-degree corner at a pole, an interior node 0.21 from it on three triangles, two of them 4.5
#: degrees at the corner. Merged into a curve node, one 9-degree triangle fills the corner; the ring loses
#: 5e-4 of its area, the face 2e-6. A share of the ring's area instead (1e-2) let gmsh's first slivers on
#: boxed_sphere's cylinders merge away 2 degrees of their optimised smallest angle at 1e-3.
SLIVER_AREA = 1e-5
#: A trial position is projected onto the surface only if, unprojected, its triangles' smallest angle is
#: within this many degrees of what a collapse needs (the projection moves it by far less than an edge).
PRE_SLACK = 2.0


def _normal(p: np.ndarray) -> np.ndarray:
    return cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])


def _trial_min(x: np.ndarray, new: np.ndarray, a: int, pos: np.ndarray) -> float:
    """Smallest angle of the triangles ``new`` (node indices) with node ``a`` at ``pos``."""
    p = x[new]
    p[new == a] = pos
    return float(min_angles(p.reshape(-1, 3), np.arange(3 * len(new)).reshape(-1, 3)).min())


def _folds(normals: NodeNormals, new: np.ndarray, a: int, params: np.ndarray | None, new_normals: np.ndarray) -> bool:
    """Whether a triangle of ``new`` (its normals ``new_normals``) folds against the surface with node
    ``a`` at parameters ``params`` (None: where it stands, its normal kept)."""
    kept = normals.up[a].copy()
    if params is not None:
        normals.up[a] = normals.at(params[None])[0]
    try:
        return bool(np.any(np.einsum("ij,ij->i", new_normals, reference_normals(normals.up, new)) < 0))
    finally:
        normals.up[a] = kept


def collapse_edges(x: np.ndarray, tri: np.ndarray, movable: np.ndarray, project, *,
                   below: float = COLLAPSE_BELOW,
                   normals: NodeNormals | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Collapse interior edges of triangles under ``below`` degrees where that raises the smallest angle
    around them (see the module doc); ``normals``: the nodes' oriented surface normals, against which
    no new triangle may fold (the merged node's taken at its new position; updated as nodes merge).

    ``project(points (k, 3), rows (k,))`` returns the points (near nodes ``rows``) moved onto the surface
    and their parametric coordinates (k, d). Returns ``(x, tri, removed, params)``: the coordinates (rows of removed nodes unchanged, no
    longer used), the remaining triangles (orientation kept), a mask of the removed nodes, and for every
    node the parametric coordinates of its new position (NaN rows for nodes that did not move; shape
    (n, d), or (n, 0) when nothing moved).
    """
    x = np.array(x, dtype=float)
    tri = np.array(tri, dtype=np.int64)
    n = len(x)
    removed = np.zeros(n, dtype=bool)
    if not len(tri) or not np.any(movable):
        return x, tri, removed, np.zeros((n, 0))
    ang = min_angles(x, tri)
    bad = np.flatnonzero(ang < below)
    if not len(bad):
        return x, tri, removed, np.zeros((n, 0))
    face_area = float(np.linalg.norm(_normal(x[tri]), axis=1).sum())  # twice it, as the rings' below
    alive = np.ones(len(tri), dtype=bool)
    # node -> its triangles, only for the nodes that can take part (and their neighbours' triangles)
    order = np.argsort(tri.ravel(), kind="stable")
    owner = order // 3
    starts = np.searchsorted(tri.ravel()[order], np.arange(n + 1))
    around: dict[int, set[int]] = {}

    def tris_of(v: int) -> set[int]:
        if v not in around:
            around[v] = set(owner[starts[v]:starts[v + 1]].tolist())
        return around[v]

    touched = np.zeros(n, dtype=bool)
    moved: list[tuple[int, np.ndarray]] = []
    for t in bad[np.argsort(ang[bad])].tolist():
        if not alive[t]:
            continue
        corners = tri[t]
        if touched[corners].any():
            continue
        best = None
        for k in range(3):
            a, b = int(corners[k]), int(corners[(k + 1) % 3])
            if not (movable[a] or movable[b]):
                continue
            if not movable[b]:
                a, b = b, a  # a node on a curve survives, where it stands
            ta, tb = tris_of(a), tris_of(b)
            gone = ta & tb
            if len(gone) != 2:
                continue
            ring = sorted(ta | tb)
            rt = tri[ring]
            opposite = {int(v) for g in gone for v in tri[g] if v != a and v != b}
            na = {int(v) for v in tri[sorted(ta)].ravel()} - {a, b}
            nb = {int(v) for v in tri[sorted(tb)].ravel()} - {a, b}
            if na & nb != opposite or len(opposite) != 2:
                continue  # not a manifold collapse
            keep = np.array([r not in gone for r in ring])
            new = np.where(rt == b, a, rt)[keep]
            old_min = ang[ring].min()
            normals0 = _normal(x[rt[keep]])
            if movable[a]:
                neighbours = np.array(sorted(na | nb))
                trial = np.array([0.5 * (x[a] + x[b]), x[a], x[b], x[neighbours].mean(axis=0)])
                # projecting is the costly part: only trials whose unprojected position comes near winning
                can = [i for i, pos in enumerate(trial) if _trial_min(x, new, a, pos) > old_min + MIN_GAIN - PRE_SLACK]
                if not can:
                    continue
                on, uv = project(trial[can], np.full(len(can), a))
            else:  # a node on a curve stays where it is, on the surface
                area = np.linalg.norm(_normal(x[rt]), axis=1).sum()
                lost = abs(np.linalg.norm(_normal(x[new]), axis=1).sum() - area)
                if lost > CURVE_AREA * area and not (old_min < SLIVER_DEG and lost <= SLIVER_AREA * face_area):
                    continue  # the merge would flatten a curved face
                on, uv = x[a][None], [None]
            for pos, puv in zip(on, uv):
                p = x[new]
                p[new == a] = pos
                if np.any(np.einsum("ij,ij->i", _normal(p), normals0) <= 0):
                    continue
                if normals is not None and _folds(normals, new, a, puv, _normal(p)):
                    continue
                q = _trial_min(x, new, a, pos)
                if q > old_min + (MIN_GAIN if movable[a] else CURVE_GAIN) and (best is None or q > best[0]):
                    best = (q, a, b, pos, puv, ring, keep, new, gone)
        if best is None:
            continue
        _, a, b, pos, puv, ring, keep, new, gone = best
        ring = np.asarray(ring)
        x[a] = pos
        if normals is not None and puv is not None:
            normals.up[a] = normals.at(puv[None])[0]
        tri[ring[keep]] = new
        alive[list(gone)] = False
        removed[b] = True
        touched[tri[ring[keep]].ravel()] = True
        ang[ring[keep]] = min_angles(x, new)
        merged = (tris_of(a) | tris_of(b)) - gone
        for v in {int(v) for g in gone for v in tri[g]} - {a, b}:
            tris_of(v).difference_update(gone)
        around[a] = merged
        around[b] = set()
        if puv is not None:
            moved.append((a, puv))
    if not removed.any():
        return x, tri, removed, np.zeros((n, 0))
    if not moved:
        return x, tri[alive], removed, np.zeros((n, 0))
    params = np.full((n, len(moved[0][1])), np.nan)
    for a, puv in moved:
        params[a] = puv
    return x, tri[alive], removed, params
