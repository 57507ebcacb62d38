"""Inside the gmsh job: a face gmsh's own meshers failed on, meshed in its own parameters laid flat at their
scale, as a plane face in a model of its own (:func:`cadedge.mesh.flat.mesh_plane`).

gmsh meshes a face in its parameters too, but a face on a periodic surface goes through its own periodic
mesher (``meshGeneratorPeriodic`` in its ``meshGFace.cpp``), which gives up on some: the ventilator pump's
face 704, a B-spline band 0.1 mm wide and 73 mm round, periodic along its length and closed by a seam of
one segment, failed in every strategy with "Impossible to mesh periodic surface", and so did gmsh alone.
Its parameters are uniform on it (the surface's derivatives vary by 0.5% over the face and are square to
each other): laid out at their scale, ``x = |S_u| u`` and ``y = |S_v| v``, the face is a plane strip whose
lengths and angles are the surface's to that share. Here its boundary nodes are laid out there, each curve
at its own parameters on the face (a seam's nodes twice, once on each of its sides), the plane is meshed as
a plane face, sized from its boundary and no coarser than the face's curvature asks
(:func:`~cadedge.mesh.generate.uniform_curvature_size`), and the new nodes are evaluated on the surface at
their parameters, so they lie on it exactly.

Only faces whose parameters are that even are meshed so (:func:`scales`, :data:`MAX_STRETCH`,
:data:`MAX_SHEAR`): elsewhere the plane's triangles would be stretched on the surface as the parameters
are. It comes after gmsh's algorithms and sizes have failed, before the strategies that change the face's
curve meshes (:data:`~cadedge.mesh.strategies.STRATEGIES`).

A face whose boundary crosses itself, its edges crossing within their tolerance, is laid out the same way,
its crossings undone in the plane only (:mod:`cadedge.mesh.tangles`), and meshed so before gmsh's
strategies, which hang on it (:func:`crossed`, :data:`~cadedge.mesh.strategies.CROSSED_ORDER`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .flat import add_triangles, boundary_sizes, mesh_plane
from .tangles import crossings, untangle

#: The surface's derivative along each parameter is sampled on this many points a side of the face's
#: parameter box.
SAMPLES = 9
#: The most the derivative along a parameter may vary over the face (largest over smallest): triangles laid
#: out in the plane are stretched on the surface by up to this much.
MAX_STRETCH = 1.5
#: The largest cosine between the two derivatives: the parameters' skew (0.26: 15 degrees off square).
MAX_SHEAR = 0.26
#: Two places of one boundary node closer than this share of the face's narrower side in the plane are one
#: place (its curves' parameters at it differ within their tolerances); a seam's node has two, a period
#: apart.
SAME_PLACE = 0.25
#: Gmsh surface -> where its boundary crossed itself when it was last meshed laid flat
#: (:func:`tangle_zones`), for the report to name the triangles there (in the mesh process).
TANGLED: dict[int, list[tuple[tuple[float, float, float], float]]] = {}
#: :func:`crossed` traces crossing segments along their curves in this many pieces, then pieces this many
#: times finer, :data:`LEVELS` times: two chords of curves that do not cross part as their sagittas shrink
#: (256-fold a level), curves that cross still do. :data:`RING` neighbours each way along the boundary are
#: traced too, and no more than :data:`MAX_TRACED` pieces.
FINE = 16
LEVELS = 3
RING = 2
MAX_TRACED = 200_000


def scales(surface: int) -> tuple[float, float, np.ndarray, np.ndarray] | str:
    """The lengths per unit of gmsh ``surface``'s two parameters (their derivatives' medians over the face's
    parameter box) and the box's corners (low, high); or why its parameters are too uneven to be laid flat
    (:data:`MAX_STRETCH`, :data:`MAX_SHEAR`)."""
    import gmsh

    lo, hi = (np.asarray(b, dtype=float) for b in gmsh.model.getParametrizationBounds(2, surface))
    u, v = np.meshgrid(np.linspace(lo[0], hi[0], SAMPLES), np.linspace(lo[1], hi[1], SAMPLES), indexing="ij")
    try:
        d = np.asarray(gmsh.model.getDerivative(2, surface, np.column_stack([u.ravel(), v.ravel()]).ravel().tolist()),
                       dtype=float).reshape(-1, 6)
    except Exception as err:  # gmsh's bare Exception: a surface it cannot evaluate
        return f"its parameters cannot be evaluated ({err})"
    du, dv = np.linalg.norm(d[:, :3], axis=1), np.linalg.norm(d[:, 3:], axis=1)
    if not (np.all(np.isfinite(du)) and np.all(np.isfinite(dv)) and du.min() > 0 and dv.min() > 0):
        return "its parameters degenerate on it (a pole)"
    stretch = max(du.max() / du.min(), dv.max() / dv.min())
    shear = float(np.max(np.abs(np.einsum("ij,ij->i", d[:, :3], d[:, 3:])) / (du * dv)))
    if stretch > MAX_STRETCH or shear > MAX_SHEAR:
        return (f"its parameters are too uneven to be laid flat (lengths vary {stretch:.3g}-fold, "
                f"skew cosine {shear:.2g})")
    return float(np.median(du)), float(np.median(dv)), lo, hi


class Layout(NamedTuple):
    """A face's boundary nodes laid out flat (:func:`layout`)."""

    plane: np.ndarray  # (n, 2) places
    tags: np.ndarray  # (n,) gmsh node tags
    params: np.ndarray  # (n, 2) parameters on the face
    coords: np.ndarray  # (n, 3) points
    segments: np.ndarray  # (m, 2) the boundary segments, as pairs of rows
    curves: np.ndarray  # (m, 2) per segment: its curve and use (gmsh's ``which``)
    spans: np.ndarray  # (m, 2) per segment: its ends' parameters on its curve


