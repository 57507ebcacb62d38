"""Inside the gmsh job: a face of linear extrusion laid flat, meshed in the plane and rolled back up.

A face swept by a curve along a fixed direction ``D`` (OCCT's ``Geom_SurfaceOfLinearExtrusion``, what
cadquery's ``extrude`` makes of a spline; gmsh calls its type "Unknown"; a B-spline surface straight and
alike along one parameter is taken where its section has a corner, :data:`CORNERED_TYPES`) is
developable: it unrolls onto
the plane with ``x`` the arc length of the curve's section across ``D`` and ``y`` the distance along
``D``, lengths and angles kept. gmsh meshes it in its parameters instead, ``u`` along the curve and ``v``
along ``D``; on a gear whose side is a periodic spline through 600 points of ``r = 40 + 3 |cos 15 t|**0.3``
(30 sharp valleys) it ran over 60 s in every strategy and 2-D algorithm, even alone at one uniform size.
Here the face's boundary nodes are laid out in the plane (a closed section's seam nodes twice, at ``x = 0``
and at its length), the plane is meshed by gmsh (:func:`cadedge.mesh.flat.mesh_plane`), sized along ``x``
as the face would be (:func:`_sizes`), and the new nodes are put back on the surface at the parameters of
their ``x`` and ``y``: that gear's side meshes in about a second (34 000 triangles at 0.5 mm).

Where the section folds, a line of nodes runs along the fold (:mod:`cadedge.mesh.creases`).

The section's arc length is tabulated on :data:`TABLE` samples of ``u``, more where its heading turns
sharply (:data:`TURN_STEP`: a corner is placed to a hair), by the trapezoid rule on the surface's
derivative across ``D``, and read back by linear interpolation; new nodes are evaluated on the
surface itself, so they lie on it exactly, at most the table's error away from where the plane put them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .creases import (CREASES, FOLD_LOSS, GROWTH, Creases, across_folds, fold_lines, folds, graded_points,
                      has_corner, steps)
from .flat import add_triangles, boundary_sizes, mesh_plane

#: gmsh's surface types laid flat when straight along one parameter: OCCT's surfaces of linear extrusion
#: are gmsh's "Unknown" (cylinders and planes are extrusions too, but gmsh meshes them well in their own
#: parameters).
TYPES = frozenset({"Unknown"})
#: gmsh's surface types laid flat when straight along one parameter and their section has a corner
#: (:func:`cadedge.mesh.creases.has_corner`). gmsh meshes them in their own parameters, its triangles
#: across the corners (OCCT's Alias key: a B-spline wall with 90-degree corners, 5.8e-3 short at 1e-3);
#: without a corner gmsh does as well with fewer triangles (917_fusee's 223 B-spline extrusions, mostly
#: flat, laid flat: 11% more triangles at 1e-3, no face nearer its area).
CORNERED_TYPES = frozenset({"BSpline surface", "Bezier surface"})
#: Samples of the surface's parameters checked for straight lines along one parameter, all alike.
PROBES = 9
#: A share of the face's size: within it, probes are on one straight line, copies of one vector apart,
#: and a closed section's ends meet (a node's share of the section's length: it is on the seam).
TOL = 1e-7
#: A boundary node farther than this share of the face's size from where its parameters put it is off
#: the surface (loose tolerances: mesh_T106_V3's faces 1 and 2); the face is then left to gmsh.
NODE_TOL = 1e-4
#: Samples of the section's arc length: at least this many, and :data:`PER_NODE` per boundary node.
TABLE = 4096
PER_NODE = 8
#: Where the section's heading turns by more than :data:`TURN_STEP` degrees between two samples, a sample
#: is added between them, at most :data:`REFINE_LEVELS` times over: a corner of the section (a
#: B-spline's C0 knot) is then placed within its parameter range / (TABLE 2**REFINE_LEVELS), and the
#: width a fold turns within (:func:`cadedge.mesh.creases.fold_loss`) is measured, not the table's step
#: (a 90-degree corner of a 53 mm section read as a 0.026 mm round, costing a third of a 1e-3 budget).
TURN_STEP = 5.0
REFINE_LEVELS = 24
#: Samples of a section searched for a corner (:func:`is_extrusion`): as many as its smooth turns need
#: (they are sampled more finely until no gap turns :data:`TURN_STEP`), a corner found at any count.
CORNER_TABLE = 256
#: The size field's table keeps a sample where the sizes' log has varied by this much since the last one
#: kept (and at both ends): linear between the samples kept, sizes are within about this share.
SIZE_STEP = 0.02
#: The size field's cells are at most this many times taller than their column is wide, and at most
#: :data:`FIELD_CELLS` in all (then taller). gmsh's ``PostView`` field finds a point's cell through the
#: cells' bounding boxes: a 2 mm rod 1 148 mm long, its table's 54 816 samples each one column over the
#: whole height, hung gmsh for over 60 s.
CELL_ASPECT = 8.0
FIELD_CELLS = 100_000


@dataclass(frozen=True)
class Extrusion:
    """A gmsh surface of linear extrusion: ``swap`` if its first parameter runs along ``along`` (unit),
    ``rate`` the surface's derivative along that parameter; the section's parameter ``t`` (the other one)
    sampled at ``v0`` of that one, with its arc length ``x`` across ``along`` from the first sample, the
    samples' points' heights ``base`` along ``along``, the section's unit ``heading`` across ``along`` at
    them (zero where it has none), and whether the section closes."""

    swap: bool
    along: np.ndarray
    rate: np.ndarray
    v0: float
    t: np.ndarray
    x: np.ndarray
    base: np.ndarray
    heading: np.ndarray
    closed: bool

    @property
    def length(self) -> float:
        """The section's arc length across ``along``."""
        return float(self.x[-1])

    def flat_x(self, t: np.ndarray) -> np.ndarray:
        """The section's arc length at its parameters ``t``."""
        return np.interp(t, self.t, self.x)

    def params(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The surface's parameters (k, 2) of plane points ``(x, y)``: ``t`` of arc length ``x``, and the
        other parameter where the height along ``along`` is ``y``."""
        t = np.interp(x, self.x, self.t)
        v = self.v0 + (y - np.interp(x, self.x, self.base)) / float(self.rate @ self.along)
        return np.column_stack([v, t] if self.swap else [t, v])


def _values(surface: int, uv: np.ndarray) -> np.ndarray:
    """The points (k, 3) of gmsh surface ``surface`` at parameters ``uv`` (k, 2), in one call."""
    import gmsh

    return np.asarray(gmsh.model.getValue(2, surface, np.asarray(uv, dtype=float).ravel().tolist()),
                      dtype=float).reshape(-1, 3)


def _straight(surface: int) -> tuple[bool, np.ndarray, np.ndarray, np.ndarray, float] | None:
    """Whether gmsh surface ``surface`` is straight and alike along one of its parameters (its type in
    :data:`TYPES`): (``swap``: it is the first, the surface's derivative along it, the parameter bounds'
    lows and highs, the face's size); else None."""
    import gmsh

    if gmsh.model.getType(2, surface) not in TYPES | CORNERED_TYPES:
        return None
    lo, hi = (np.asarray(b, dtype=float) for b in gmsh.model.getParametrizationBounds(2, surface))
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi > lo)):
        return None
    s = np.linspace(0.0, 1.0, PROBES)
    for swap in (False, True):
        a, b = (0, 1) if swap else (1, 0)  # a: the straight parameter, b: the section's
        grid = np.empty((PROBES, 3, 2))
        grid[:, :, b] = (lo[b] + (hi[b] - lo[b]) * s)[:, None]
        grid[:, :, a] = lo[a] + (hi[a] - lo[a]) * np.array([0.0, 0.5, 1.0])
        try:
            p = _values(surface, grid.reshape(-1, 2)).reshape(PROBES, 3, 3)
        except Exception:  # gmsh's bare Exception: a surface it cannot evaluate
            return None
        size = float(np.ptp(p.reshape(-1, 3), axis=0).max())
        step = p[:, 2] - p[:, 0]
        if (size > 0 and np.linalg.norm(step[0]) > TOL * size and np.abs(step - step[0]).max() <= TOL * size
                and np.abs(p[:, 1] - 0.5 * (p[:, 0] + p[:, 2])).max() <= TOL * size):
            return swap, step[0] / (hi[a] - lo[a]), lo, hi, size
    return None


