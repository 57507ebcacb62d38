"""Mesh sizes from edge-grid spacings: a graded size field and gmsh size settings (the ``.geo`` export
is :mod:`cadedge.mesh.spacing_geo`).

Every grid point carries a local spacing (the mean of its neighbouring segment lengths; at a vertex the
vertex spacing). The size anywhere is ``min_i (h_i + growth * |x - p_i|)`` over the nearest grid points,
clamped to ``[min_size, max_size]``: faces are graded from their edges, fine next to small edges and
growing linearly away from them, so there are neither slivers at small edges nor huge faces of tiny
triangles.
"""

from __future__ import annotations

import contextlib
from typing import Iterator

import gmsh
import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError
from ..shapegrid import ShapeEdgeGrid, ShapeGrid, vertex_spacings
from . import DEFAULT_GROWTH
from .gmsh_model import EntityMap
_NEIGHBOURS = 8


def node_spacings(edge: ShapeEdgeGrid) -> np.ndarray:
    """Local spacing at each grid point of a non-degenerate edge: mean of the adjacent segment lengths."""
    seg = edge.segment_lengths
    h = np.empty(len(seg) + 1)
    h[0], h[-1] = seg[0], seg[-1]
    h[1:-1] = 0.5 * (seg[:-1] + seg[1:])
    return h


def vertex_sizes(grid: ShapeGrid) -> dict[int, float]:
    """Each vertex's spacing: the grid's own where it has one, else the shortest end segment there."""
    out = vertex_spacings(grid.edges)
    out.update({v.id: float(v.spacing) for v in grid.vertices if v.spacing})
    return out


class SizeField:
    """The graded size function of a shape grid; callable as gmsh's size callback."""

    def __init__(self, grid: ShapeGrid, *, growth: float = DEFAULT_GROWTH, min_size: float | None = None,
                 max_size: float | None = None):
        if growth <= 0:
            raise InputError(f"growth must be positive, got {growth}")
        pts, hs = [], []
        vsp = vertex_sizes(grid)
        for v in grid.vertices:
            if v.id in vsp:
                pts.append(np.asarray(v.point, dtype=float)[None])
                hs.append([vsp[v.id]])
        for e in grid.edges:
            if not e.degenerate and len(e.points) > 2:
                pts.append(e.points[1:-1])
                hs.append(node_spacings(e)[1:-1])
        if not pts:
            raise InputError(f"{grid.source}: no edge with a grid to take mesh sizes from")
        self.points = np.vstack(pts)
        self.spacing = np.concatenate(hs)
        positive = self.spacing[self.spacing > 0]
        self.min_size = float(min_size) if min_size else float(positive.min()) if len(positive) else 0.0
        self.max_size = float(max_size) if max_size else float(self.spacing.max())
        self.growth = float(growth)
        self._tree = cKDTree(self.points)
        self._k = min(_NEIGHBOURS, len(self.points))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """Sizes at points ``x`` (shape (n, 3))."""
        d, i = self._tree.query(np.atleast_2d(x), k=self._k)
        d, i = d.reshape(len(d), -1), i.reshape(len(i), -1)
        size = np.min(self.spacing[i] + self.growth * d, axis=1)
        return np.clip(size, self.min_size, self.max_size)

def configure_gmsh_sizes(field: SizeField) -> None:
    """Size faces from their boundary segments, graded by ``field.growth``, in gmsh's own C++.

    gmsh's ``Extend`` field takes the local boundary segment length and grows it linearly with the
    distance to the boundary up to ``field.max_size`` (a Python size callback would do the same but is
    called hundreds of thousands of times). Curvature, default and point-interpolated sizes are off: a
    straight edge between two fine vertices would otherwise be fine all along instead of graded.
    """
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeMin", field.min_size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", field.max_size)
    ext = gmsh.model.mesh.field.add("Extend")
    gmsh.model.mesh.field.setNumbers(ext, "CurvesList", [t for _, t in gmsh.model.getEntities(1)])
    gmsh.model.mesh.field.setNumber(ext, "SizeMax", field.max_size)
    gmsh.model.mesh.field.setNumber(ext, "DistMax", max(field.max_size - field.min_size, 0.0) / field.growth)
    gmsh.model.mesh.field.setNumber(ext, "Power", 1.0)
    gmsh.model.mesh.field.setAsBackgroundMesh(ext)


def configure_curvature_sizes(per_circle: float, min_size: float) -> None:
    """Also size face interiors by surface curvature: ``2 pi / (per_circle * k)`` with ``k`` the largest
    principal curvature where gmsh places a node (gmsh's ``Mesh.MeshSizeFromCurvature`` evaluates it on the
    B-rep surface itself). Edge grids are imposed, so only face interiors follow it. Sizes stop at
    ``min_size`` (a share of the finest edge spacing): a spline surface's curvature estimate can spike
    where it is nearly singular, and gmsh then hangs filling a face with ever smaller triangles."""
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", float(per_circle))
    gmsh.option.setNumber("Mesh.MeshSizeMin", float(min_size))


