"""Edge splits: one interior node more where a triangle has all three nodes on the face's boundary.

At a 90-degree face corner between boundary segments of 2.5 and 2.0, gmsh closes the corner with one
triangle whose three nodes lie on the boundary (38.7 degrees). Nothing of it can move: every boundary node
is an edge grid node, shared with the neighbouring face. Splitting the triangle's inner edge (the one that
is not a curve segment) at a new interior node cuts the corner in two and gives the node freedom: placed
well, about 43 degrees there; gmsh alone, with near-uniform sizes, gets 41. The same holds for any
all-boundary triangle with an inner edge (a face's narrow end, a fan at a sharp corner).

The split is made where the smallest angle of the four new triangles is not much below that of the two
triangles they replace (:data:`MIN_GAIN`: the smoothing that follows settles them); the node is placed
at the best of a few positions along the inner edge's normal in the face, each projected onto the
surface (from the parameters of the node nearest it) first. Nodes on curves never move; the new node is interior,
so the face stays conforming with its neighbours. The caller keeps the result only if the face's smallest
angle rose (see :func:`cadedge.mesh.optimize.smooth_face`).
"""

from __future__ import annotations

import numpy as np

from .collapse import _normal
from .folds import NodeNormals, folded, reference_normals
from .quality import min_angles

#: All-boundary triangles under this many degrees are tried.
SPLIT_BELOW = 42.0
#: A split may lower the smallest angle there by up to this many degrees: its neighbours are not yet
#: smoothed (as for the collapses: :data:`cadedge.mesh.collapse.MIN_GAIN`). A cube face's corner
#: triangle (2.5 by 2.0, 38.7 degrees) whose neighbour's third node lies near the corner gives 28 degrees
#: right after the split and 42.3 once smoothed; -8 left it unsplit.
MIN_GAIN = -15.0
#: That slack is for a corner triangle (two of its sides on curves). A triangle with one side on a curve
#: and two across the face (a strip between two curves, filled without interior nodes: what
#: :mod:`cadedge.mesh.collapse` makes of one where the strip is narrower than its segments) is split
#: only where that lowers nothing: split with the slack, sphere_box's spherical face at 1e-2 fell from
#: 26.9 to 13.6 degrees, beyond what smoothing undid.
#: Trial positions of the new node: the inner edge's midpoint moved into the neighbouring triangle by
#: these shares of the edge's length.
OFFSETS = (0.0, 0.1, 0.2, 0.3, 0.4)
#: More trial positions where the split may lower nothing: weighted means of the two triangles' four
#: nodes (weights 1-3 each). twisted_blade's trailing edge at 1e-2 (a 21.4-degree triangle between two
#: all-boundary ones): 25.2 degrees.
_LATTICE = np.array([w for w in np.ndindex(3, 3, 3, 3)], dtype=float) + 1.0
_LATTICE /= _LATTICE.sum(axis=1, keepdims=True)
#: Trial triangles (four per trial position) judged in one batch: the candidates are judged together, a
#: block of them at a time, and only the trials that beat their candidate's floor are checked for
#: turning over or folding. gmsh's SlenderSurface.brep, a strip 0.0004 wide filled with 26 000
#: all-boundary triangles once its edges are cut to its width, took 63 s judged one by one, 17 s now:
#: the same mesh.
_BATCH = 40_000


