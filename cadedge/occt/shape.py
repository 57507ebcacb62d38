"""``refine_shape``: edge grids for every edge of a B-rep shape, anchored on its vertices.

Each non-degenerate edge is refined in target mode. Lines, circles, ellipses, hyperbolas, B-splines and
Bezier curves are read once into flat arrays (:class:`~cadedge.occt.edgetable.EdgeTable`) and refined a
chunk of edges per compiled call (``cadedge/_batch.c``), with the same results as the per-edge path; every
other edge, any edge that path cannot finish alike (it would add a note), with ``max_growth`` any edge
whose grid comes within :data:`GROWTH_MARGIN` of it (the per-edge path grades those), and every run with
``min_length`` or ``max_length`` takes the per-edge path: a black box
(:class:`~cadedge.occt.edgecurve.EdgeCurve`) refined by :func:`cadedge.refine_curve`. Either way the
grid's first and last points are then replaced by the B-rep vertex points, so an edge's ends are
bit-identical in every edge sharing the vertex (downstream meshers match nodes exactly). Degenerate edges are flagged, not refined. With ``max_growth`` the end
segments meeting at a vertex are graded (see :mod:`cadedge.occt.vertexgrowth`).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping
from typing import Any, Callable

import numpy as np
from OCP.BRep import BRep_Tool

from ..errors import CadedgeWarning, CurveEvaluationError, GeometryError, InputError
from ..grid import polyline_length
from ..options import refine_options
from ..refine import refine_curve
from ..shapegrid import ShapeEdgeGrid, ShapeGrid, VertexGrid, vertex_spacings
from ..splitting import worst_growth
from ..target import MIN_CLOSED_SEGMENTS
from .edgecurve import EdgeCurve
from .edgetable import EdgeTable, TableCurves, refine_table
from .localald import check_ald_for, edge_targets
from .reader import load_shape, tolerance_warnings
from .topology import Topology, curve_type_name
from .vertexgrowth import grade_vertices

Progress = Callable[[int, int], None]
#: Most segments in the grids of one model (about 100 MB of points and parameters, far more as JSON):
#: a target that needs more is refused with a clear error instead of exhausting memory.
MAX_MODEL_SEGMENTS = 5_000_000
#: Edges refined per compiled call: between calls the segment count is checked against the limit above.
CHUNK = 256
#: With ``max_growth``, a compiled grid whose adjacent segments' worst ratio is over ``max_growth`` times
#: ``1 - GROWTH_MARGIN`` is refined again by the per-edge path, which grades it. The per-edge path judges
#: the grid before its ends are put on the vertices, the compiled one after: the margin keeps the two
#: judgements alike unless snapping an end moves its segment's length by more than this share. The mesher
#: refines with ``max_growth`` 2 (the Koch leader arm: 13 of 12 104 edges over it; reading and refining
#: it took 9.5 s with the per-edge path for all of them, now 6.0).
GROWTH_MARGIN = 1e-3


def _anchor(points: np.ndarray, first: np.ndarray, last: np.ndarray, estimate: float) -> tuple[np.ndarray, float]:
    """Put the vertex points at the ends; shift the deficit estimate by the change in length.

    The refiner's estimate is ``1 - length / total``; ``total`` is recovered from it and kept.
    """
    old = polyline_length(points)
    pts = points.copy()
    pts[0], pts[-1] = first, last
    new = polyline_length(pts)
    if old <= 0.0 or estimate >= 1.0:
        return pts, estimate
    total = old / (1.0 - estimate)
    return pts, max(1.0 - new / total, 0.0)


def _refine_edge(topo: Topology, i: int, vpoints: np.ndarray, src: str, opts: dict[str, Any],
                 notes: list[str], curves: dict[int, EdgeCurve], tolerance: float) -> ShapeEdgeGrid:
    eid = i + 1
    edge = topo.edges[i]
    v1, v2 = topo.edge_vertices[i]
    p1, p2 = vpoints[v1 - 1], vpoints[v2 - 1]
    degenerate = topo.is_degenerate(i)
    common = dict(id=eid, vertices=(v1, v2), degenerate=degenerate, closed=topo.is_closed(i),
                  faces=list(topo.edge_faces[i]), tolerance=tolerance)
    if degenerate:
        try:
            kind = topo.curve_type(i)
        except GeometryError:
            kind = "OtherCurve"  # a degenerate edge without even a curve on a surface
        first, last = BRep_Tool.Range_s(edge)
        return ShapeEdgeGrid(params=np.array([first, last], dtype=float), points=np.array([p1, p1]),
                             ald_estimate=0.0, evaluations=0, curve=kind, **common)
    try:
        curve = curves[eid] = EdgeCurve(edge, eid)
        grid = refine_curve(curve, curve.domain, **opts)
    except CurveEvaluationError as exc:
        raise GeometryError(f"{src}: edge {eid}: {exc}") from exc
    except InputError as exc:  # an option this edge cannot honour (e.g. a max_length past the cap)
        raise InputError(f"{src}: edge {eid}: {exc}") from exc
    except GeometryError as exc:  # EdgeCurve's messages already name the edge
        raise GeometryError(f"{src}: {exc}") from exc
    common["curve"] = curve_type_name(curve.kind)
    points, estimate = _anchor(grid.points, p1, p2, grid.ald_estimate)
    notes.extend(f"edge {eid}: {w}" for w in grid.warnings)
    if estimate > opts["ald"] and grid.ald_estimate <= opts["ald"]:
        notes.append(f"edge {eid}: ald {estimate:.3g} after snapping the ends to the vertices "
                     f"(vertices lie off the curve by up to {common['tolerance']:.3g})")
    return ShapeEdgeGrid(params=grid.params, points=points, ald_estimate=estimate,
                         evaluations=grid.evaluations, **common)


def _refine_rows(table: EdgeTable, rows: slice, targets: np.ndarray, vpoints: np.ndarray, topo: Topology,
                 tolerance: list[float],
                 max_growth: float | None = None) -> list[tuple[ShapeEdgeGrid, str | None] | None]:
    """Grids of the table's ``rows`` in one compiled call, anchored on their vertices: per row, its grid and the
    note it adds (or None), or None where the per-edge path must refine the edge (the compiled path could not
    finish it alike, a closed edge got fewer than ``MIN_CLOSED_SEGMENTS`` segments: see refine_target, or
    its segments grow by near ``max_growth`` or more: see :data:`GROWTH_MARGIN`)."""
    edge_ids = table.rows[rows]
    ends = [topo.edge_vertices[i] for i in edge_ids]
    at = np.array(ends, dtype=np.int64).reshape(-1, 2) - 1
    ald = targets[edge_ids]
    status, offsets, params, points, estimate, raw, evaluations = refine_table(
        table, rows, ald, vpoints[at[:, 0]], vpoints[at[:, 1]])
    bounds = offsets.tolist()
    faces = topo.edge_faces
    out: list[tuple[ShapeEdgeGrid, str | None] | None] = []
    for i, (v1, v2), name, failed, lo, hi, est, raw_est, evals, target in zip(
            edge_ids, ends, table.names[rows], status.tolist(), bounds, bounds[1:], estimate.tolist(), raw.tolist(),
            evaluations.tolist(), ald.tolist()):
        if failed or (v1 == v2 and hi - lo - 1 < MIN_CLOSED_SEGMENTS) or (
                max_growth is not None and worst_growth(points[lo:hi]) > max_growth * (1.0 - GROWTH_MARGIN)):
            out.append(None)
            continue
        note = None
        if est > target and raw_est <= target:
            note = (f"edge {i + 1}: ald {est:.3g} after snapping the ends to the vertices "
                    f"(vertices lie off the curve by up to {tolerance[i]:.3g})")
        out.append((ShapeEdgeGrid(id=i + 1, vertices=(v1, v2), degenerate=False, closed=v1 == v2,
                                  faces=list(faces[i]), tolerance=tolerance[i], curve=name, params=params[lo:hi],
                                  points=points[lo:hi], ald_estimate=est, evaluations=evals), note))
    return out


def refine_shape(source: Any, *, ald: float = 1e-3, min_length: float | None = None,
                 max_length: float | None = None, max_growth: float | None = None,
                 ald_for: Mapping[Any, float] | None = None,
                 progress: Progress | None = None, allow_partial: bool = False) -> ShapeGrid:
    """Refine every edge of ``source`` (STEP path, cadquery/build123d shape or ``TopoDS_Shape``).

    Edges and vertices are listed in ``TopExp::MapShapes`` order, degenerate edges included and
    flagged. ``progress(done, total)`` is called after each edge. Per-edge notes from the refiner go
    to ``ShapeGrid.warnings`` (prefixed with the edge id) instead of the warnings module.

    ``ald_for`` maps edges or faces to their own target (see :mod:`cadedge.occt.localald`): keys are
    build123d/cadquery edges or faces (or a cadquery Workplane selection of them), ``TopoDS_Edge``/
    ``TopoDS_Face`` shapes matched with ``IsSame``, or ids ``("edge", n)``/``("face", n)``. A face means
    its edges; each edge gets the finest of ``ald`` and every setting reaching it. The settings are
    recorded by id in ``options["ald_for"]``.
    """
    opts = refine_options(ald, min_length, max_length, max_growth)  # before the (possibly slow) read
    local = check_ald_for(ald_for)
    t0 = time.perf_counter()
    loaded = load_shape(source, allow_partial=allow_partial, tolerance_scan=False)
    try:
        topo = Topology(loaded.shape)
    except GeometryError as exc:
        raise GeometryError(f"{loaded.source}: {exc}") from exc
    loaded.warnings += tolerance_warnings(loaded.shape, loaded.units, loaded.declared, topo.dump)
    try:
        targets, local_records, notes = edge_targets(local, topo, opts["ald"])
    except InputError as exc:
        raise InputError(f"{loaded.source}: {exc}") from exc
    vpoints = topo.vertex_points()
    edge_tolerance, vertex_tolerance = topo.tolerances()
    total = len(topo.edges)
    batched = opts["min_length"] is None and opts["max_length"] is None
    table = EdgeTable(topo.edges, topo.non_degenerate() if batched else [], topo.dump)
    row_of = {i: r for r, i in enumerate(table.rows)}
    edges: list[ShapeEdgeGrid] = []
    curves: dict[int, EdgeCurve] = {}  # built by the per-edge path; the table's are built on demand
    segments = 0
    done = 0  # table rows refined so far
    start, chunk = 0, []  # the rows refined by the last compiled call, from row start
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CadedgeWarning)  # collected per edge in notes instead
        for i in range(total):
            r = row_of.get(i)
            if r is not None and r >= done:  # refine the next rows of the table in one compiled call
                start, done = r, min(r + CHUNK, len(table))
                chunk = _refine_rows(table, slice(start, done), targets, vpoints, topo, edge_tolerance,
                                     opts["max_growth"])
            made = chunk[r - start] if r is not None else None
            if made is not None:
                grid, note = made
                if note is not None:
                    notes.append(note)
            else:
                edge_opts = {**opts, "ald": float(targets[i])}  # the edge's own target (ald_for)
                grid = _refine_edge(topo, i, vpoints, loaded.source, edge_opts, notes, curves, edge_tolerance[i])
            edges.append(grid)
            segments += len(edges[-1].params) - 1
            if segments > MAX_MODEL_SEGMENTS:
                raise InputError(f"{loaded.source}: the grids would exceed {MAX_MODEL_SEGMENTS:,} segments "
                                 f"(reached after {i + 1} of {total} edges); use a larger ald")
            if progress is not None:
                progress(i + 1, total)
    curves = TableCurves(table, [i + 1 for i in table.rows], curves, topo.edges)
    if opts["max_growth"] is not None:
        try:
            edges, graded = grade_vertices(edges, curves, opts["max_growth"], targets)
            notes += graded
        except GeometryError as exc:
            raise GeometryError(f"{loaded.source}: grading edge ends at vertices: {exc}") from exc
    spacing = vertex_spacings(edges)
    vertices = [VertexGrid(id=k + 1, point=p, spacing=spacing.get(k + 1), tolerance=tol)
                for k, (p, tol) in enumerate(zip(vpoints, vertex_tolerance))]
    return ShapeGrid(source=loaded.source, units=loaded.units,
                     options={**opts, "ald_for": local_records} if local_records else dict(opts),
                     vertices=vertices, edges=edges, faces=len(topo.faces),
                     seconds=time.perf_counter() - t0, warnings=loaded.warnings + notes, shape=loaded.shape,
                     curves=curves)