def _samples(edge: ShapeEdgeGrid, max_size: float) -> tuple[np.ndarray, np.ndarray]:
    """Grid parameters and points, plus extra ones splitting segments longer than a quarter of ``max_size``."""
    parts = np.maximum(np.ceil(edge.segment_lengths / (0.25 * max_size)), 1).astype(int)
    seg = np.repeat(np.arange(len(parts)), parts)  # each sample's segment, and its place along it
    t = (np.arange(len(seg)) - np.repeat(np.cumsum(parts) - parts, parts)) / parts[seg]
    u, x = np.asarray(edge.params, dtype=float), np.asarray(edge.points, dtype=float)
    params = np.append(u[seg] + (u[seg + 1] - u[seg]) * t, u[-1])
    points = np.vstack([x[seg] + (x[seg + 1] - x[seg]) * t[:, None], x[-1:]])
    return params, points


def apply_spacing_sizes(grid: ShapeGrid, emap: EntityMap, field: SizeField, *, factor: float = 1.0,
                        curves: set[int] | None = None) -> None:
    """Spacing-only mode: sizes at parametric points on each curve and at each B-rep vertex.

    Each curve gets the graded size ``field`` at its grid parameters and at extra parameters splitting
    long segments, so a long straight edge between fine vertices is graded rather than uniformly fine.
    Curves no grid maps to (unmatched edges) get ``field`` at points sampled on gmsh's own curve, so they
    are graded from their neighbours too rather than meshed at the largest size.
    Each vertex gets its spacing as its point size (kept in the model for exports and for meshers that
    read point sizes; gmsh's interpolation of point sizes along curves is off, see
    :func:`configure_gmsh_sizes`). ``factor`` scales the curve sizes and ``curves`` (gmsh tags) limits
    them to those curves (see :func:`retry_failed_faces`).
    """
    if curves is None:
        for vid, h in vertex_sizes(grid).items():
            if h > 0 and vid in emap.vertices:
                gmsh.model.mesh.setSize([(0, emap.vertices[vid])], float(h))
    chosen = [(e, emap.edges[e.id]) for e in grid.edges
              if not e.degenerate and e.id in emap.edges and len(e.points) >= 2
              and (curves is None or emap.edges[e.id].tag in curves)]
    samples = [_samples(e, field.max_size) for e, _ in chosen]
    points = np.vstack([pts for _, pts in samples]) if samples else np.zeros((0, 3))
    sized_all = factor * field(points) if len(points) else np.zeros(0)  # the field in one query
    per_curve = np.split(sized_all, np.cumsum([len(own) for own, _ in samples])[:-1])
    sized = set()
    for (e, m), (own, _), sizes in zip(chosen, samples, per_curve):
        gparams = np.interp(own, e.params, m.params)  # our parameters -> gmsh's (same or reversed)
        if gparams[-1] < gparams[0]:
            gparams, sizes = gparams[::-1], sizes[::-1]
        gmsh.model.mesh.setSizeAtParametricPoints(1, m.tag, gparams.tolist(), sizes.tolist())
        sized.add(m.tag)
    for tag in emap.unmatched_curves:
        if tag not in sized and (curves is None or tag in curves):
            _size_own_curve(tag, field, factor)


#: Points sampled on a curve without a grid to size it from the field (sizes are linear in between).
_OWN_CURVE_SAMPLES = 65


def _size_own_curve(tag: int, field: SizeField, factor: float = 1.0) -> None:
    """Sizes from ``field`` at evenly spaced parameters of gmsh curve ``tag`` (one no grid maps to)."""
    try:
        lo, hi = (float(b[0]) for b in gmsh.model.getParametrizationBounds(1, tag))
        u = np.linspace(lo, hi, _OWN_CURVE_SAMPLES)
        x = np.asarray(gmsh.model.getValue(1, tag, u.tolist()), dtype=float).reshape(-1, 3)
    except Exception:  # gmsh raises a bare Exception on a curve it cannot evaluate: leave it to the field
        return
    if len(x) == len(u) and np.all(np.isfinite(x)):
        gmsh.model.mesh.setSizeAtParametricPoints(1, tag, u.tolist(), (factor * field(x)).tolist())


#: ``Mesh.LcIntegrationPrecision`` for meshing curves from sizes (gmsh's default: 1e-9). gmsh integrates
#: the size along each curve to place its nodes; at 1e-9 it evaluates the size field hundreds of
#: thousands of times per curve. At this precision the curve meshes of 917_fusee are the same (8074
#: segments, sizes mode at ALD 1e-2) for 0.3 s of CPU instead of 3.2 s.
INTEGRATION_PRECISION = 1e-5