def is_extrusion(surface: int) -> bool:
    """Whether gmsh surface ``surface`` is a face of linear extrusion that :func:`mesh_unrolled` takes:
    of a type in :data:`TYPES`, or in :data:`CORNERED_TYPES` with a corner in its section."""
    import gmsh

    if gmsh.model.getType(2, surface) in TYPES:
        return _straight(surface) is not None
    ext = extrusion_of(surface, table=CORNER_TABLE)  # None unless straight and of a cornered type
    return ext is not None and has_corner(ext)


def _section_uv(t: np.ndarray, swap: bool, v0: float) -> np.ndarray:
    """The surface parameters (k, 2) of its section's parameters ``t`` (the first column if not ``swap``),
    the other parameter at ``v0``."""
    uv = np.empty((len(t), 2))
    uv[:, 1 if swap else 0], uv[:, 0 if swap else 1] = t, v0
    return uv


def _section(surface: int, t: np.ndarray, swap: bool, v0: float, along: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """The section of gmsh surface ``surface`` (straight along ``along``, its first parameter if
    ``swap``) at its parameters ``t``, the other parameter at ``v0``: its points (k, 3) and its
    derivative across ``along`` (k, 3)."""
    import gmsh

    uv = _section_uv(t, swap, v0)
    points = _values(surface, uv)
    d = np.asarray(gmsh.model.getDerivative(2, surface, uv.ravel().tolist()), dtype=float).reshape(-1, 2, 3)
    d = d[:, 1 if swap else 0]
    return points, d - np.outer(d @ along, along)


def extrusion_of(surface: int, nodes: int = 0, table: int = TABLE) -> Extrusion | None:
    """The extrusion of gmsh surface ``surface`` if it is straight along one parameter (:func:`_straight`),
    its section's arc length tabulated on ``table`` samples or :data:`PER_NODE` per boundary node
    (``nodes``), more where its heading turns sharply (:data:`TURN_STEP`); else None."""
    straight = _straight(surface)
    if straight is None:
        return None
    swap, rate, lo, hi, size = straight
    a, b = (0, 1) if swap else (1, 0)
    along = rate / np.linalg.norm(rate)
    t = np.linspace(lo[b], hi[b], max(table, PER_NODE * nodes))
    try:
        points, dt = _section(surface, t, swap, float(lo[a]), along)
        for _ in range(REFINE_LEVELS):  # halve the gaps the heading turns sharply across
            unit = dt / np.maximum(np.linalg.norm(dt, axis=1), 1e-300)[:, None]
            gap = np.flatnonzero((steps(unit) > np.radians(TURN_STEP)) & (np.abs(unit[:-1]).sum(axis=1) > 0)
                                 & (np.abs(unit[1:]).sum(axis=1) > 0) & (np.diff(t) > 1e-12 * (hi[b] - lo[b])))
            if not len(gap):
                break
            mid = 0.5 * (t[gap] + t[gap + 1])
            p_mid, d_mid = _section(surface, mid, swap, float(lo[a]), along)
            t, points, dt = (np.insert(t, gap + 1, mid), np.insert(points, gap + 1, p_mid, axis=0),
                             np.insert(dt, gap + 1, d_mid, axis=0))
    except Exception:  # gmsh's bare Exception: a surface it cannot evaluate
        return None
    speed = np.linalg.norm(dt, axis=1)
    x = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(t))])
    if not (np.all(np.isfinite(x)) and x[-1] > 0):
        return None
    ends = points[-1] - points[0]
    closed = bool(np.linalg.norm(ends - (ends @ along) * along) <= TOL * size)
    heading = dt / np.where(speed > 0, speed, 1.0)[:, None]
    return Extrusion(swap, along, rate, float(lo[a]), t, x, points @ along, heading, closed)


