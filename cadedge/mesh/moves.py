"""The face optimiser's moves on one face's triangles (see :mod:`cadedge.mesh.optimize`): edge swaps
(:func:`flip_edges`), a "smart" Laplacian (:func:`smooth_nodes`), a local search (:func:`climb_nodes`)
and the unfolding of triangles folded against the surface (:func:`untangle_nodes`).

Each works on plain arrays (coordinates, triangles as node indices, which nodes may move) and a
projection back onto the B-rep surface; nodes on curves and points never move.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from .. import kernels
from .folds import NodeNormals, _normals, folded, reference_normals
from .quality import cross, min_angles

#: Smoothing iterations per pass.
ITERATIONS = 4
#: Nodes with a triangle angle under this many degrees are moved to the best of a few trial positions
#: (40 stopped the planar faces of the cylinder-and-box models at 40-41 degrees, where gmsh alone gets 41;
#: 45 lifts them to 42-45 for about twice the optimiser's time, 50 adds nothing).
CLIMB_BELOW = 45.0
#: The trial positions' distances, as shares of the node's mean edge length.
STEPS = (0.03, 0.1, 0.25)
#: Edge-swap rounds per face and pass.
FLIP_ROUNDS = 10
#: An edge swap must keep each new triangle's normal within this many degrees of its nodes' surface
#: normals, or, across a ridge (where those disagree), of both old triangles' normals (see
#: :func:`_swap_keeps_shape`). Where two triangles bend sharply across their shared edge (a thin blade's
#: rounded edge, the surface turning nearly 180 degrees within a triangle or two) the diagonal carries
#: the shape: swapping it folded triangles against the surface (sharp_blade at 1e-2: up to 10 on a face,
#: 3 left in the final mesh), which the test against the sum of the old normals could not tell. A mesh
#: at ALD 1e-2 bends about 28 degrees between neighbours on a curved face.
FLIP_TURN = 45.0
#: An old triangle with an angle under this many degrees is a sliver whose normal tells nothing of the
#: surface: across a ridge a swap is judged by the other old triangle alone (see :func:`_swap_keeps_shape`).
SLIVER_NORMAL = 1.0
#: Rounds of :func:`untangle_nodes`; each moves at most one node per neighbourhood.
UNTANGLE_ROUNDS = 8
#: An unfolding move may leave the node's triangles no worse than their smallest angle before it or this
#: many degrees, the smaller: near a boundary that lies off its surface (LLNL boxed_sphere's cylinders,
#: edges up to 0.027 off) folds come from the boundary nodes, no interior move undoes them, and moves
#: taken for fewer folds alone left 0.2-degree slivers (27.7 degrees before, at 1e-3).
UNTANGLE_KEEP = 20.0
#: Rounds of undoing moves that made a triangle worse than before the pass (its nodes' neighbours moved
#: too), after which the pass is undone as a whole.
_UNDO_ROUNDS = 8


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


def _adjacency(tri: np.ndarray, n: int) -> tuple[sparse.csr_matrix, np.ndarray]:
    """The node adjacency of triangles ``tri`` over ``n`` nodes (0/1, symmetric) and each node's degree."""
    e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    adj = sparse.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    adj = ((adj + adj.T) > 0).astype(float)
    return adj, np.asarray(adj.sum(axis=1)).ravel()