@contextlib.contextmanager
def curves_from_spacings() -> Iterator[None]:
    """Mesh curves from the spacing sizes alone: surface curvature sizing is off inside the block, and
    the size integration along curves is :data:`INTEGRATION_PRECISION`.

    gmsh sizes a curve by the largest curvature of the surfaces around it as well as its own
    (``Mesh.MeshSizeFromCurvature``, switched on for face interiors by the surface target). Near a
    cone's apex or a sphere's pole that curvature grows without bound, so the seam running into it was
    split down to the minimum size (368 segments where the grid has 7), and gmsh then failed or hung
    meshing the face on it. The edge grids already meet the ALD along the curves, so in sizes mode
    curves follow them; faces still get the curvature sizes.
    """
    options = {"Mesh.MeshSizeFromCurvature": 0, "Mesh.LcIntegrationPrecision": INTEGRATION_PRECISION}
    before = {name: gmsh.option.getNumber(name) for name in options}
    for name, value in options.items():
        gmsh.option.setNumber(name, value)
    try:
        yield
    finally:
        for name, value in before.items():
            gmsh.option.setNumber(name, value)


#: Factors on a failed face's curve sizes tried by :func:`retry_failed_faces`, in turn.
RETRY_FACTORS = (4.0, 2.0, 0.5)


def retry_failed_faces(ctx) -> None:
    """``after_generate`` hook of the sizes mode: a face that failed every strategy gets its curves meshed
    again by gmsh at other sizes (:data:`RETRY_FACTORS` times the spacing sizes) and is meshed again, with
    the faces sharing those curves.

    The retry strategies of :mod:`cadedge.mesh.generate` keep a face's curve mesh (or split it, or have
    gmsh mesh it again from the same sizes), so a curve mesh gmsh cannot recover in the face's parameter
    plane fails them all: on mesh_T106_V3, whose B-spline edges lie 0.02 off their faces, gmsh's nodes on
    the 3-D curve map to a boundary gmsh cannot recover in the plane of the thin face 5 ("Unable to
    recover the edge"). Other node spacings step over it (4x there). gmsh's ``generate(1)`` clears every
    face's mesh, so every meshed face is meshed again after each retry: costly on a large model, but only
    faces that failed every strategy come here. A retry is kept only if the face and every
    neighbour it cleared mesh; otherwise the curves get their spacing sizes back and the neighbours are
    meshed again as they were. Each retry is announced as ``refine F`` (the watchdog's line for meshing
    after the first pass: a hang or crash there keeps the face as it was). Only the first two strategies
    are tried on the face per retry; faces in ``job.no_refine`` (a retry hung or crashed) are left alone.
    """
    import time

    from .generate import mesh_faces, remesh_curves
    from .gmsh_model import surface_curve_uses
    from .outcomes import FaceOutcome
    from .strategies import STRATEGIES

    job = ctx.job
    if job.mode != "sizes":
        return
    face_of = ctx.emap.face_of_surface
    say = ctx.progress or (lambda line: None)
    per_circle = (job.options.get("fidelity") or {}).get("face_per_circle", {})
    default = gmsh.option.getNumber("Mesh.MeshSizeFromCurvature")

    def started(face: int, k: int) -> None:  # each face's own curvature sizes, as the first pass gave them
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", per_circle.get(face, default))

    def remesh(s: int, curves: set[int], factor: float, only: set[int]) -> dict:
        apply_spacing_sizes(job.grid, ctx.emap, job.field, factor=factor, curves=curves)
        touched = set(remesh_curves(sorted(curves))) | {s}
        skip = {face_of.get(s, s): {k: "not tried again" for k in range(2, len(STRATEGIES))}}
        return mesh_faces(sorted(n for n in touched if n in only), face_of, skip=skip, started=started)

    failed = [s for s, o in ctx.outcomes.items() if s > 0 and not o.ok and face_of.get(s, s) not in job.no_refine]
    try:
        for s in failed:
            face, curves = face_of.get(s, s), set(surface_curve_uses(s))
            attempts = list(ctx.outcomes[s].attempts)
            tried = won = False
            was_ok = {n for n, o in ctx.outcomes.items() if o.ok}
            for factor in RETRY_FACTORS:
                if job.deadline is not None and time.time() > job.deadline:
                    break
                say(f"refine {face}")
                tried = True
                redo = remesh(s, curves, factor, set(ctx.outcomes))
                if redo[s].ok and all(o.ok for n, o in redo.items() if n in was_ok):
                    redo[s].strategy = f"{redo[s].strategy}, curves at {factor:g}x the spacing sizes"
                    redo[s].attempts = attempts
                    ctx.outcomes.update(redo)
                    won = True
                    break
                why = redo[s].reason() if not redo[s].ok else "a neighbouring face failed on that curve mesh"
                attempts.append((f"curves at {factor:g}x the spacing sizes", why))
                ctx.outcomes.update({n: o for n, o in redo.items() if n != s})
            if not won:
                if tried:  # back to the spacing sizes: the neighbours as they were, this face failed
                    ctx.outcomes.update(remesh(s, curves, 1.0, set(ctx.outcomes) - {s}))
                    gmsh.model.mesh.clear([(2, s)])
                ctx.outcomes[s] = FaceOutcome(face=face, surface=s, attempts=attempts)
    finally:
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", default)