def mesh_unrolled(surface: int, algorithm: int) -> str | None:
    """Mesh (empty) gmsh surface ``surface``, if it is a face of linear extrusion (:func:`extrusion_of`),
    laid flat (see the module doc) with gmsh's 2-D ``algorithm``, sized as :func:`_sizes`; None if it
    passed, else why not (the surface is then left empty)."""
    import gmsh

    from .gmsh_model import surface_curve_uses

    uses = surface_curve_uses(surface)
    curves = []
    for curve in uses:
        tags, coords, par = gmsh.model.mesh.getNodes(1, curve, includeBoundary=True)
        _, seg = gmsh.model.mesh.getElementsByType(1, curve)
        uv = gmsh.model.reparametrizeOnSurface(1, curve, par, surface) if len(par) == len(tags) else []
        curves.append((curve, np.asarray(tags, dtype=np.int64), np.asarray(coords, dtype=float).reshape(-1, 3),
                       np.asarray(seg, dtype=np.int64).reshape(-1, 2),
                       np.asarray(uv, dtype=float).reshape(-1, 2) if len(uv) else np.full((len(tags), 2), np.nan)))
    xyz = np.vstack([c[2] for c in curves])
    if not len(xyz):
        return "its boundary curves carry no nodes"
    ext = extrusion_of(surface, len(xyz))
    if ext is None:
        return "not a face of linear extrusion"
    uv = np.vstack([c[4] for c in curves])  # from the curves' own parameters: exact, and 4 ms a node faster
    within = NODE_TOL * max(float(np.ptp(xyz, axis=0).max()), ext.length)  # than gmsh's projection
    off = np.isnan(uv).any(axis=1)
    off[~off] = np.linalg.norm(_values(surface, uv[~off]) - xyz[~off], axis=1) > within
    if off.any():
        uv[off] = np.reshape(gmsh.model.getParametrization(2, surface, xyz[off].ravel().tolist()), (-1, 2))
        if np.linalg.norm(_values(surface, uv[off]) - xyz[off], axis=1).max() > within:
            return "unrolled: its boundary nodes are not where their parameters put them"
    x_all = ext.flat_x(uv[:, 1 if ext.swap else 0])
    y_all = xyz @ ext.along
    length, tol = ext.length, TOL * ext.length
    keys: dict[tuple[int, bool], tuple[float, float]] = {}  # (node tag, far side of the seam?) -> (x, y)
    segments = []
    start = 0
    for curve, tags, _, seg, _ in curves:
        x, y = x_all[start:start + len(tags)], y_all[start:start + len(tags)]
        start += len(tags)
        at = {t: i for i, t in enumerate(tags.tolist())}
        for a, b in seg.tolist():
            ia, ib = at[a], at[b]
            seam = np.array([ext.closed and (x[i] < tol or x[i] > length - tol) for i in (ia, ib)])
            if uses[curve] == 2 and not seam.all():
                return "its seam's nodes do not lie on the section's ends"
            for far in ((False, True) if uses[curve] == 2 else (None,)):
                ends = []
                for k, (node, i) in enumerate(((a, ia), (b, ib))):
                    if seam[k]:
                        other = x[(ib, ia)[k]] if not seam[1 - k] else None
                        side = far if far is not None else bool(other is not None and other > 0.5 * length)
                        key, px = (node, side), (length if side else 0.0)
                    else:
                        key, px = (node, False), float(x[i])
                    keys[key] = (px, float(y[i]))
                    ends.append(key)
                if ends[0] != ends[1]:
                    segments.append(tuple(ends))
    order = list(keys)
    index = {key: i for i, key in enumerate(order)}
    rows = [(index[a], index[b]) for a, b in segments]
    plane = np.array([keys[k] for k in order], dtype=float)
    k, table, at, window = _fold_sizes(surface, ext)
    lines = fold_lines(plane, rows, at, window)
    lined = sorted({f for _, _, f in lines})
    # a fold's curvature, a spike its line makes moot (no triangle spans it), gives way to its flanks':
    # left in, it asked for triangles 20 times smaller there and, weighed into the face's k**-1/2 sizes,
    # put the whole of cyclo_gear's side at the smallest size (471 022 triangles at 1e-2, against 6 918).
    # Only folds with a line: triangles still span the others.
    if lined:
        table = _sizes(surface, ext, across_folds(ext.x, k, at[lined], window, np.minimum))
    grading = _job_grading()
    growth = grading[0] / grading[1] if grading is not None and grading[1] > 0 else GROWTH
    near = boundary_sizes(plane, rows)
    inner = [(lo, hi, graded_points(plane[lo], plane[hi], near[lo], near[hi],
                                    float(np.interp(plane[lo, 0], ext.x, table)), growth))
             for lo, hi, _ in lines]
    options = {"Mesh.MeshSizeFromCurvature": 0}
    if grading is not None:  # the job's graded sizes from the boundary, not gmsh's interpolation of them
        options |= {"Mesh.MeshSizeExtendFromBoundary": 0, "Mesh.MeshSizeFromPoints": 0}
    views: list[int] = []
    try:
        got = mesh_plane(plane, rows, near, algorithm,
                         lambda: views.append(_size_field(ext, table, plane[:, 1].min(), plane[:, 1].max(),
                                                          grading)), options, inner)
    finally:
        for view in views:
            gmsh.view.remove(view)
    if isinstance(got, str):
        return got
    flat, tri = got
    params = ext.params(flat[:, 0], flat[:, 1])
    tags = np.array([k[0] for k in order] + [-1] * (len(flat) - len(order)), dtype=np.int64)
    new = np.arange(len(order), len(flat))
    points = np.vstack([_boundary_points(curves, order), _values(surface, params[new]) if len(new) else
                        np.zeros((0, 3))])
    add_triangles(surface, tags, points, tri, params)
    CREASES.pop(surface, None)
    if inner:
        xs = np.unique([plane[lo, 0] for lo, _, _ in inner])
        ends = {order[row][0]: int(np.searchsorted(xs, plane[lo, 0]))
                for lo, hi, _ in inner for row in (lo, hi)}
        CREASES[surface] = Creases(1 if ext.swap else 0, np.interp(xs, ext.x, ext.t), ends)
    return None