def _rows(movable: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The movable nodes' indices, and for every node its row among them (-1 if it does not move): the
    rows of the parametric coordinates the moves return."""
    mov_idx = np.flatnonzero(movable)
    where = np.full(len(movable), -1)
    where[mov_idx] = np.arange(len(mov_idx))
    return mov_idx, where


def _turned(new: np.ndarray, old: np.ndarray, ref_new: np.ndarray | None = None,
            ref_old: np.ndarray | None = None) -> np.ndarray:
    """Triangles whose normals ``new`` (after a move) point against ``old`` (before it) or, given their
    reference directions after and before it (``ref_new``, ``ref_old``: the surface's normal, see
    :func:`cadedge.mesh.folds.reference_normals`), face against them where they did not. A move is
    checked against its triangles' normals before it, but many small turns, each under 90 degrees, add
    up: on a thin blade's rounded edge the local search folded triangles against the surface."""
    out = np.einsum("ij,ij->i", new, old) <= 0
    if ref_new is not None and ref_old is not None:
        out |= (np.einsum("ij,ij->i", new, ref_new) < 0) & ~(np.einsum("ij,ij->i", old, ref_old) < 0)
    return out


def _references(normals: NodeNormals | None, rows: np.ndarray, params: np.ndarray,
                tri: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]:
    """The nodes' normals with nodes ``rows`` moved to ``params``, and the triangles' reference directions
    before and after the move (:func:`cadedge.mesh.folds.reference_normals`); all None without
    ``normals``."""
    if normals is None:
        return None, None, None
    up1 = normals.moved(rows, params)
    return up1, reference_normals(normals.up, tri), reference_normals(up1, tri)


def smooth_nodes(x: np.ndarray, tri: np.ndarray, movable: np.ndarray, project, *, iterations: int = ITERATIONS,
                 normals: NodeNormals | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    """Smart-Laplacian smoothing of the ``movable`` nodes of the triangles ``tri`` (indices into ``x``).

    ``project(points (k, 3), rows (k,))`` returns the points (those of nodes ``rows``) moved onto the
    surface and their parametric coordinates (k, d). Returns the new coordinates and the parametric coordinates of the movable nodes (NaN rows for
    nodes that stayed; ``None`` if nothing moved). A move stays only if no triangle of the node flips (nor
    folds against the surface, given the nodes' ``normals``: see :func:`_turned`; they follow the moves)
    and the smallest angle of its triangles does not fall; moves
    that, with their neighbours', flip a triangle or bring it below the worst angle around it before the
    pass are undone.
    """
    x = np.array(x, dtype=float)
    n = len(x)
    mov = np.flatnonzero(movable)
    if not len(mov) or not len(tri):
        return x, None
    adj, deg = _adjacency(tri, n)
    params = None
    for _ in range(iterations):
        ang0 = min_angles(x, tri)
        nrm0 = _normals(x, tri)
        node0 = _node_min(ang0, tri, n)
        target = (adj @ x)[mov] / deg[mov, None]
        moved, uv = project(target, mov)
        cand = x.copy()
        cand[mov] = moved
        ang1 = min_angles(cand, tri)
        up1, ref0, ref1 = _references(normals, mov, uv, tri)
        flipped = _turned(_normals(cand, tri), nrm0, ref1, ref0)
        bad_node = _node_min(np.where(flipped, -1.0, ang1), tri, n)
        accept = np.zeros(n, dtype=bool)
        accept[mov] = (bad_node[mov] >= node0[mov]) & np.any(cand[mov] != x[mov], axis=1)
        floor = node0[tri].min(axis=1)  # a triangle may get worse, but not below its neighbourhood's worst
        for _round in range(_UNDO_ROUNDS):
            trial = np.where(accept[:, None], cand, x)
            ang_t = min_angles(trial, tri)
            ref_t = None if up1 is None else reference_normals(np.where(accept[:, None], up1, normals.up), tri)
            worse = (ang_t < floor) | _turned(_normals(trial, tri), nrm0, ref_t, ref0)
            if not worse.any():
                break
            accept[tri[worse].ravel()] = False
        else:
            accept[:] = False
        if not accept.any():
            break
        x[accept] = cand[accept]
        if up1 is not None:
            normals.up[accept] = up1[accept]
        if params is None:
            params = np.full((len(mov), uv.shape[1]), np.nan)
        take = accept[mov]
        params[take] = uv[take]
    return x, params


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=1), 1e-300)[:, None]


