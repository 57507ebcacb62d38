"""Improve every meshed face's triangles, keeping its boundary and its area target.

gmsh's frontal mesher leaves 22-30 degree triangles where its sizes change (from a boundary graded from
the edge grids to the curvature sizes inside); gmsh alone, with nearly uniform sizes, gets 33-40 degrees
on the same cylinders and boxes. Each face gets a few passes of:

- edge swaps (:func:`flip_edges`): the diagonal of two triangles is swapped where that raises their
  smaller angle; curve segments are never swapped;
- a "smart" Laplacian (:func:`smooth_nodes`): every interior node moves to the mean of its neighbours in
  3-D, projected back onto the B-rep surface (:class:`~cadedge.mesh.project.Projector`), where the smallest angle
  of its triangles does not fall and none flips;
- a local search (:func:`climb_nodes`): nodes of triangles under :data:`CLIMB_BELOW` degrees move to the
  best of 24 trial positions around them, the one that raises their worst angle most.

Only nodes within two rings of a triangle under :data:`CLIMB_BELOW` degrees move (and are projected,
the costly part on B-spline faces); the rest of a face is left as gmsh made it. A face still under
:data:`~cadedge.mesh.collapse.COLLAPSE_BELOW` degrees then gets passes with edge collapses
(:mod:`cadedge.mesh.collapse`: one interior node less where triangles crowd around a point, e.g. a
90-degree face corner fanned out in three 30-degree wedges) and edge splits (:mod:`cadedge.mesh.corners`:
one interior node more where a triangle has all three nodes on the boundary, e.g. a face corner closed by
one triangle), and then a few more without, each stage kept only if the face's smallest angle rose.

Working in 3-D rather than in the surface's parameters treats nodes beside a seam like any other (gmsh's
own ``Laplace2D`` and ``Relocate2D`` left the worst triangles of a cylinder, beside its seam, in place).
Nodes on curves and points (every edge grid node) never move, so neighbours stay conforming. A face
keeps the result only when its smallest angle does not fall and its area deficit stays within its
target (or does not grow).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from .collapse import COLLAPSE_BELOW, collapse_edges
from .corners import split_corner_triangles
from .project import Projector
from .quality import triangle_angles

#: Smoothing iterations per pass, and passes (edge swaps, then smoothing) per face.
ITERATIONS = 4
PASSES = 3
#: Passes of the stages after the first, each kept only if it raises the face's smallest angle: with edge
#: collapses (:mod:`cadedge.mesh.collapse`), then without. The stages are chaotic (5 passes at once lifted
#: the cylinder fixture at 1e-3 from 39.0 to 40.3 degrees but undid red_cube_blue_cylinder's collapses at
#: 1e-2, 39.7 -> 33.7); kept only when better, each can only help.
LATER_STAGES = ((3, True), (2, False))
#: Nodes with a triangle angle under this many degrees are moved to the best of a few trial positions
#: (40 stopped the planar faces of the cylinder-and-box models at 40-41 degrees, where gmsh alone gets 41;
#: 45 lifts them to 42-45 for about twice the optimiser's time, 50 adds nothing).
CLIMB_BELOW = 45.0
#: The trial positions' distances, as shares of the node's mean edge length.
STEPS = (0.03, 0.1, 0.25)
#: Edge-swap rounds per face and pass.
FLIP_ROUNDS = 10
#: The optimiser's time budget: this share of the time the job took before it (reading the shape, sizes,
#: gmsh's meshing), at least :data:`MIN_BUDGET` seconds, and never past the job's soft deadline. Each
#: face (worst first) may use :data:`FACE_SHARE` of what is left, or more if its triangles are a larger
#: share of those still to improve; a face out of time keeps its last stage's result (or gmsh's).
BUDGET_SHARE = 1.0
MIN_BUDGET = 30.0
FACE_SHARE = 0.5
#: Rounds of undoing moves that made a triangle worse than before the pass (its nodes' neighbours moved
#: too), after which the pass is undone as a whole.
_UNDO_ROUNDS = 8


def _normals(x: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p = x[tri]
    return np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])


def _group_min(values: np.ndarray, keys: np.ndarray, n: int) -> np.ndarray:
    """Smallest of ``values`` per key in ``0..n-1`` (``inf`` for a key without any); a sort and
    ``np.minimum.reduceat`` (``np.minimum.at`` is many times slower)."""
    out = np.full(n, np.inf)
    if not len(keys):
        return out
    order = np.argsort(keys, kind="stable")
    k = keys[order]
    starts = np.flatnonzero(np.concatenate([[True], k[1:] != k[:-1]]))
    out[k[starts]] = np.minimum.reduceat(values[order], starts)
    return out


def _group_max(values: np.ndarray, keys: np.ndarray, n: int) -> np.ndarray:
    """Largest of ``values`` per key (``-inf`` for a key without any)."""
    return -_group_min(-values, keys, n)


def _node_min(values: np.ndarray, tri: np.ndarray, n: int) -> np.ndarray:
    """Smallest value over each node's triangles (``inf`` for a node without any)."""
    return _group_min(np.repeat(values, 3), tri.ravel(), n)


