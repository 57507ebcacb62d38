"""``refine_shape``: edge grids for every edge of a B-rep shape, anchored on its vertices.

Each non-degenerate edge is refined as a black box (:class:`~cadedge.occt.edgecurve.EdgeCurve`) by
:func:`cadedge.refine_curve` in target mode. Its first and last points are then replaced by the B-rep
vertex points, so an edge's ends are bit-identical in every edge sharing the vertex (downstream
meshers match nodes exactly). Degenerate edges are flagged, not refined. With ``max_growth`` the end
segments meeting at a vertex are graded (see :mod:`cadedge.occt.vertexgrowth`).
"""

from __future__ import annotations

import time
import warnings
from typing import Any, Callable

import numpy as np
from OCP.BRep import BRep_Tool

from ..errors import CadedgeWarning, CurveEvaluationError, GeometryError
from ..grid import polyline_length
from ..options import refine_options
from ..refine import refine_curve
from ..shapegrid import ShapeEdgeGrid, ShapeGrid, VertexGrid, vertex_spacings
from .edgecurve import EdgeCurve
from .reader import load_shape
from .topology import Topology, curve_type_name
from .vertexgrowth import grade_vertices

Progress = Callable[[int, int], None]


def _point(vertex) -> np.ndarray:
    return np.array(BRep_Tool.Pnt_s(vertex).Coord(), dtype=float)


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


def _refine_edge(topo: Topology, i: int, vpoints: list[np.ndarray], src: str, opts: dict[str, Any],
                 notes: list[str], curves: dict[int, EdgeCurve]) -> ShapeEdgeGrid:
    eid = i + 1
    edge = topo.edges[i]
    v1, v2 = topo.edge_vertices[i]
    p1, p2 = vpoints[v1 - 1], vpoints[v2 - 1]
    degenerate = topo.is_degenerate(i)
    common = dict(id=eid, vertices=(v1, v2), degenerate=degenerate, closed=topo.is_closed(i),
                  faces=list(topo.edge_faces[i]), tolerance=float(BRep_Tool.Tolerance_s(edge)))
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


def refine_shape(source: Any, *, ald: float = 1e-3, min_length: float | None = None,
                 max_length: float | None = None, max_growth: float | None = None,
                 progress: Progress | None = None) -> ShapeGrid:
    """Refine every edge of ``source`` (STEP path, cadquery/build123d shape or ``TopoDS_Shape``).

    Edges and vertices are listed in ``TopExp::MapShapes`` order, degenerate edges included and
    flagged. ``progress(done, total)`` is called after each edge. Per-edge notes from the refiner go
    to ``ShapeGrid.warnings`` (prefixed with the edge id) instead of the warnings module.
    """
    opts = refine_options(ald, min_length, max_length, max_growth)  # before the (possibly slow) read
    t0 = time.perf_counter()
    loaded = load_shape(source)
    try:
        topo = Topology(loaded.shape)
    except GeometryError as exc:
        raise GeometryError(f"{loaded.source}: {exc}") from exc
    vpoints = [_point(v) for v in topo.vertices]
    notes: list[str] = []
    edges: list[ShapeEdgeGrid] = []
    curves: dict[int, EdgeCurve] = {}  # one adaptor per edge, kept for grading and later splitting
    total = len(topo.edges)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CadedgeWarning)  # collected per edge in notes instead
        for i in range(total):
            edges.append(_refine_edge(topo, i, vpoints, loaded.source, opts, notes, curves))
            if progress is not None:
                progress(i + 1, total)
    if opts["max_growth"] is not None:
        try:
            edges, graded = grade_vertices(edges, curves, opts["max_growth"])
            notes += graded
        except GeometryError as exc:
            raise GeometryError(f"{loaded.source}: grading edge ends at vertices: {exc}") from exc
    spacing = vertex_spacings(edges)
    vertices = [VertexGrid(id=k + 1, point=p, spacing=spacing.get(k + 1),
                           tolerance=float(BRep_Tool.Tolerance_s(topo.vertices[k])))
                for k, p in enumerate(vpoints)]
    return ShapeGrid(source=loaded.source, units=loaded.units,
                     options=dict(opts),
                     vertices=vertices, edges=edges, faces=len(topo.faces),
                     seconds=time.perf_counter() - t0, warnings=loaded.warnings + notes, shape=loaded.shape,
                     curves=curves)