def layout(surface: int, scale: tuple[float, float], lo: np.ndarray) -> Layout | str:
    """``surface``'s boundary nodes laid out in the plane of its parameters scaled by ``scale`` from ``lo``;
    or why not. A node has one place, or one per side of a seam it lies on: its places within
    :data:`SAME_PLACE` of the first are one."""
    import gmsh

    from .gmsh_model import boundary_uses

    scale = np.array(scale, dtype=float)
    ends: list[tuple[np.ndarray, ...]] = []  # per curve use, per segment: tags, parameters, points, curve, span
    for curve, which in boundary_uses(surface):
        node_tags, coords, par = gmsh.model.mesh.getNodes(1, curve, includeBoundary=True)
        _, seg = gmsh.model.mesh.getElementsByType(1, curve)
        if not len(seg) or len(par) != len(node_tags):
            return "its boundary curves carry no nodes at their parameters"
        node_tags = np.asarray(node_tags, dtype=np.int64)
        seg = np.asarray(seg, dtype=np.int64).reshape(-1, 2)
        xyz = np.asarray(coords, dtype=float).reshape(-1, 3)
        t = np.asarray(par, dtype=float)
        uv = np.asarray(gmsh.model.reparametrizeOnSurface(1, curve, par, surface, which),
                        dtype=float).reshape(-1, 2)
        by_tag = np.argsort(node_tags, kind="stable")
        at = by_tag[np.searchsorted(node_tags[by_tag], seg, side="right") - 1]  # a tag's last listing
        p, span = uv[at], t[at]
        # a closed curve's end node is listed twice with one parameter: it takes the curve's first or last,
        # whichever the segment's other end is nearer on the face (its place) and along the curve (its
        # parameter: on a plane both ends are one place)
        unique, count = np.unique(node_tags, return_counts=True)
        closing = unique[count > 1]
        if len(closing):
            bounds = np.ravel(gmsh.model.getParametrizationBounds(1, curve))
            both = np.reshape(gmsh.model.reparametrizeOnSurface(1, curve, bounds.tolist(), surface, which), (-1, 2))
            for k in np.flatnonzero(np.isin(seg, closing).any(axis=1)).tolist():
                for end in (0, 1):
                    if seg[k, end] in closing:
                        p[k, end] = both[int(np.argmin(np.linalg.norm((both - p[k, 1 - end]) * scale, axis=1)))]
                        span[k, end] = bounds[int(np.argmin(np.abs(bounds - span[k, 1 - end])))]
                if np.isin(seg[k], closing).all():  # a closed curve of one segment: the whole way round
                    span[k] = bounds
        ends.append((seg, p, xyz[at], np.tile([curve, which], (len(seg), 1)), span))
    if not ends:
        return "its boundary curves carry no nodes"
    seg, p, xyz, curves, spans = (np.concatenate(parts) for parts in zip(*ends))
    tags, p, xyz = seg.ravel(), p.reshape(-1, 2), xyz.reshape(-1, 3)  # every segment end, in order
    xy = (p - lo) * scale
    extent = np.ptp(xy, axis=0)
    near = SAME_PLACE * max(float(extent.min()), 1e-12 * float(extent.max()))
    # each end to a place: a tag's first end not yet placed starts one, which takes its ends within near
    order = np.argsort(tags, kind="stable")
    group = np.cumsum(np.r_[True, tags[order][1:] != tags[order][:-1]]) - 1
    cluster = np.full(len(tags), -1, dtype=np.int64)  # per sorted end
    starts: list[np.ndarray] = []
    while (left := np.flatnonzero(cluster < 0)).size:
        first = left[np.r_[True, group[left][1:] != group[left][:-1]]]
        lead = np.empty(group[-1] + 1, dtype=np.int64)
        lead[group[first]] = first
        number = np.empty_like(lead)
        number[group[first]] = sum(len(s) for s in starts) + np.arange(len(first))
        take = left[np.linalg.norm(xy[order[left]] - xy[order[lead[group[left]]]], axis=1) <= near]
        cluster[take] = number[group[take]]
        starts.append(order[first])
    start = np.concatenate(starts)  # each place's first end, by place number
    rank = np.empty(len(start), dtype=np.int64)
    rank[np.argsort(start, kind="stable")] = np.arange(len(start))  # places numbered as first met
    row = np.empty(len(tags), dtype=np.int64)
    row[order] = rank[cluster]
    rows = row.reshape(-1, 2)
    keep = rows[:, 0] != rows[:, 1]
    first = np.sort(start)
    return Layout(xy[first], tags[first], p[first], xyz[first], rows[keep], curves[keep], spans[keep])