def _boundary_points(curves: list, order: list) -> np.ndarray:
    """The points of the boundary nodes ``order`` (keys (tag, side)) from the curves' nodes."""
    where = {}
    for _, tags, coords, _, _ in curves:
        where.update(zip(tags.tolist(), coords))
    return np.array([where[k[0]] for k in order], dtype=float)


def _curvatures(surface: int, ext: Extrusion) -> np.ndarray:
    """The surface's largest principal curvature (absolute) at the section's samples (0 where unknown)."""
    import gmsh

    uv = _section_uv(ext.t, ext.swap, ext.v0)
    kmax, kmin, _, _ = gmsh.model.getPrincipalCurvatures(surface, uv.ravel().tolist())
    k = np.maximum(np.abs(np.asarray(kmax, dtype=float)), np.abs(np.asarray(kmin, dtype=float)))
    return np.where(np.isfinite(k), k, 0.0)


def _sizes(surface: int, ext: Extrusion, k: np.ndarray) -> np.ndarray:
    """The face's sizes at the section's samples of curvature ``k`` (:func:`_curvatures`), as gmsh would
    size the face now: the ``k**-1/2`` sizes of :func:`cadedge.mesh.interior.root_sizes` where the face
    was sampled, else gmsh's curvature sizes ``2 pi / (N k)``, within ``Mesh.MeshSizeMin`` and
    ``Mesh.MeshSizeMax``; at least the face's size floor. ``N`` is the face's count per ``2 pi``
    (:func:`cadedge.mesh.interior.use_per_circle`); without one, ``Mesh.MeshSizeMax``."""
    import gmsh

    from .interior import SIZES, root_sizes

    lo = max(gmsh.option.getNumber("Mesh.MeshSizeMin"), 1e-12)
    hi = gmsh.option.getNumber("Mesh.MeshSizeMax")
    hi = max(hi if 0 < hi < 1e22 else 10.0 * ext.length, lo)
    per_circle = SIZES.per_circle.get(surface, gmsh.option.getNumber("Mesh.MeshSizeFromCurvature"))
    if not per_circle > 0 or not np.any(k > 0):
        sizes = np.full(len(k), hi)
    elif SIZES.faces.get(surface) is not None and SIZES.faces[surface].sizes is not None:
        da = np.gradient(ext.x)  # the section's samples' share of the face: their arc length
        sizes = root_sizes(k, da, per_circle)
    else:
        with np.errstate(divide="ignore"):
            sizes = np.clip(2.0 * np.pi / (per_circle * k), lo, hi)
    return np.maximum(sizes, SIZES.floors.get(surface, 0.0))