def _swap_keeps_shape(x: np.ndarray, old: list[np.ndarray], new: list[np.ndarray],
                      up: np.ndarray | None, old_min: list[np.ndarray]) -> np.ndarray:
    """Whether swapping the diagonal of the triangle pairs ``old`` into ``new`` keeps the surface's shape.

    With the nodes' oriented surface normals ``up`` (:mod:`cadedge.mesh.folds`): each new triangle's
    normal within :data:`FLIP_TURN` degrees of its nodes' normals, where those agree; where they do not
    (across a ridge), within :data:`FLIP_TURN` of both old triangles' normals (of the other alone where one
    is a sliver, :data:`SLIVER_NORMAL`; ``old_min``: the old triangles' smallest angles). Without ``up``, the
    new triangles turn less than 90 degrees from the sum of the old ones' normals (a sliver's normal can
    point anywhere about its long edge, so only a face with trusted normals gets the stricter test)."""
    normals_new = [_normals(x, b) for b in new]
    if up is None:
        ref = _normals(x, old[0]) + _normals(x, old[1])
        return (np.einsum("ij,ij->i", normals_new[0], ref) > 0) & (np.einsum("ij,ij->i", normals_new[1], ref) > 0)
    cos = np.cos(np.radians(FLIP_TURN))
    bend = np.ones(len(old[0]), dtype=bool)
    # a sliver's normal can point anywhere about its long edge: it does not judge the bend, its
    # neighbour's does (a triangle capping two segments of one edge at 179.7 degrees, 0.09 degrees, stayed
    # beside a B-rep vertex whose nodes' normals made the swap a ridge's)
    thin = [a < SLIVER_NORMAL for a in old_min]
    for a, skip in zip(old, [thin[0] & ~thin[1], thin[1] & ~thin[0]]):
        na = _unit(_normals(x, a))
        for nb in normals_new:
            bend &= skip | (np.einsum("ij,ij->i", na, _unit(nb)) > cos)
    ok = np.ones(len(old[0]), dtype=bool)
    ridge = np.zeros(len(old[0]), dtype=bool)
    for b, nb in zip(new, normals_new):
        ref = reference_normals(up, b)
        known = np.any(ref != 0.0, axis=1)
        ok &= ~known | (np.einsum("ij,ij->i", _unit(nb), _unit(ref)) > cos)
        ridge |= ~known
    return ok & (~ridge | bend)


def _in_sorted(keys: np.ndarray, query: np.ndarray) -> np.ndarray:
    """Whether each of ``query`` is among ``keys`` (sorted): ``np.isin`` without sorting ``keys`` again,
    which on a face of 500 000 triangles took 0.6 s a call, a fifth of the optimiser's time.

    >>> _in_sorted(np.array([2, 5, 9]), np.array([9, 1, 5, 10]))
    array([ True, False,  True, False])
    """
    if not len(keys):
        return np.zeros(len(query), dtype=bool)
    return keys[np.minimum(np.searchsorted(keys, query), len(keys) - 1)] == query


def _swappable(tri: np.ndarray, n: int, fixed_keys: np.ndarray) -> tuple[np.ndarray, ...]:
    """The edges of ``tri`` (over ``n`` nodes) held by exactly two triangles of one orientation and not in
    ``fixed_keys`` (``a * (n + 1) + b``, ``a < b``): their triangles ``t1 = (a, b, c)`` and ``t2 = (b, a, d)``
    as ``t1, t2, a, b, c, d``, and the sorted keys of all the edges. Swapping one makes ``(a, d, c)`` and
    ``(d, b, c)``."""
    a = tri.ravel()
    b = np.roll(tri, -1, axis=1).ravel()
    c = np.roll(tri, -2, axis=1).ravel()
    owner = np.repeat(np.arange(len(tri)), 3)
    key = np.minimum(a, b) * (n + 1) + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    ks = key[order]
    pair = np.flatnonzero(ks[1:] == ks[:-1])
    pair = pair[((pair + 2 >= len(ks)) | (ks[np.minimum(pair + 2, len(ks) - 1)] != ks[pair]))
                & ((pair == 0) | (ks[pair - 1] != ks[pair]))]  # edges with exactly two triangles
    h1, h2 = order[pair], order[pair + 1]
    keep = (a[h1] == b[h2]) & (b[h1] == a[h2]) & ~_in_sorted(fixed_keys, ks[pair])
    h1, h2 = h1[keep], h2[keep]
    return owner[h1], owner[h2], a[h1], b[h1], c[h1], c[h2], ks