def laid_flat(surface: int) -> tuple[Layout, tuple[float, float], np.ndarray] | str:
    """``surface``'s boundary laid out at its parameters' scale (:func:`scales`, :func:`layout`), the scale
    and the parameters' low corner; or why not."""
    found = scales(surface)
    if isinstance(found, str):
        return found
    su, sv, lo, _ = found
    laid = layout(surface, (su, sv), lo)
    return laid if isinstance(laid, str) else (laid, (su, sv), lo)


def mesh_parametric(surface: int, algorithm: int) -> str | None:
    """Mesh (empty) gmsh ``surface`` in its parameters laid flat (see the module doc) with gmsh's 2-D
    ``algorithm``; None if it passed, else why not (the surface is then left empty)."""
    import gmsh

    from .generate import uniform_curvature_size
    from .interior import SIZES

    TANGLED.pop(surface, None)
    got = laid_flat(surface)
    if isinstance(got, str):
        return got
    (laid_at, tags, params, coords, segments, _, _), (su, sv), lo = got
    rows = [tuple(r) for r in segments.tolist()]
    # a node far from where its curve's parameters put it on the face (more than a share of the face's
    # width): the plane's boundary would not be the face's
    points = np.reshape(gmsh.model.getValue(2, surface, params.ravel().tolist()), (-1, 3))
    off = float(np.linalg.norm(points - coords, axis=1).max())
    near = SAME_PLACE * max(float(np.ptp(laid_at, axis=0).min()), 1e-12 * float(np.ptp(coords, axis=0).max()))
    if off > near:
        return f"its boundary nodes lie up to {off:.3g} from their curves' parameters on it"
    untangled = untangle(laid_at, rows, near)  # a boundary crossing itself: meshed as if it did not
    if isinstance(untangled, str):
        return untangled
    plane, places = untangled
    per_circle = gmsh.option.getNumber("Mesh.MeshSizeFromCurvature") or SIZES.per_circle.get(surface, 0.0)
    largest = gmsh.option.getNumber("Mesh.MeshSizeMax")
    h = uniform_curvature_size(surface, per_circle) if per_circle > 0 else None
    options = {"Mesh.MeshSizeFromCurvature": 0.0,
               "Mesh.MeshSizeMax": largest if h is None else max(min(h, largest),
                                                                  gmsh.option.getNumber("Mesh.MeshSizeMin"))}
    got = mesh_plane(plane, rows, boundary_sizes(plane, rows), algorithm, lambda: None, options)
    if isinstance(got, str):
        return got.replace("unrolled", "laid flat")
    flat, tri = got
    uv = np.vstack([params, flat[len(plane):] / np.array([su, sv]) + lo])
    new = np.reshape(gmsh.model.getValue(2, surface, uv[len(plane):].ravel().tolist()), (-1, 3))
    all_tags = np.concatenate([tags, -np.ones(len(flat) - len(plane), dtype=np.int64)])
    add_triangles(surface, all_tags, np.vstack([coords, new]), tri, uv)
    if places:
        TANGLED[surface] = tangle_zones(coords, rows, places)
    return None