def _folds(p: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Per trial, whether one of its triangles of the corners ``p`` (trials, k, 3, 3) folds against its
    nodes' normals ``up`` (trials, k, 3, 3)."""
    rows = np.arange(3 * p.shape[0] * p.shape[1]).reshape(-1, 3)
    return folded(p.reshape(-1, 3), rows, reference_normals(up.reshape(-1, 3), rows)).reshape(p.shape[:2]).any(axis=1)


def _judge(x: np.ndarray, tri: np.ndarray, cand: np.ndarray, floor: np.ndarray, lattice: bool, project,
           normals: NodeNormals | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The best split of each candidate (rows of ``t, u, a, b, c, w``: triangle ``t`` and its neighbour
    ``u`` across the inner edge ``a``-``b``, their third nodes ``c`` and ``w``): the smallest angle of its
    four triangles at the best trial position, that position on the surface and its parameters; ``-inf``
    where no position beats the candidate's ``floor`` without turning a triangle over or folding it (those
    are checked only for positions that beat it)."""
    t, u, a, b, c, w = cand.T
    mid = 0.5 * (x[a] + x[b])
    ab = x[b] - x[a]
    inward = x[w] - mid  # into the neighbouring triangle, within the face
    inward -= np.einsum("ij,ij->i", inward, ab)[:, None] / np.einsum("ij,ij->i", ab, ab)[:, None] * ab
    norm = np.linalg.norm(inward, axis=1)
    length = np.linalg.norm(ab, axis=1)
    step = np.where(norm > 0, length / np.where(norm > 0, norm, 1.0), 0.0)[:, None] * inward
    trial = mid[:, None] + np.asarray(OFFSETS)[None, :, None] * step[:, None]
    near = np.stack([a, b, c, w], axis=1)
    if lattice:  # no loss allowed now, none for smoothing to undo later: try more positions
        trial = np.concatenate([trial, _LATTICE @ x[near]], axis=1)
    n, k = trial.shape[:2]
    # each trial's projection starts from its nearest node's parameters
    rows = near[np.arange(n)[:, None], np.argmin(((trial[:, :, None] - x[near][:, None]) ** 2).sum(axis=3), axis=2)]
    on, uv = project(trial.reshape(-1, 3), rows.ravel())
    on, uv = on.reshape(n, k, 3), uv.reshape(n, k, -1)
    # each triangle (.., a, .., b, ..) -> its a-half and its b-half, orientation kept; -1 is the new node
    pair = tri[np.stack([t, u], axis=1)]  # (n, 2, 3)
    quads = np.stack([np.where(pair == b[:, None, None], -1, pair), np.where(pair == a[:, None, None], -1, pair)],
                     axis=2).reshape(n, 4, 3)
    # the four triangles of every trial as rows of x and the trial positions after it
    at = np.where(quads[:, None] == -1, len(x) + np.arange(n * k).reshape(n, k, 1, 1), quads[:, None])
    points = np.vstack([x, on.reshape(-1, 3)])
    q = min_angles(points, at.reshape(-1, 3)).reshape(n, k, 4).min(axis=2)
    live = np.flatnonzero((q > floor[:, None]) & (norm > 0)[:, None])  # flat (candidate, trial) indices
    row = live // k
    # the pair's normal (area-weighted): a triangle of three nearly collinear curve nodes has none of its own
    normal0 = _normal(x[pair.reshape(-1, 3)]).reshape(n, 2, 3).sum(axis=1)[row]
    pl = points[at.reshape(n * k, 4, 3)[live]]  # (live, 4, 3, 3)
    ok = np.all(np.einsum("mjd,md->mj", _normal(pl.reshape(-1, 3, 3)).reshape(-1, 4, 3), normal0) > 0, axis=1)
    if normals is not None and ok.any():
        ups = np.where((quads[row] == -1)[..., None], normals.at(uv.reshape(n * k, -1)[live])[:, None, None, :],
                       normals.up[np.maximum(quads[row], 0)])
        ok &= ~_folds(pl, ups)
    judged = np.full(n * k, -np.inf)
    judged[live[ok]] = q.ravel()[live[ok]]
    i = np.argmax(judged.reshape(n, k), axis=1)
    each = np.arange(n)
    return judged.reshape(n, k)[each, i], on[each, i], uv[each, i]


def split_corner_triangles(x: np.ndarray, tri: np.ndarray, movable: np.ndarray, fixed: set[tuple[int, int]],
                           project, *, below: float = SPLIT_BELOW, normals: NodeNormals | None = None
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Split the inner edge of each triangle under ``below`` degrees whose three nodes are not
    ``movable``, where that raises the smallest angle there (see the module doc). ``fixed`` holds the
    curve segments as sorted node pairs; ``project(points (k, 3), rows (k,))`` returns the points (each
    near node ``rows``) on the surface and their parametric coordinates (k, d). ``normals``: the nodes'
    oriented surface normals, against which no new triangle may fold (the new node's taken where it is
    placed; see :mod:`cadedge.mesh.folds`). Every candidate split is judged first, in batches
    (:func:`_judge`); then the triangles are taken worst first, each split at its best inner edge whose
    neighbour no earlier split took.

    Returns ``(x, tri, movable, params)``: coordinates with the new nodes appended, the triangles
    (orientation kept), the movable mask extended (new nodes are movable), and the parametric coordinates
    of the new nodes ((m, d) for the m appended rows, (0, 0) when nothing was split).
    """
    x = np.asarray(x, dtype=float)
    tri = np.array(tri, dtype=np.int64)
    movable = np.asarray(movable, dtype=bool)
    none = (x, tri, movable, np.zeros((0, 0)))
    if not len(tri):
        return none
    ang = min_angles(x, tri)
    bad = np.flatnonzero((ang < below) & ~movable[tri].any(axis=1))
    if not len(bad):
        return none
    edge_tris: dict[tuple[int, int], list[int]] = {}
    for t, (a, b, c) in enumerate(tri.tolist()):
        for p, q in ((a, b), (b, c), (c, a)):
            edge_tris.setdefault((min(p, q), max(p, q)), []).append(t)
    order = bad[np.argsort(ang[bad])].tolist()
    cand, slack = [], []  # per candidate: t, u, a, b, c, w; the loss its split may cause
    for t in order:
        nodes = tri[t].tolist()
        on_curves = sum((min(p, q), max(p, q)) in fixed for p, q in zip(nodes, nodes[1:] + nodes[:1]))
        for k in range(3):
            a, b = nodes[k], nodes[(k + 1) % 3]
            pair = edge_tris.get((min(a, b), max(a, b)), [])
            if (min(a, b), max(a, b)) in fixed or len(pair) != 2:
                continue
            u = pair[0] if pair[1] == t else pair[1]
            cand.append((t, u, a, b, nodes[(k + 2) % 3], next(int(v) for v in tri[u] if v != a and v != b)))
            slack.append(MIN_GAIN if on_curves >= 2 else 0.0)
    if not cand:
        return none
    cand, slack = np.array(cand, dtype=np.int64), np.array(slack)
    floor = np.minimum(ang[cand[:, 0]], ang[cand[:, 1]]) + slack  # what a split must beat
    q = np.full(len(cand), -np.inf)
    pos = np.zeros((len(cand), 3))
    uvs: np.ndarray | None = None
    for lattice in (False, True):
        group = np.flatnonzero((slack == 0.0) == lattice)
        block = max(1, _BATCH // (4 * (len(OFFSETS) + (len(_LATTICE) if lattice else 0))))
        for s in range(0, len(group), block):
            g = group[s:s + block]
            q[g], pos[g], uv = _judge(x, tri, cand[g], floor[g], lattice, project, normals)
            uvs = np.zeros((len(cand), uv.shape[1])) if uvs is None else uvs
            uvs[g] = uv
    touched = np.zeros(len(tri), dtype=bool)
    new_x: list[np.ndarray] = []
    new_uv: list[np.ndarray] = []
    replaced: list[tuple[int, np.ndarray, np.ndarray]] = []  # triangle row, its first and second halves
    mine: dict[int, list[int]] = {}
    for i, t in enumerate(cand[:, 0].tolist()):
        mine.setdefault(t, []).append(i)
    for t in order:
        if touched[t] or t not in mine:
            continue
        best = None
        for i in mine[t]:
            u = int(cand[i, 1])
            if touched[u]:
                continue
            if q[i] > floor[i] and (best is None or q[i] > q[best]):
                best = i
        if best is None:
            continue
        _, u, a, b, _, _ = cand[best].tolist()
        node = len(x) + len(new_x)
        new_x.append(pos[best])
        new_uv.append(uvs[best])
        for row in (t, u):  # each triangle (.., a, .., b, ..) -> its a-half and its b-half, orientation kept
            r = tri[row]
            replaced.append((row, np.where(r == b, node, r), np.where(r == a, node, r)))
        touched[[t, u]] = True
    if not new_x:
        return none
    out = tri.copy()
    extra = []
    for row, first, second in replaced:
        out[row] = first
        extra.append(second)
    x = np.vstack([x, np.array(new_x)])
    movable = np.concatenate([movable, np.ones(len(new_x), dtype=bool)])
    return x, np.vstack([out, np.array(extra)]), movable, np.array(new_uv)