def flip_folds(x: np.ndarray, tri: np.ndarray, fixed: set[tuple[int, int]], up: np.ndarray, *,
               rounds: int = UNTANGLE_ROUNDS) -> np.ndarray:
    """Swap the diagonal between a folded triangle (against its nodes' oriented unit surface normals
    ``up``, see :mod:`cadedge.mesh.folds`) and a neighbour wherever the two new triangles hold fewer folded
    ones than the two old; edges in ``fixed`` (the curve segments) never. Where moving nodes cannot
    (:func:`untangle_nodes`): near the pole of a half ellipsoid (gmsh's ellipses.brep) Frontal-Delaunay
    leaves triangles turned over in its parameters among neighbours spread round the pole, each of whose
    nodes would have to move a whole triangle's length; four swaps undo its four folds. The new triangles
    may be thin: the face optimiser's later moves lift them and never fold one. Returns the new triangles
    (same count)."""
    tri = np.array(tri, dtype=np.int64)
    fixed_keys = np.array(sorted(a * (len(x) + 1) + b for a, b in fixed), dtype=np.int64)
    for _ in range(rounds):
        bad = folded(x, tri, reference_normals(up, tri))
        if not bad.any():
            break
        t1, t2, pa, pb, pc, pd, ks = _swappable(tri, len(x), fixed_keys)
        near = (bad[t1] | bad[t2]) & (pc != pd)
        t1, t2, pa, pb, pc, pd = t1[near], t2[near], pa[near], pb[near], pc[near], pd[near]
        new1 = np.column_stack([pa, pd, pc])
        new2 = np.column_stack([pd, pb, pc])
        gain = (bad[t1].astype(int) + bad[t2] - folded(x, new1, reference_normals(up, new1))
                - folded(x, new2, reference_normals(up, new2)))
        new_key = np.minimum(pc, pd) * (len(x) + 1) + np.maximum(pc, pd)
        ok = (gain > 0) & ~_in_sorted(ks, new_key)
        taken, made = np.zeros(len(tri), dtype=bool), set()
        for k in np.flatnonzero(ok)[np.argsort(-gain[ok], kind="stable")]:  # a few: the folds' edges
            if not (taken[t1[k]] or taken[t2[k]] or new_key[k] in made):
                tri[t1[k]], tri[t2[k]] = new1[k], new2[k]
                taken[[t1[k], t2[k]]] = True
                made.add(new_key[k])
        if not taken.any():
            break
    return tri


def flip_edges(x: np.ndarray, tri: np.ndarray, fixed: set[tuple[int, int]], *,
               rounds: int = FLIP_ROUNDS, up: np.ndarray | None = None) -> np.ndarray:
    """Swap the diagonal of pairs of triangles wherever that raises the smaller of their two smallest
    angles; edges in ``fixed`` (sorted node-index pairs: the curve segments) are never swapped, nor an edge
    whose new triangles would not keep the surface's shape (:func:`_swap_keeps_shape`, with the nodes'
    oriented surface normals ``up`` if given) or whose new diagonal is already an edge. Each round swaps, for every triangle, at most its
    best edge. Returns the new triangles (same count and orientation)."""
    tri = np.array(tri, dtype=np.int64)
    fixed_keys = np.array(sorted(a * (len(x) + 1) + b for a, b in fixed), dtype=np.int64)
    for _ in range(rounds):
        t1, t2, pa, pb, pc, pd, ks = _swappable(tri, len(x), fixed_keys)
        if not len(t1):
            break
        new1 = np.column_stack([pa, pd, pc])
        new2 = np.column_stack([pd, pb, pc])
        old_min = [min_angles(x, tri[t1]), min_angles(x, tri[t2])]
        before = np.minimum(*old_min)
        after = np.minimum(min_angles(x, new1), min_angles(x, new2))
        new_key = np.minimum(pc, pd) * (len(x) + 1) + np.maximum(pc, pd)
        ok = (after - before > 1e-6) & (pc != pd)
        ok[ok] = ~_in_sorted(ks, new_key[ok])  # the new diagonal already joins c and d (a fan at an apex): a flip
        # would stack a second pair of triangles on the existing ones
        ok[ok] = _swap_keeps_shape(x, [tri[t1[ok]], tri[t2[ok]]], [new1[ok], new2[ok]], up,  # only swaps that gain
                                   [a[ok] for a in old_min])
        gain = np.where(ok, after - before, 0.0)
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