def tangle_zones(coords: np.ndarray, segments: list[tuple[int, int]],
                 places: list[np.ndarray]) -> list[tuple[tuple[float, float, float], float]]:
    """Each place where a boundary crossed itself (rows of ``coords`` (n, 3), :func:`untangle`'s) as a
    ball round it: the rows' centre and their furthest distance from it plus the longest boundary segment
    at them, which the triangles there span."""
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    length = np.linalg.norm(coords[seg[:, 0]] - coords[seg[:, 1]], axis=1)
    zones = []
    for rows in places:
        centre = coords[rows].mean(axis=0)
        at = np.isin(seg, rows).any(axis=1)
        radius = float(np.linalg.norm(coords[rows] - centre, axis=1).max()) + float(length[at].max(initial=0.0))
        zones.append((tuple(float(c) for c in centre), radius))
    return zones


def crossed(surface: int) -> bool:
    """Whether gmsh ``surface``'s boundary crosses itself in its parameters where its curves do, not only
    their chords (:mod:`cadedge.mesh.tangles`): gmsh's meshers split crossing chords until they part, and
    hang on curves that cross. The segments that cross, and :data:`RING` more along the boundary each way,
    are traced along their curves in :data:`FINE` pieces and looked at again, those still crossing in
    ``FINE`` times finer pieces, :data:`LEVELS` times. Only faces whose parameters can be laid flat are
    looked at."""
    got = laid_flat(surface)
    if isinstance(got, str):
        return False
    laid, (su, sv), lo = got
    pairs = crossings(laid.plane, laid.segments)
    if pairs is None or not len(pairs):
        return False
    chosen = np.unique(pairs)
    for level in range(1, LEVELS + 1):
        for _ in range(RING):  # a crossing moves along the boundary as its chords follow their curves
            chosen = np.flatnonzero(np.isin(laid.segments, laid.segments[chosen]).any(axis=1))
        if len(chosen) * FINE ** level > MAX_TRACED:
            break  # crossing still, too many pieces to look closer
        traced, pieces = _traced(surface, laid, (su, sv), lo, chosen, FINE ** level)
        again = crossings(traced, pieces)
        if again is None:
            break
        if not len(again):
            return False
        chosen = chosen[np.unique(again) // FINE ** level]
    return True


def _traced(surface: int, laid: Layout, scale: tuple[float, float], lo: np.ndarray, chosen: np.ndarray,
            fine: int) -> tuple[np.ndarray, np.ndarray]:
    """Segments ``chosen`` (indices) of ``laid``'s boundary traced along their curves in ``fine`` pieces
    each: the places (the layout's, then the points between) and the pieces as pairs of rows, ``fine`` a
    segment in ``chosen``'s order."""
    import gmsh

    seg = np.asarray(laid.segments, dtype=np.int64)[chosen].reshape(-1, 2)
    curves, spans = laid.curves[chosen], laid.spans[chosen]
    inner = np.empty((len(seg), fine - 1, 2))
    step = np.arange(1, fine) / fine
    for curve, which in np.unique(curves, axis=0).tolist():
        ks = np.flatnonzero((curves[:, 0] == curve) & (curves[:, 1] == which))
        t = spans[ks, :1] + np.outer(spans[ks, 1] - spans[ks, 0], step)
        uv = np.reshape(gmsh.model.reparametrizeOnSurface(1, curve, t.ravel().tolist(), surface, which), (-1, 2))
        inner[ks] = ((uv - lo) * np.asarray(scale)).reshape(len(ks), fine - 1, 2)
    n = len(laid.plane)
    rows = n + np.arange(len(seg) * (fine - 1)).reshape(len(seg), fine - 1)
    chain = np.column_stack([seg[:, :1], rows, seg[:, 1:]])
    pieces = np.stack([chain[:, :-1], chain[:, 1:]], axis=-1).reshape(-1, 2)
    return np.vstack([laid.plane, inner.reshape(-1, 2)]), pieces