def smooth_nodes(x: np.ndarray, tri: np.ndarray, movable: np.ndarray, project, *,
                 iterations: int = ITERATIONS) -> tuple[np.ndarray, np.ndarray | None]:
    """Smart-Laplacian smoothing of the ``movable`` nodes of the triangles ``tri`` (indices into ``x``).

    ``project(points (k, 3), rows (k,))`` returns the points (those of nodes ``rows``) moved onto the
    surface and their parametric coordinates (k, d). Returns the new coordinates and the parametric coordinates of the movable nodes (NaN rows for
    nodes that stayed; ``None`` if nothing moved). A move stays only if no triangle of the node flips and
    the smallest angle of its triangles does not fall; moves that, with their neighbours', flip a triangle
    or bring it below the worst angle around it before the pass are undone.
    """
    x = np.array(x, dtype=float)
    n = len(x)
    mov = np.flatnonzero(movable)
    if not len(mov) or not len(tri):
        return x, None
    e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    adj = sparse.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    adj = ((adj + adj.T) > 0).astype(float)
    deg = np.asarray(adj.sum(axis=1)).ravel()
    params = None
    for _ in range(iterations):
        ang0 = triangle_angles(x, tri).min(axis=1)
        nrm0 = _normals(x, tri)
        node0 = _node_min(ang0, tri, n)
        target = (adj @ x)[mov] / deg[mov, None]
        moved, uv = project(target, mov)
        cand = x.copy()
        cand[mov] = moved
        ang1 = triangle_angles(cand, tri).min(axis=1)
        flipped = np.einsum("ij,ij->i", _normals(cand, tri), nrm0) <= 0
        bad_node = _node_min(np.where(flipped, -1.0, ang1), tri, n)
        accept = np.zeros(n, dtype=bool)
        accept[mov] = (bad_node[mov] >= node0[mov]) & np.any(cand[mov] != x[mov], axis=1)
        floor = node0[tri].min(axis=1)  # a triangle may get worse, but not below its neighbourhood's worst
        for _round in range(_UNDO_ROUNDS):
            trial = np.where(accept[:, None], cand, x)
            ang_t = triangle_angles(trial, tri).min(axis=1)
            worse = (ang_t < floor) | (np.einsum("ij,ij->i", _normals(trial, tri), nrm0) <= 0)
            if not worse.any():
                break
            accept[tri[worse].ravel()] = False
        else:
            accept[:] = False
        if not accept.any():
            break
        x[accept] = cand[accept]
        if params is None:
            params = np.full((len(mov), uv.shape[1]), np.nan)
        take = accept[mov]
        params[take] = uv[take]
    return x, params