def _fold_sizes(surface: int, ext: Extrusion) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """The face's curvature at the section's samples (:func:`_curvatures`), its sizes (:func:`_sizes`),
    its folds (:func:`cadedge.mesh.creases.folds`) and their window. The folds are found on the sizes,
    then again on the sizes with their curvature taken out (:func:`~cadedge.mesh.creases.across_folds`),
    whose typical size is the flanks'. What their flanks lose beside their lines
    (:func:`~cadedge.mesh.creases.fold_loss`) may be :data:`~cadedge.mesh.creases.FOLD_LOSS` of the job's
    surface target (without one, of the deficit the face's count per ``2 pi`` is designed for,
    :func:`cadedge.mesh.fidelity.per_circle`): a stadium's ends of radius 0.3, taken as folds, lost
    their curvature sizes, 0.45% of the face's area, and were refined back at 1.6 times the triangles
    at 1e-3."""
    import gmsh

    from .fidelity import DEFAULT_C, INTERIOR_SHARE
    from .interior import SIZES

    target = SIZES.target
    if target is None:
        per_circle = SIZES.per_circle.get(surface, gmsh.option.getNumber("Mesh.MeshSizeFromCurvature"))
        target = DEFAULT_C * (2.0 * np.pi / per_circle) ** 2 / INTERIOR_SHARE if per_circle > 0 else np.inf
    budget = FOLD_LOSS * target * ext.length
    k = _curvatures(surface, ext)
    plain = _sizes(surface, ext, k)
    at, window = folds(ext, plain, budget)
    for _ in range(2):
        if not len(at):
            break
        at, window = folds(ext, _sizes(surface, ext, across_folds(ext.x, k, at, window, np.minimum)), budget)
    return k, plain, at, window


