"""Inside the gmsh job: a curved face whose mesh falls short of its B-rep area gets edges split on its surface.

gmsh evaluates a face's sizes only at the points it tries, so a ridge narrower than the triangles around
it can lie between them all. twisted_blade (``scripts/hard_models.py``) at ``--ald 1e-2``: its lofted
side's trailing edge has a radius of about 0.013 mm, and triangles of 0.5-1.4 mm spanned it in both of
gmsh's algorithms and at finer sizes; the face stayed 1.16e-2 short of its area. An edge split at the
surface point of its parametric middle adds back the area its chord cut off. Each round the triangles
that gain most from a split of one of their edges are taken, until their gains make up the shortfall
down to :data:`AIM` of the target, and each is refined along its longest-edge path (Rivara: the edge
split is the longest of both its triangles, which keeps their angles at least half of what they were);
where that path ends on a curve, the triangle's own best edge is split. No diagonal is swapped here:
swaps that raised angles took the new nodes off the ridge again (twisted_blade: 14.6 degrees and the
face back over its target after the optimiser), so the optimiser, which keeps the face within its
target, does that. Only interior edges are split: the curves' nodes stay, so neighbours stay conforming.
"""

from __future__ import annotations

import numpy as np

from .areas import triangle_areas
from .folds import folded, normals_at, orientation, reference_normals

#: Edges are split until the face's deficit is at most this share of its target, which leaves the face
#: optimiser room to move nodes (twisted_blade at 1e-2: 25.2 degrees at 0.2 and 0.5, 22.2 at 0.3, 25.2
#: with its blade face named at 1.22e-2 before).
AIM = 0.2
#: At most this many sets of splits per face.
ROUNDS = 12
#: A face held at a size floor that the splits at middles leave over its target is split again from its
#: mesh as it was, each edge where its split adds the most area (``ridge=True``): at most this many sets
#: of splits, each point searched within :data:`SPAN` of its edge's middle (in shares of the edge) by
#: :data:`SEARCH` golden-section steps (each keeps 0.618 of the bracket: 14 leave 0.2% of the edge).
#: razor_wing (a wing 0.12 mm thick over a 20 mm chord) at 1e-3: 3.1e-2 -> 2.8e-4 with 2.2x its triangles,
#: where the middles reached 7.5e-3 in 12 sets, and 3.0e-4 in 40 with 2.7x but a smallest angle of 0.8
#: degrees against 3.4. The middles come first: on twisted_blade at 1e-2 the searched points left 14.2
#: degrees against 25.2.
RIDGE_ROUNDS = 40
SPAN = 0.25
SEARCH = 14
#: A face may grow to at most this many times its triangles; past it the face keeps its mesh.
GROWTH = 3.0
#: A surface point farther than this many times its edge's length from the edge's middle is taken for a
#: parametric middle on the wrong side of a seam: the middle is projected instead.
FAR = 1.0


def _edges(tri: np.ndarray, n: int, fixed_keys: np.ndarray):
    """The face's edges: each triangle's three edge ids (m, 3; edge ``j`` runs from node ``j`` to node
    ``j + 1``), and per edge its nodes ``a -> b`` as its first triangle ``t1`` runs it, the nodes ``c``
    (in ``t1``) and ``d`` (in ``t2``) opposite it, and ``t2`` (-1 on a curve or the face's border:
    such edges are never split)."""
    a, b, c = tri.ravel(), np.roll(tri, -1, axis=1).ravel(), np.roll(tri, -2, axis=1).ravel()
    key = np.minimum(a, b) * (n + 1) + np.maximum(a, b)
    keys, first, eid, count = np.unique(key, return_index=True, return_inverse=True, return_counts=True)
    owner = np.repeat(np.arange(len(tri)), 3)
    second = np.full(len(keys), -1, dtype=np.int64)
    later = np.ones(len(key), dtype=bool)
    later[first] = False
    second[eid[later]] = np.flatnonzero(later)
    t2 = np.where((count == 2) & ~np.isin(keys, fixed_keys) & (second >= 0), owner[np.maximum(second, 0)], -1)
    t2[t2 >= 0] = np.where(a[second[t2 >= 0]] == b[first[t2 >= 0]], t2[t2 >= 0], -1)  # opposite ways
    d = np.where(t2 >= 0, c[np.maximum(second, 0)], -1)
    return eid.reshape(-1, 3), owner[first], t2, a[first], b[first], c[first], d