def flip_edges(x: np.ndarray, tri: np.ndarray, fixed: set[tuple[int, int]], *,
               rounds: int = FLIP_ROUNDS) -> np.ndarray:
    """Swap the diagonal of pairs of triangles wherever that raises the smaller of their two smallest
    angles; edges in ``fixed`` (sorted node-index pairs: the curve segments) are never swapped, nor an edge
    whose new triangles would turn against the old ones or whose new diagonal is already an edge. Each round swaps, for every triangle, at most its
    best edge. Returns the new triangles (same count and orientation)."""
    tri = np.array(tri, dtype=np.int64)
    fixed_keys = np.array(sorted(a * (len(x) + 1) + b for a, b in fixed), dtype=np.int64)
    for _ in range(rounds):
        a = tri.ravel()
        b = np.roll(tri, -1, axis=1).ravel()
        c = np.roll(tri, -2, axis=1).ravel()
        owner = np.repeat(np.arange(len(tri)), 3)
        key = np.minimum(a, b) * (len(x) + 1) + np.maximum(a, b)
        order = np.argsort(key, kind="stable")
        ks = key[order]
        pair = np.flatnonzero(ks[1:] == ks[:-1])
        pair = pair[((pair + 2 >= len(ks)) | (ks[np.minimum(pair + 2, len(ks) - 1)] != ks[pair]))
                    & ((pair == 0) | (ks[pair - 1] != ks[pair]))]  # edges with exactly two triangles
        h1, h2 = order[pair], order[pair + 1]
        keep = (a[h1] == b[h2]) & (b[h1] == a[h2]) & ~np.isin(ks[pair], fixed_keys)
        h1, h2 = h1[keep], h2[keep]
        if not len(h1):
            break
        t1, t2 = owner[h1], owner[h2]
        pa, pb, pc, pd = a[h1], b[h1], c[h1], c[h2]
        new1 = np.column_stack([pa, pd, pc])
        new2 = np.column_stack([pd, pb, pc])
        before = np.minimum(triangle_angles(x, tri[t1]).min(axis=1), triangle_angles(x, tri[t2]).min(axis=1))
        after = np.minimum(triangle_angles(x, new1).min(axis=1), triangle_angles(x, new2).min(axis=1))
        ref = _normals(x, tri[t1]) + _normals(x, tri[t2])
        ok = (np.einsum("ij,ij->i", _normals(x, new1), ref) > 0) & (np.einsum("ij,ij->i", _normals(x, new2), ref) > 0)
        new_key = np.minimum(pc, pd) * (len(x) + 1) + np.maximum(pc, pd)
        ok &= ~np.isin(new_key, ks)  # the new diagonal already joins c and d (a fan at an apex): a flip would
        # stack a second pair of triangles on the existing ones
        gain = np.where(ok & (pc != pd), after - before, 0.0)
        good = gain > 1e-6
        if not good.any():
            break
        g = np.flatnonzero(good)
        best = np.maximum(_group_max(np.concatenate([gain[g], gain[g]]), np.concatenate([t1[g], t2[g]]),
                                     len(tri)), 0.0)
        pick = good & (gain >= best[t1]) & (gain >= best[t2])
        idx = np.flatnonzero(pick)  # ties: one swap per triangle, the first edge found
        first = _group_max(np.concatenate([-idx, -idx]).astype(float), np.concatenate([t1[idx], t2[idx]]),
                           len(tri))
        pick[idx] = (first[t1[idx]] == -idx) & (first[t2[idx]] == -idx)
        idx = np.flatnonzero(pick)  # two swaps in one round must not make the same new diagonal
        _, once = np.unique(new_key[idx], return_index=True)
        pick[np.setdiff1d(idx, idx[once])] = False
        tri[t1[pick]] = new1[pick]
        tri[t2[pick]] = new2[pick]
    return tri