def _job_grading() -> tuple[float, float, float] | None:
    """The job's ``Extend`` field (:func:`cadedge.mesh.sizes.configure_gmsh_sizes`: sizes grown from the
    boundary segments' lengths with the distance to them) as (``SizeMax``, ``DistMax``, ``Power``), the
    slower-growing one where planes have their own (:func:`cadedge.mesh.fidelity.grow_planes`); None if
    the current model has none."""
    import gmsh

    fields = gmsh.model.mesh.field
    extend = [t for t in fields.list() if fields.getType(t) == "Extend"]
    if not extend:
        return None
    slow = max(extend, key=lambda t: fields.getNumber(t, "DistMax"))
    return tuple(float(fields.getNumber(slow, name)) for name in ("SizeMax", "DistMax", "Power"))


def _kept_samples(table: np.ndarray) -> np.ndarray:
    """Indices of the samples of sizes ``table`` the size field keeps: both ends, and one wherever the
    sizes' log has varied by :data:`SIZE_STEP` since the last one kept (a cylinder's constant sizes keep
    two)."""
    steps = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(np.log(table))))])
    bins = np.floor(steps / SIZE_STEP)
    keep = np.flatnonzero(np.diff(bins) > 0) + 1
    return np.unique(np.concatenate([[0], keep, [len(table) - 1]]))