def _ends(longest: np.ndarray, t1: np.ndarray, t2: np.ndarray) -> np.ndarray:
    """Each triangle's end of its longest-edge path (Rivara): the triangle across its longest edge, and
    so on, until the longest edge is also the longest of the triangle across it (or is never split).
    Splitting that edge, which is the longest of both its triangles, keeps their angles at least half of
    what they were; the starting triangle is reached in later rounds."""
    e = longest
    other = np.where(t1[e] == np.arange(len(e)), t2[e], t1[e])
    step = np.where((other >= 0) & (longest[np.maximum(other, 0)] != e), other, np.arange(len(e)))
    for _ in range(int(np.ceil(np.log2(max(len(e), 2)))) + 1):
        step = step[step]
    return step


def _apart(edges: np.ndarray, gain: np.ndarray, t1: np.ndarray, t2: np.ndarray, n_tri: int) -> np.ndarray:
    """Of ``edges``, those that gain the most of the given edges in both their triangles: no two share a
    triangle (two splits of one triangle in one round would overwrite it); the rest wait a round."""
    rank = np.empty(len(edges), dtype=np.int64)
    rank[np.lexsort((edges, gain[edges]))] = np.arange(len(edges))
    top = np.full(n_tri, -1, dtype=np.int64)
    np.maximum.at(top, t1[edges], rank)
    np.maximum.at(top, t2[edges], rank)
    return edges[(top[t1[edges]] == rank) & (top[t2[edges]] == rank)]


def _periods(surface: int) -> tuple[np.ndarray, np.ndarray]:
    """The parametric range's low ends (2,) and, per direction, its length where the surface closes up
    across it (its two ends give the same points: a seam) and ``inf`` where it does not."""
    import gmsh

    low, high = np.asarray(gmsh.model.getParametrizationBounds(2, surface), dtype=float)
    span = np.full(2, np.inf)
    for k in range(2):
        if not np.isfinite(high[k] - low[k]):
            continue
        across = np.linspace(low[1 - k], high[1 - k], 7)
        ends = [np.insert(across[:, None], k, end, axis=1) for end in (low[k], high[k])]
        p, q = (np.asarray(gmsh.model.getValue(2, surface, e.ravel().tolist()), dtype=float).reshape(-1, 3)
                for e in ends)
        size = float(np.ptp(np.vstack([p, q]), axis=0).max())
        if np.linalg.norm(p - q, axis=1).max() <= 1e-7 * max(size, 1e-300):
            span[k] = high[k] - low[k]
    return low, span


def _short_way(surface: int, uv: np.ndarray, a: np.ndarray, b: np.ndarray):
    """Edges ``a``-``b``'s parametric segments: their starts (k, 2), their steps to their ends (k, 2),
    taken the short way round a seam (:func:`_periods`) where the ends lie over half the period apart
    (the seam's nodes carry one end of the range), and a function that moves parameters along them back
    into the range."""
    low, span = _periods(surface)
    period = np.where(np.isfinite(span), span, 0.0)
    step = uv[b] - uv[a]
    step = step - np.where(np.abs(step) > 0.5 * span, np.sign(step) * period, 0.0)

    def inside(q: np.ndarray) -> np.ndarray:
        return np.where(q < low, q + period, np.where(q > low + span, q - period, q))

    return uv[a], step, inside