def _incident_min(x: np.ndarray, tri: np.ndarray, node: np.ndarray, slot: np.ndarray, t: np.ndarray,
                  pos: np.ndarray, n: int) -> np.ndarray:
    """For incidences (``node`` at corner ``slot`` of triangle ``t``), the smallest angle of each node's
    triangles with that node moved to ``pos[node]`` (the others where they are)."""
    p = x[tri[t]].copy()
    p[np.arange(len(t)), slot] = pos[node]
    ang = np.empty(len(t))
    for k in range(3):
        a = p[:, (k + 1) % 3] - p[:, k]
        b = p[:, (k + 2) % 3] - p[:, k]
        cos = np.einsum("ij,ij->i", a, b)
        ang_k = np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), cos))
        ang = ang_k if k == 0 else np.minimum(ang, ang_k)
    return _group_min(ang, node, n)


def climb_nodes(x: np.ndarray, tri: np.ndarray, movable: np.ndarray, project, *,
                iterations: int = ITERATIONS, below: float = CLIMB_BELOW) -> tuple[np.ndarray, np.ndarray | None]:
    """Move movable nodes whose triangles have an angle under ``below`` degrees to the best of a few trial
    positions around them (8 directions in their tangent plane, :data:`STEPS` away), the one that raises
    the smallest angle of their triangles most. Of neighbours that can both improve, only the worse off
    moves in one iteration, so each move is judged exactly (up to the projection back onto the surface,
    checked after it). Returns the coordinates and the parametric coordinates of the movable nodes as
    :func:`smooth_nodes` does."""
    x = np.array(x, dtype=float)
    n = len(x)
    mov_idx = np.flatnonzero(movable)
    if not len(mov_idx) or not len(tri):
        return x, None
    where = np.full(n, -1)
    where[mov_idx] = np.arange(len(mov_idx))
    node = tri.ravel()
    slot = np.tile(np.arange(3), len(tri))
    t = np.repeat(np.arange(len(tri)), 3)
    sel = movable[node]
    node, slot, t = node[sel], slot[sel], t[sel]
    e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    phi = np.arange(8) * np.pi / 4
    params = None
    for _ in range(iterations):
        ang = triangle_angles(x, tri).min(axis=1)
        node0 = _node_min(ang, tri, n)
        want = movable & (node0 < below)
        if not want.any():
            break
        go = want
        tn = np.repeat(_normals(x, tri), 3, axis=0)
        nrm = np.column_stack([np.bincount(tri.ravel(), weights=tn[:, k], minlength=n) for k in range(3)])
        seg = np.repeat(np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1), 2)
        h = np.bincount(e.ravel(), weights=seg, minlength=n) / np.maximum(np.bincount(e.ravel(), minlength=n), 1)
        nn = nrm / np.maximum(np.linalg.norm(nrm, axis=1), 1e-300)[:, None]
        ref = np.where(np.abs(nn[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
        u = np.cross(nn, ref)
        u /= np.maximum(np.linalg.norm(u, axis=1), 1e-300)[:, None]
        v = np.cross(nn, u)
        best = node0.copy()
        best_pos = x.copy()
        sub = go[node]
        nd, sl, tt = node[sub], slot[sub], t[sub]
        for step in STEPS:
            for a in phi:
                pos = x + step * h[:, None] * (np.cos(a) * u + np.sin(a) * v)
                q = _incident_min(x, tri, nd, sl, tt, pos, n)
                better = go & (q > best + 1e-9)
                best[better] = q[better]
                best_pos[better] = pos[better]
        improves = go & (best > node0 + 1e-9)
        # one node per neighbourhood: of two neighbours that can improve, the worse off moves first
        rank = node0 + np.arange(n) * 1e-12
        both = improves[e[:, 0]] & improves[e[:, 1]]
        i, j = e[both, 0], e[both, 1]
        improves[np.where(rank[i] > rank[j], i, j)] = False
        moved = np.flatnonzero(improves)
        if not len(moved):
            break
        px, puv = project(best_pos[moved], moved)
        cand = x.copy()
        cand[moved] = px
        after = triangle_angles(cand, tri).min(axis=1)
        flipped = np.einsum("ij,ij->i", _normals(cand, tri), _normals(x, tri)) <= 0
        got = _node_min(np.where(flipped, -1.0, after), tri, n)
        ok = moved[got[moved] > node0[moved]]
        if not len(ok):
            break
        x[ok] = cand[ok]
        if params is None:
            params = np.full((len(mov_idx), puv.shape[1]), np.nan)
        params[where[ok]] = puv[np.searchsorted(moved, ok)]
    return x, params


def _near_bad(x: np.ndarray, tri: np.ndarray, movable: np.ndarray) -> np.ndarray:
    """The movable nodes within two rings of a triangle under :data:`CLIMB_BELOW` degrees: the only ones
    worth moving (and projecting onto the surface, the costly part on B-spline faces)."""
    near = np.zeros(len(x), dtype=bool)
    near[tri[triangle_angles(x, tri).min(axis=1) < CLIMB_BELOW].ravel()] = True
    for _ in range(2):
        near[tri[near[tri].any(axis=1)].ravel()] = True
    return near & movable


def _area(x: np.ndarray, tri: np.ndarray) -> float:
    return float(0.5 * np.linalg.norm(_normals(x, tri), axis=1).sum())


@dataclass
class _Face:
    """One face's mesh while it is improved: coordinates, triangles (indices into them), which nodes may
    move, the parametric coordinates of the interior nodes and which of them moved."""

    x: np.ndarray
    tri: np.ndarray
    movable: np.ndarray
    uv: np.ndarray
    moved: np.ndarray

    def min_angle(self) -> float:
        return float(triangle_angles(self.x, self.tri).min())


def _improve(face: _Face, fixed: set[tuple[int, int]], project, passes: int, late, *,
             collapse: bool = False) -> _Face:
    """``passes`` times: edge swaps, edge collapses and edge splits (with ``collapse``; see
    :mod:`cadedge.mesh.collapse` and :mod:`cadedge.mesh.corners`) and swaps again, then smoothing and the local search of the nodes near bad triangles. Returns a new
    :class:`_Face` (``face`` is left as it is); stops when ``late()``."""
    x, tri, movable = face.x, face.tri, face.movable.copy()
    uv, moved = face.uv.copy(), face.moved.copy()
    if isinstance(project, Projector):
        project.uv = uv  # the nodes' current parameters start their projections

    def took(params: np.ndarray | None, rows: np.ndarray) -> None:
        if params is None or not params.shape[1]:
            return
        got = ~np.isnan(params[:, 0])
        uv[rows[got]] = params[got]
        moved[rows[got]] = True

    for _ in range(passes):
        if late():
            break
        tri = flip_edges(x, tri, fixed)
        if collapse:
            x, tri, gone, params = collapse_edges(x, tri, movable, project)
            took(params, np.arange(len(x)))
            if gone.any():
                movable &= ~gone
                tri = flip_edges(x, tri, fixed)
            x, tri, movable, new_uv = split_corner_triangles(x, tri, movable, fixed, project)
            if len(new_uv):  # new interior nodes: rows appended
                uv = np.vstack([uv, new_uv])
                moved = np.concatenate([moved, np.ones(len(new_uv), dtype=bool)])
                if isinstance(project, Projector):
                    project.uv = uv
                tri = flip_edges(x, tri, fixed)
        active = _near_bad(x, tri, movable)
        if not active.any():
            break
        rows = np.flatnonzero(active)
        for mover in (smooth_nodes, climb_nodes):
            if late():
                break
            x, params = mover(x, tri, active, project)
            took(params, rows)
    return _Face(x, tri, movable, uv, moved)


def smooth_face(surface: int, *, brep_area: float = 0.0, target: float | None = None,
                passes: int = PASSES, deadline: float | None = None) -> bool:
    """Improve one meshed gmsh surface: ``passes`` times edge swaps (:func:`flip_edges`, never a curve
    segment) then smoothing of its interior nodes (:func:`smooth_nodes`, :func:`climb_nodes`); then the
    :data:`LATER_STAGES` (with edge collapses while its smallest angle is under
    :data:`~cadedge.mesh.collapse.COLLAPSE_BELOW`, then without), each kept only if it raises the
    smallest angle. A result replaces the face's mesh only if its
    smallest angle does not fall and its area deficit (against ``brep_area``) stays within ``target`` or
    does not grow; a face that lost nodes is written again (its interior nodes and triangles; its curves'
    nodes stay). No pass or move starts after ``deadline`` (``time.time()``). Returns whether the face's
    mesh changed."""
    import time

    import gmsh

    from .generate import node_lookup
    from .gmsh_model import surface_curve_uses

    el_tags, tri_tags = gmsh.model.mesh.getElementsByType(2, surface)
    if not len(tri_tags):
        return False
    tags, coords, _ = gmsh.model.mesh.getNodes(2, surface, includeBoundary=True)
    tags = np.asarray(tags, dtype=np.int64)
    lookup = node_lookup(tags)
    tri_tags = np.asarray(tri_tags, dtype=np.int64)
    if tri_tags.max() >= len(lookup) or (lookup[tri_tags] < 0).any():
        return False
    tri0 = lookup[tri_tags].reshape(-1, 3)
    x0 = np.asarray(coords, dtype=float).reshape(-1, 3)
    fixed: set[tuple[int, int]] = set()
    for curve in surface_curve_uses(surface):
        seg = np.asarray(gmsh.model.mesh.getElementsByType(1, curve)[1], dtype=np.int64).reshape(-1, 2)
        seg = seg[(seg < len(lookup)).all(axis=1)]
        seg = lookup[seg]
        fixed.update((int(min(p, q)), int(max(p, q))) for p, q in seg if p >= 0 and q >= 0)
    inner_tags, _, inner_uv = gmsh.model.mesh.getNodes(2, surface, includeBoundary=False, returnParametricCoord=True)
    inner = np.asarray(inner_tags, dtype=np.int64)
    movable = np.zeros(len(tags), dtype=bool)
    movable[lookup[inner]] = True
    uv = np.full((len(tags), 2), np.nan)  # parametric coordinates of the interior nodes, by node row
    if len(inner) and len(inner_uv) == 2 * len(inner):
        uv[lookup[inner]] = np.asarray(inner_uv, dtype=float).reshape(-1, 2)
    start = _Face(x0, tri0, movable, uv, np.zeros(len(tags), dtype=bool))
    project = Projector(surface)

    def late() -> bool:
        return deadline is not None and time.time() > deadline

    def fits(face: _Face) -> bool:
        """Its smallest angle is not below gmsh's and its area deficit within the target (or no worse)."""
        if face.min_angle() < start.min_angle():
            return False
        if target is not None and brep_area > 0:
            d0, d1 = abs(1.0 - _area(x0, tri0) / brep_area), abs(1.0 - _area(face.x, face.tri) / brep_area)
            return d1 <= max(target, d0)
        return True

    best = _improve(start, fixed, project, passes, late)
    if not fits(best):
        best = start
    for n, collapse in LATER_STAGES:
        if late() or best.min_angle() >= (COLLAPSE_BELOW if collapse else CLIMB_BELOW):
            continue
        more = _improve(best, fixed, project, n, late, collapse=collapse)
        if more.min_angle() > best.min_angle() and fits(more):
            best = more
    if best is start:
        return False
    x, tri, movable, uv, moved = best.x, best.tri, best.movable, best.uv, best.moved
    if len(tri) != len(tri0) or len(x) != len(tags):  # nodes removed or added: the interior written anew
        el = np.asarray(el_tags, dtype=np.int64)
        if len(x) > len(tags):  # new nodes (edge splits) get new tags, their triangles too
            tags = np.concatenate([tags, gmsh.model.mesh.getMaxNodeTag() + 1 + np.arange(len(x) - len(tags))])
        if len(tri) > len(el):
            el = np.concatenate([el, gmsh.model.mesh.getMaxElementTag() + 1 + np.arange(len(tri) - len(el))])
        keep = movable & np.bincount(tri.ravel(), minlength=len(tags)).astype(bool)
        rows = np.flatnonzero(keep)
        gmsh.model.mesh.clear([(2, surface)])
        params = [] if np.isnan(uv[rows]).any() else uv[rows].ravel().tolist()
        gmsh.model.mesh.addNodes(2, surface, tags[rows].tolist(), x[rows].ravel().tolist(), params)
        gmsh.model.mesh.addElementsByType(surface, 2, el[:len(tri)].tolist(), tags[tri].ravel().tolist())
        return True
    changed = False
    for i in np.flatnonzero(moved & movable).tolist():
        gmsh.model.mesh.setNode(int(tags[i]), x[i].tolist(), uv[i].tolist())
        changed = True
    if not np.array_equal(tri, tri0):
        gmsh.model.mesh.removeElements(2, surface)
        gmsh.model.mesh.addElementsByType(surface, 2, np.asarray(el_tags).tolist(), tags[tri].ravel().tolist())
        changed = True
    return changed


def _face_min_angle(surface: int) -> float:
    """The smallest triangle angle of one meshed gmsh surface (180 for a face without triangles)."""
    import gmsh

    from .generate import node_lookup

    _, tri = gmsh.model.mesh.getElementsByType(2, surface)
    tags, coords, _ = gmsh.model.mesh.getNodes(2, surface, includeBoundary=True)
    if not len(tri) or not len(tags):
        return 180.0
    lookup = node_lookup(tags)
    tri = np.asarray(tri, dtype=np.int64)
    if tri.max() >= len(lookup) or (lookup[tri] < 0).any():
        return 180.0
    return float(triangle_angles(np.asarray(coords, dtype=float).reshape(-1, 3), lookup[tri].reshape(-1, 3)).min())


def after_generate(ctx) -> None:
    """Hook (after the area-target pass): improve every meshed face (:func:`smooth_face`), worst smallest
    angle first, within the optimiser's budget (:data:`BUDGET_SHARE`, :data:`MIN_BUDGET`; on a loaded
    machine a large model gets part of the faces: the worst go first); the faces whose mesh changed land
    in ``ctx.smoothed``."""
    import time

    import gmsh

    opts = ctx.job.options.get("fidelity") or {}
    areas = np.asarray(opts.get("brep_areas", []), dtype=float)
    target = opts.get("surface_ald")
    face_of = ctx.emap.face_of_surface
    kept = []
    now = time.time()
    end = now + max(MIN_BUDGET, BUDGET_SHARE * (now - ctx.started))
    if ctx.job.deadline is not None:
        end = min(end, ctx.job.deadline)
    meshed = [s for s, outcome in sorted(ctx.outcomes.items()) if outcome.ok]
    worst = {s: _face_min_angle(s) for s in meshed}
    todo = [s for s in sorted(meshed, key=lambda s: worst[s]) if worst[s] < CLIMB_BELOW]
    size = {s: len(gmsh.model.mesh.getElementsByType(2, s)[0]) for s in todo}
    left = sum(size.values())
    for s in todo:  # worst smallest angle first; faces without a triangle worth moving are left alone
        now = time.time()
        if now > end:
            break  # out of the optimiser's time: the faces left keep gmsh's triangles
        share = max(FACE_SHARE, size[s] / left if left > 0 else 1.0)
        left -= size[s]
        f = face_of.get(s, s)
        area = float(areas[f - 1]) if 1 <= f <= len(areas) else 0.0
        if smooth_face(s, brep_area=area, target=target, deadline=now + share * (end - now)):
            kept.append(f)
            ctx.outcomes[s].triangles = len(gmsh.model.mesh.getElementsByType(2, s)[0])
    ctx.smoothed = kept
