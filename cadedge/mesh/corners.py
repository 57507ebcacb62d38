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


def _folds(p: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Per trial, whether one of its triangles of the corners ``p`` (trials, k, 3, 3) folds against its
    nodes' normals ``up`` (trials, k, 3, 3)."""
    rows = np.arange(3 * p.shape[0] * p.shape[1]).reshape(-1, 3)
    return folded(p.reshape(-1, 3), rows, reference_normals(up.reshape(-1, 3), rows)).reshape(p.shape[:2]).any(axis=1)


def split_corner_triangles(x: np.ndarray, tri: np.ndarray, movable: np.ndarray, fixed: set[tuple[int, int]],
                           project, *, below: float = SPLIT_BELOW, normals: NodeNormals | None = None
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Split the inner edge of each triangle under ``below`` degrees whose three nodes are not
    ``movable``, where that raises the smallest angle there (see the module doc). ``fixed`` holds the
    curve segments as sorted node pairs; ``project(points (k, 3), rows (k,))`` returns the points (each
    near node ``rows``) on the surface and their parametric coordinates (k, d). ``normals``: the nodes'
    oriented surface normals, against which no new triangle may fold (the new node's taken where it is
    placed; see :mod:`cadedge.mesh.folds`).

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
    touched = np.zeros(len(tri), dtype=bool)
    new_x: list[np.ndarray] = []
    new_uv: list[np.ndarray] = []
    replaced: list[tuple[int, np.ndarray, np.ndarray]] = []  # triangle row, its first and second halves
    for t in bad[np.argsort(ang[bad])].tolist():
        if touched[t]:
            continue
        best = None
        on_curves = sum((min(p, q), max(p, q)) in fixed for p, q in zip(tri[t].tolist(), np.roll(tri[t], -1).tolist()))
        slack = MIN_GAIN if on_curves >= 2 else 0.0
        for k in range(3):
            a, b = int(tri[t, k]), int(tri[t, (k + 1) % 3])
            key = (min(a, b), max(a, b))
            pair = edge_tris.get(key, [])
            if key in fixed or len(pair) != 2:
                continue
            u = pair[0] if pair[1] == t else pair[1]
            if touched[u]:
                continue
            old = min(ang[t], ang[u])
            c = int(tri[t, (k + 2) % 3])
            w = next(int(v) for v in tri[u] if v != a and v != b)
            mid = 0.5 * (x[a] + x[b])
            inward = x[w] - mid  # into the neighbouring triangle, within the face
            inward -= np.dot(inward, x[b] - x[a]) / np.dot(x[b] - x[a], x[b] - x[a]) * (x[b] - x[a])
            norm = np.linalg.norm(inward)
            if not norm > 0:
                continue
            length = np.linalg.norm(x[b] - x[a])
            trial = np.array([mid + s * length * inward / norm for s in OFFSETS])
            if slack == 0.0:  # no loss allowed now, none for smoothing to undo later: try more positions
                trial = np.vstack([trial, _LATTICE @ x[[a, b, c, w]]])
            near = np.array([a, b, c, w])  # each trial's projection starts from its nearest node's parameters
            on, uv = project(trial, near[np.argmin(((trial[:, None] - x[near][None]) ** 2).sum(axis=2), axis=1)])
            halves = []
            for row in (t, u):  # each triangle (.., a, .., b, ..) -> its a-half and its b-half, orientation kept
                r = tri[row]
                halves.append((np.where(r == b, -1, r), np.where(r == a, -1, r)))
            # the pair's normal (area-weighted): a triangle of three nearly collinear curve nodes has none
            # of its own to keep
            normal0 = _normal(x[[tri[t], tri[u]]]).sum(axis=0)
            quads = np.array([h for pair_ in halves for h in pair_])
            new = (quads == -1)[None, :, :, None]  # where the new node stands in the four triangles
            p = np.where(new, on[:, None, None, :], x[np.maximum(quads, 0)][None])  # (trials, 4, 3, 3)
            n = len(on)
            ok = np.all(_normal(p.reshape(-1, 3, 3)).reshape(n, 4, 3) @ normal0 > 0, axis=1)  # none turned over
            if normals is not None and ok.any():
                ups = np.where(new, normals.at(uv)[:, None, None, :], normals.up[np.maximum(quads, 0)][None])
                ok &= ~_folds(p, ups)
            q = min_angles(p.reshape(-1, 3), np.arange(12 * n).reshape(-1, 3)).reshape(n, 4).min(axis=1)
            q = np.where(ok, q, -np.inf)
            i = int(np.argmax(q))
            if q[i] > old + slack and (best is None or q[i] > best[0]):
                best = (float(q[i]), t, u, on[i], uv[i], halves)
        if best is None:
            continue
        _, t, u, pos, puv, halves = best
        node = len(x) + len(new_x)
        new_x.append(pos)
        new_uv.append(puv)
        for row, (first, second) in zip((t, u), halves):
            replaced.append((row, np.where(first == -1, node, first), np.where(second == -1, node, second)))
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