def climb_nodes(x: np.ndarray, tri: np.ndarray, movable: np.ndarray, project, *,
                iterations: int = ITERATIONS, below: float = CLIMB_BELOW,
                normals: NodeNormals | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    """Move movable nodes whose triangles have an angle under ``below`` degrees to the best of a few trial
    positions around them (8 directions in their tangent plane, :data:`STEPS` away), the one that raises
    the smallest angle of their triangles most. Of neighbours that can both improve, only the worse off
    moves in one iteration, so each move is judged exactly (up to the projection back onto the surface,
    checked after it, with no triangle flipped or, given the nodes' ``normals``, folded against the
    surface; see :func:`smooth_nodes`). Returns the coordinates and the
    parametric coordinates of the movable nodes as :func:`smooth_nodes` does."""
    x = np.array(x, dtype=float)
    n = len(x)
    mov_idx, where = _rows(movable)
    if not len(mov_idx) or not len(tri):
        return x, None
    node = tri.ravel()
    slot = np.tile(np.arange(3), len(tri))
    t = np.repeat(np.arange(len(tri)), 3)
    sel = movable[node]
    node, slot, t = node[sel], slot[sel], t[sel]
    e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    phi = np.arange(8) * np.pi / 4
    cosines, sines = np.array([np.cos(a) for a in phi]), np.array([np.sin(a) for a in phi])
    params = None
    for _ in range(iterations):
        ang = min_angles(x, tri)
        node0 = _node_min(ang, tri, n)
        want = movable & (node0 < below)
        if not want.any():
            break
        go = want
        nrm_x = _normals(x, tri)
        tn = np.repeat(nrm_x, 3, axis=0)
        nrm = np.column_stack([np.bincount(tri.ravel(), weights=tn[:, k], minlength=n) for k in range(3)])
        seg = np.repeat(np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1), 2)
        h = np.bincount(e.ravel(), weights=seg, minlength=n) / np.maximum(np.bincount(e.ravel(), minlength=n), 1)
        nn = nrm / np.maximum(np.linalg.norm(nrm, axis=1), 1e-300)[:, None]
        axis = np.where(np.abs(nn[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
        u = cross(nn, axis)
        u /= np.maximum(np.linalg.norm(u, axis=1), 1e-300)[:, None]
        v = cross(nn, u)
        best = node0.copy()
        best_pos = x.copy()
        sub = go[node]
        # each wanted node at each trial position: its worst angle there, the best kept (one compiled call)
        kernels.climb_trials(x, tri, node[sub], slot[sub], t[sub], u, v, h, np.asarray(STEPS, dtype=float),
                             cosines, sines, best, best_pos)
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
        after = min_angles(cand, tri)
        up1, ref0, ref1 = _references(normals, moved, puv, tri)
        flipped = _turned(_normals(cand, tri), nrm_x, ref1, ref0)
        got = _node_min(np.where(flipped, -1.0, after), tri, n)
        ok = moved[got[moved] > node0[moved]]
        if not len(ok):
            break
        x[ok] = cand[ok]
        if up1 is not None:
            normals.up[ok] = up1[ok]
        if params is None:
            params = np.full((len(mov_idx), puv.shape[1]), np.nan)
        params[where[ok]] = puv[np.searchsorted(moved, ok)]
    return x, params


def around(tri: np.ndarray, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The part of a face's mesh that moving the ``active`` nodes can change, with all that judges it:
    the triangles with a node within one ring of an active node, as ``(nodes, triangles)`` (the nodes'
    indices into the face's, ascending, and the triangles renumbered into them). Every move and check
    of :func:`smooth_nodes` and :func:`climb_nodes` reads only these (each active node's triangles,
    and every triangle of their nodes), so running them on this part gives the same result in a
    fraction of the time: the active nodes are those near bad triangles, a small share of a face."""
    ring = active.copy()
    ring[tri[active[tri].any(axis=1)].ravel()] = True
    local = tri[ring[tri].any(axis=1)]
    nodes, inverse = np.unique(local, return_inverse=True)
    return nodes, inverse.reshape(local.shape)


def _near_bad(x: np.ndarray, tri: np.ndarray, movable: np.ndarray, below: float = CLIMB_BELOW) -> np.ndarray:
    """The movable nodes within two rings of a triangle under ``below`` degrees: the only ones worth
    moving (and projecting onto the surface, the costly part on B-spline faces)."""
    near = np.zeros(len(x), dtype=bool)
    near[tri[min_angles(x, tri) < below].ravel()] = True
    for _ in range(2):
        near[tri[near[tri].any(axis=1)].ravel()] = True
    return near & movable


def untangle_nodes(x: np.ndarray, tri: np.ndarray, movable: np.ndarray, project, ref: np.ndarray, *,
                   rounds: int = UNTANGLE_ROUNDS) -> tuple[np.ndarray, np.ndarray | None]:
    """Move movable nodes of folded triangles (facing against ``ref``, see :mod:`cadedge.mesh.folds`) to
    the mean of their neighbours, projected onto the surface, where that leaves fewer folded triangles
    around them and keeps their angles (:data:`UNTANGLE_KEEP`): gmsh folded one of twisted_blade's
    blade-face triangles at 1e-2, a node beyond the ring of its neighbours. Nodes moved in one round share no triangle (the node with most folded triangles
    first), so each move is judged exactly; a node refused is tried again once a neighbour moved.
    Returns the coordinates and the parametric coordinates of the movable nodes as :func:`smooth_nodes`
    does."""
    x = np.array(x, dtype=float)
    n = len(x)
    mov_idx, where = _rows(movable)
    if not len(mov_idx) or not len(tri):
        return x, None
    e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    adj, deg = _adjacency(tri, n)
    deg = np.maximum(deg, 1.0)
    params = None
    refused = np.zeros(n, dtype=bool)
    for _ in range(rounds):
        count = np.bincount(tri[folded(x, tri, ref)].ravel(), minlength=n)
        want = movable & (count > 0) & ~refused
        if not want.any():
            break
        rank = count + np.arange(n) / (n + 1.0)  # most folded triangles first, ties by index
        both = want[e[:, 0]] & want[e[:, 1]]
        i, j = e[both, 0], e[both, 1]
        go = want.copy()
        go[np.where(rank[i] < rank[j], i, j)] = False
        nodes = np.flatnonzero(go)
        px, puv = project((adj @ x)[nodes] / deg[nodes, None], nodes)
        trial = x.copy()
        trial[nodes] = px
        after = np.bincount(tri[folded(trial, tri, ref)].ravel(), minlength=n)
        worst = _node_min(min_angles(trial, tri), tri, n)
        ok = (after[nodes] < count[nodes]) & (worst[nodes] >= np.minimum(_node_min(min_angles(x, tri), tri, n)[nodes],
                                                                          UNTANGLE_KEEP))
        refused[nodes[~ok]] = True
        moved = nodes[ok]
        if not len(moved):
            continue
        x[moved] = px[ok]
        refused[tri[np.isin(tri, moved).any(axis=1)].ravel()] = False
        if params is None:
            params = np.full((len(mov_idx), puv.shape[1]), np.nan)
        params[where[moved]] = puv[ok]
    return x, params