def _size_field(ext: Extrusion, table: np.ndarray, y_lo: float, y_hi: float,
                grading: tuple[float, float, float] | None) -> int:
    """The plane model's background field: the face's size ``table`` at each sample's ``x``, linear
    between them (the samples :func:`_kept_samples` keeps), across the plane's heights ``y_lo`` to
    ``y_hi`` (a post-processing view of two triangles per cell, each column cut in cells no taller than
    :data:`CELL_ASPECT` times its width, gmsh's ``PostView`` field), and with ``grading`` the job's
    ``Extend`` field (:func:`_job_grading`) on the plane's boundary, the smaller of the two. gmsh's sizes
    from the boundary instead (``Mesh.MeshSizeExtendFromBoundary``) interpolate the boundary's sizes over
    the whole face: a wing's extruded faces, fine at their trailing edge, took 25 000-29 000 triangles
    each against 4 900. Not a size callback: gmsh's Python API keeps one callback for all models, and
    replacing it left the job's own model calling freed memory (a SIGSEGV when the face was meshed
    again). Returns the view, for the caller to remove."""
    import gmsh

    fields = gmsh.model.mesh.field
    keep = _kept_samples(table)
    x, table = ext.x[keep], table[keep]
    pad = 0.01 * max(y_hi - y_lo, ext.length)
    height = y_hi - y_lo + 2.0 * pad
    width = np.maximum(np.diff(x), 1e-12 * height)
    aspect = CELL_ASPECT  # raised where even that many cells would be too many
    while True:
        rows = np.maximum(np.ceil(height / (aspect * width)), 1.0).astype(np.int64)
        if 2 * rows.sum() <= FIELD_CELLS or rows.max() == 1:
            break
        aspect *= 2.0
    # each column its own rows (the cells need not meet: the sizes vary along x only)
    a = np.repeat(np.arange(len(width)), rows)
    b = a + 1
    k = np.arange(len(a)) - np.repeat(np.cumsum(rows) - rows, rows)  # the cell's row in its column
    lo = (y_lo - pad + height * k / rows[a])[:, None]
    hi = (y_lo - pad + height * (k + 1) / rows[a])[:, None]
    # two triangles per cell: (a lo, b lo, b hi) and (a lo, b hi, a hi); per triangle its 3 x, 3 y, 3 z, 3 sizes
    xs = np.concatenate([np.column_stack([x[a], x[b], x[b]]), np.column_stack([x[a], x[b], x[a]])])
    ys = np.concatenate([np.hstack([lo, lo, hi]), np.hstack([lo, hi, hi])])
    hs = np.concatenate([np.column_stack([table[a], table[b], table[b]]),
                         np.column_stack([table[a], table[b], table[a]])])
    data = np.column_stack([xs, ys, np.zeros_like(xs), hs])
    view = gmsh.view.add("cadedge extrusion sizes")
    gmsh.view.addListData(view, "ST", len(data), data.ravel().tolist())
    field = fields.add("PostView")
    fields.setNumber(field, "ViewTag", view)
    if grading is not None:
        grown = fields.add("Extend")
        fields.setNumbers(grown, "CurvesList", [t for _, t in gmsh.model.getEntities(1)])
        for name, value in zip(("SizeMax", "DistMax", "Power"), grading):
            fields.setNumber(grown, name, value)
        both = fields.add("Min")
        fields.setNumbers(both, "FieldsList", [field, grown])
        field = both
    fields.setAsBackgroundMesh(field)
    return view