def _seam_middles(surface: int, uv: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The parametric middles (k, 2) of edges ``a``-``b``, the short way round a seam
    (:func:`_short_way`; a wing's lofted side: its middles taken from the other end of the range missed
    the hooked trailing edge beside the seam, and the face stayed 1.3e-2 short at 1e-2)."""
    start, step, inside = _short_way(surface, uv, a, b)
    return inside(start + 0.5 * step)


def _surface_middles(surface: int, x: np.ndarray, uv: np.ndarray, a: np.ndarray, b: np.ndarray):
    """The surface points (k, 3) and parameters (k, 2) of edges ``a``-``b``: at their parametric middles
    (:func:`_seam_middles`), or where one is unknown or lands far off (a seam the surface does not repeat
    across), the surface point nearest the chord's middle; and whether each is the parametric middle."""
    import gmsh

    mid = 0.5 * (x[a] + x[b])
    length = np.linalg.norm(x[a] - x[b], axis=1)
    par = _seam_middles(surface, uv, a, b)
    p = np.full_like(mid, np.nan)
    known = ~np.isnan(par).any(axis=1)
    if known.any():
        p[known] = np.asarray(gmsh.model.getValue(2, surface, par[known].ravel().tolist()), dtype=float).reshape(-1, 3)
    far = ~known | ~(np.linalg.norm(p - mid, axis=1) <= FAR * length)
    if far.any():
        got, got_uv = gmsh.model.getClosestPoint(2, surface, mid[far].ravel().tolist())
        p[far] = np.asarray(got, dtype=float).reshape(-1, 3)
        par[far] = np.asarray(got_uv, dtype=float).reshape(-1, 2)
    return p, par, ~far


def _gains(xs: np.ndarray, x: np.ndarray, tri: np.ndarray, new: list[np.ndarray], t1: np.ndarray,
           t2: np.ndarray) -> np.ndarray:
    """Area each edge's split adds: its four new triangles (``new``, rows of ``xs``) less its two (of ``x``)."""
    return sum(triangle_areas(xs, t) for t in new) - triangle_areas(x, tri[t1]) - triangle_areas(x, tri[t2])


def _quads(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, rows: np.ndarray) -> list[np.ndarray]:
    """The four triangles that split edges ``a``-``b`` at new nodes ``rows`` make (``c``, ``d`` opposite)."""
    return [np.column_stack(t) for t in ((a, rows, c), (rows, b, c), (b, rows, d), (rows, a, d))]


def _on_ridge(surface: int, x: np.ndarray, tri: np.ndarray, uv: np.ndarray, edges: tuple
              ) -> tuple[np.ndarray, np.ndarray]:
    """The surface points (k, 3) and parameters (k, 2) on the parametric segments of ``edges`` (a, b, c,
    d, t1, t2; the short way round a seam), within :data:`SPAN` of their middles, where their splits add
    the most area (golden-section search: the edges' version of the arc-length split). Where an edge
    crosses a ridge narrower than itself that is on the ridge, which its middle misses by up to half."""
    import gmsh

    a, b, c, d, t1, t2 = edges
    new = _quads(a, b, c, d, len(x) + np.arange(len(a)))
    start, step, inside = _short_way(surface, uv, a, b)

    def at(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        q = inside(start + t[:, None] * step)
        pts = np.asarray(gmsh.model.getValue(2, surface, q.ravel().tolist()), dtype=float).reshape(-1, 3)
        return pts, q, _gains(np.vstack([x, pts]), x, tri, new, t1, t2)

    lo, hi = np.full(len(a), 0.5 - SPAN), np.full(len(a), 0.5 + SPAN)
    golden = 0.5 * (np.sqrt(5.0) - 1.0)
    t_l, t_r = hi - golden * (hi - lo), lo + golden * (hi - lo)
    g_l, g_r = at(t_l)[2], at(t_r)[2]
    for _ in range(SEARCH):
        right = g_r > g_l  # the largest gain lies in [t_l, hi]
        lo, hi = np.where(right, t_l, lo), np.where(right, hi, t_r)
        t_l, t_r = np.where(right, t_r, hi - golden * (hi - lo)), np.where(right, lo + golden * (hi - lo), t_l)
        g_new = at(np.where(right, t_r, t_l))[2]
        g_l, g_r = np.where(right, g_r, g_new), np.where(right, g_new, g_l)
    pts, q, _ = at(0.5 * (lo + hi))
    return pts, q


def _to_ridge(surface: int, x: np.ndarray, tri: np.ndarray, uv: np.ndarray, ups: np.ndarray, sign,
              split: tuple, gain: np.ndarray, pick: np.ndarray, edges: tuple) -> None:
    """Move the split points of edges ``pick`` (of ``edges``: a, b, c, d, t1, t2) that are their
    parametric middles to :func:`_on_ridge`'s, in place in ``split`` (points, parameters, whether each is
    the middle) and in ``ups`` (the new nodes' normals, rows ``len(x) + edge``), where that adds more area
    than ``gain`` (the middles') and folds no triangle."""
    p, par, middle = split
    pick = pick[middle[pick]]
    if not len(pick):
        return
    sub = tuple(v[pick] for v in edges)
    pts, q = _on_ridge(surface, x, tri, uv, sub)
    xs = np.vstack([x, pts])
    new = _quads(*sub[:4], len(x) + np.arange(len(pick)))
    keep = _gains(xs, x, tri, new, sub[4], sub[5]) > gain[pick]
    normals = normals_at(surface, q)
    near = np.vstack([ups[:len(x)], normals])
    for t in new:
        keep &= ~folded(xs, t, reference_normals(near, t, sign))
    p[pick[keep]], par[pick[keep]], ups[len(x) + pick[keep]] = pts[keep], q[keep], normals[keep]


def split_short_face(surface: int, brep_area: float, target: float, *, above: float | None = None,
                     ridge: bool = False) -> bool:
    """Split interior edges of meshed gmsh surface ``surface`` at its surface, if its area deficit (against
    ``brep_area``) is over ``above`` (default ``target``), until it is within :data:`AIM` of ``target``;
    the face keeps the result only if it is then within ``target``, without more folded triangles.
    ``ridge``: each edge where its split adds the most area, in up to :data:`RIDGE_ROUNDS` sets, instead of
    at its middle in :data:`ROUNDS`. Returns whether the face's mesh changed."""
    from .facemesh import read_face, write_interior
    from .folds import node_params

    mesh = read_face(surface)
    if mesh is None or brep_area <= 0:
        return False
    x, tri, movable = mesh.x, mesh.tri, mesh.movable
    if 1.0 - triangle_areas(x, tri).sum() / brep_area <= (target if above is None else above):
        return False
    uv = node_params(surface, x, mesh.uv, mesh.tags)
    up = normals_at(surface, uv)
    sign = orientation(up, tri, x)
    folds = folded(x, tri, reference_normals(up, tri, sign)).sum()
    cap = GROWTH * len(tri)
    for _ in range(RIDGE_ROUNDS if ridge else ROUNDS):
        area = triangle_areas(x, tri).sum()
        short = (1.0 - area / brep_area - AIM * target) * brep_area
        if short <= 0 or len(tri) > cap:
            break
        fixed_keys = np.array(sorted(i * (len(x) + 1) + j for i, j in mesh.fixed), dtype=np.int64)
        eid, t1, t2, a, b, c, d = _edges(tri, len(x), fixed_keys)
        inner = np.flatnonzero(t2 >= 0)
        if not len(inner):
            break
        p = np.full((len(a), 3), np.nan)
        par = np.full((len(a), 2), np.nan)
        middle = np.zeros(len(a), dtype=bool)
        p[inner], par[inner], middle[inner] = _surface_middles(surface, x, uv, a[inner], b[inner])
        xs = np.vstack([x, np.nan_to_num(p)])
        new = _quads(a, b, c, np.maximum(d, 0), np.arange(len(a)) + len(x))  # the new nodes' rows, if all were split
        gain = np.zeros(len(a))
        gain[inner] = _gains(xs, x, tri, [t[inner] for t in new], t1[inner], t2[inner])
        ups = np.vstack([up, np.zeros((len(a), 3))])
        ups[len(up) + inner] = normals_at(surface, par[inner])
        for t in new:  # an edge whose split would fold a triangle against the surface is not split
            gain[inner[folded(xs, t[inner], reference_normals(ups, t[inner], sign))]] = -np.inf
        length = np.linalg.norm(x[a] - x[b], axis=1)
        rank = np.empty(len(a), dtype=np.int64)
        rank[np.lexsort((np.arange(len(a)), length))] = np.arange(len(a))
        longest = eid[np.arange(len(tri)), np.argmax(rank[eid], axis=1)]
        own = np.where(t2[eid] >= 0, gain[eid], -np.inf)  # each triangle's best edge to split, and its gain
        score = own.max(axis=1)
        best = eid[np.arange(len(tri)), np.argmax(own, axis=1)]
        order = np.argsort(-score, kind="stable")
        order = order[score[order] > 0]
        order = order[:int(np.searchsorted(np.cumsum(score[order]), short)) + 1]
        end = longest[_ends(longest, t1, t2)[order]]
        # the end of its longest-edge path where that edge may be split, else its own best edge (a path
        # that ends on a curve: the coarse side of a cylinder, whose longest edges are its circles' segments)
        pick = np.where((t2[end] >= 0) & np.isfinite(gain[end]), end, best[order])
        pick = _apart(np.unique(pick[np.isfinite(gain[pick])]), gain, t1, t2, len(tri))
        if not len(pick):
            break
        if ridge:
            _to_ridge(surface, x, tri, uv, ups, sign, (p, par, middle), gain, pick, (a, b, c, d, t1, t2))
        rows = np.arange(len(pick)) + len(x)
        x = np.vstack([x, p[pick]])
        uv = np.vstack([uv, par[pick]])
        up = np.vstack([up, ups[len(up) + pick]])
        movable = np.concatenate([movable, np.ones(len(pick), dtype=bool)])
        a, b, c, d, t1, t2 = a[pick], b[pick], c[pick], d[pick], t1[pick], t2[pick]
        tri = tri.copy()
        tri[t1] = np.column_stack([a, rows, c])
        tri[t2] = np.column_stack([b, rows, d])
        tri = np.vstack([tri, np.column_stack([rows, b, c]), np.column_stack([rows, a, d])])
    if 1.0 - triangle_areas(x, tri).sum() / brep_area > target or len(x) == len(mesh.x):
        return False
    if folded(x, tri, reference_normals(up, tri, sign)).sum() > folds:
        return False
    write_interior(surface, mesh, x, tri, movable, uv)
    return True


def split_short_faces(ctx, above: dict[int, float], *, target: float, most: float, deficit, areas,
                      ridged: frozenset[int] = frozenset()) -> list[int]:
    """:func:`split_short_face` on each gmsh surface of ``above`` (surface -> the deficit it is split
    from) whose deficit (``deficit(s, mesh_area)``, as measured now) is over that and at most ``most``
    (beyond it the face's mesh and B-rep areas disagree); ``areas`` the B-rep areas by face id. Surfaces
    of ``ridged`` (held at a size floor: a ridge narrower than their triangles explains any shortfall)
    have no such bound, and where the splits at middles leave one over its target it is split on its
    ridge (``ridge=True``). Stops at the job's soft deadline. Returns the ids of the faces split."""
    import time

    from .areas import unfolded_areas

    face_of = ctx.emap.face_of_surface
    say = ctx.progress or (lambda line: None)
    split = []
    for s, a in unfolded_areas(list(above)).items():
        if ctx.job.deadline is not None and time.time() > ctx.job.deadline:
            break
        f = face_of.get(s, s)
        if above[s] < deficit(s, a) <= (np.inf if s in ridged else most):
            say(f"refine {f}")  # the watchdog bounds it like any refinement
            if split_short_face(s, float(areas[f - 1]), target, above=above[s]) or (
                    s in ridged and split_short_face(s, float(areas[f - 1]), target, above=above[s], ridge=True)):
                split.append(f)
            say(f"refined {f}")
    return split
