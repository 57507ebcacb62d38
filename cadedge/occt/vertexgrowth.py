"""Grading edge ends at shared vertices so neighbouring segments differ by at most ``max_growth``.

Within an edge ``refine_curve`` limits growth; across a vertex the end segments of different edges are
unrelated. Here each edge end gets a cap, ``g`` times the shortest end segment at its vertex, and
each edge is split until its end segments respect the caps and adjacent segments differ by at most
``g``. A segment of length ``L`` that is too long next to an allowed size ``A`` (``g`` times the
short neighbour, or the cap) is split into ``A`` on the short side and ``L - A`` when ``L >= 2 A``,
else into two halves; repeated, this grades geometrically away from the short side. Caps are
recomputed until nothing changes, since splitting an edge's far end changes the shortest end segment
at its other vertex. No piece is made shorter than ``1/g`` of the shortest segment on the edge or
at its vertices, nor than ``1/g`` of the shortest segment of the whole shape before grading, so it
terminates; for ``g >= sqrt(2)`` halves never fall below that floor, below ``sqrt(2)`` some limits
may stay unmet and a note names the edges.

New points lie on the curve (placed by arc length along a small dense sampling of the split
segment, :func:`cadedge.splitting.point_at_arc`); vertex points stay bit-identical. Splitting only
lengthens the polyline, so the deficit only falls. Grids are replaced, never edited in place.
"""

from __future__ import annotations

import dataclasses
from collections import defaultdict
from typing import Mapping

import numpy as np

from ..grid import row_norms
from ..shapegrid import ShapeEdgeGrid
from ..splitting import insert_points, point_at_arc
from .edgecurve import EdgeCurve

#: Samples along a segment to place a new point by arc length.
DENSE = 17
#: Relative slack on the ratio checks (chords are placed by arc length, not exactly).
SLACK = 1e-6
#: Upper bound on splits per edge and on global rounds (safety bounds; not reached in practice).
MAX_SPLITS = 5000
MAX_ROUNDS = 50


def _allowed(seg: np.ndarray, g: float, caps: tuple[float | None, float | None]) -> tuple[np.ndarray, np.ndarray]:
    """Per segment: the longest allowed length and whether its tighter neighbour is at its start."""
    inf = np.full(1, np.inf)
    before = g * np.concatenate([inf if caps[0] is None else [caps[0] / g], seg[:-1]])
    after = g * np.concatenate([seg[1:], inf if caps[1] is None else [caps[1] / g]])
    return np.minimum(before, after), before <= after


def _fix_edge(e: ShapeEdgeGrid, curve: EdgeCurve, g: float, caps: tuple[float | None, float | None],
              floor: float) -> tuple[ShapeEdgeGrid, int, bool]:
    """``e`` split until caps and growth hold: (the new grid, points inserted, all limits met).

    No piece shorter than ``floor`` is made, which bounds the work; for ``g < sqrt(2)`` that can
    leave a limit unmet.
    """
    params, points, evaluations = e.params, e.points, e.evaluations
    seg = row_norms(np.diff(points, axis=0))
    count = 0
    for count in range(MAX_SPLITS):
        allowed, short_at_start = _allowed(seg, g, caps)
        halves = seg < 2.0 * allowed
        bad = (seg > allowed * (1 + SLACK)) & ~(halves & (0.5 * seg < floor * (1 - SLACK)))
        if not bad.any():
            break
        j = int(np.argmax(bad))
        dist = 0.5 * seg[j] if halves[j] else allowed[j]
        fwd = bool(short_at_start[j])
        u, p, n = point_at_arc(curve.evaluate, params[j], params[j + 1], points[j] if fwd else points[j + 1], dist,
                               from_start=fwd, dense=DENSE)
        evaluations += n
        longer = insert_points(params, points, np.array([u]), p[None, :])
        if len(longer[0]) == len(params):
            break  # the point fell on a node: this segment cannot be split further
        params, points = longer
        seg = row_norms(np.diff(points, axis=0))
    else:
        count = MAX_SPLITS
    met = count < MAX_SPLITS and not np.any(seg > _allowed(seg, g, caps)[0] * (1 + SLACK))
    if count == 0:
        return e, 0, met
    return dataclasses.replace(e, params=params, points=points, evaluations=evaluations), count, met


def _caps(edges: list[ShapeEdgeGrid], g: float) -> dict[int, float]:
    """``g`` times the shortest end segment at each vertex where two or more edge ends meet."""
    ends: dict[int, list[float]] = defaultdict(list)
    for e in edges:
        if not e.degenerate:
            first, last = e.spacing
            ends[e.vertices[0]].append(first)
            ends[e.vertices[1]].append(last)
    return {vid: g * min(s) for vid, s in ends.items() if len(s) > 1}


def grade_vertices(edges: list[ShapeEdgeGrid], curves: Mapping[int, EdgeCurve],
                   g: float) -> tuple[list[ShapeEdgeGrid], list[str]]:
    """Grade every edge against its vertex caps and ``g``: (new edge list, notes).

    ``curves`` maps edge ids to their curves (those refine_shape built). The notes name edges where the
    limits could not be met within the split budget.
    """
    edges = list(edges)
    totals = {k: e.length / (1.0 - e.ald_estimate) for k, e in enumerate(edges)
              if not e.degenerate and e.ald_estimate < 1.0 and e.length > 0.0}
    notes: list[str] = []
    met: dict[int, bool] = {}
    live = [e for e in edges if not e.degenerate and e.segments]
    if not live:
        return edges, []
    lowest = min(float(e.segment_lengths.min()) for e in live) / g
    for _ in range(MAX_ROUNDS):
        caps = _caps(edges, g)
        changed = False
        for k, e in enumerate(edges):
            if e.degenerate or e.segments == 0:
                continue
            ends = (caps.get(e.vertices[0]), caps.get(e.vertices[1]))
            floor = max(lowest, min([float(e.segment_lengths.min())] + [c / g for c in ends if c is not None]) / g)
            edges[k], inserted, met[k] = _fix_edge(e, curves[e.id], g, ends, floor)
            changed = changed or inserted > 0
        if not changed:
            break
    else:
        notes.append(f"max_growth {g:g} across vertices not settled after {MAX_ROUNDS} rounds")
    notes += [f"edge {k + 1}: max_growth {g:g} not met everywhere (below sqrt(2) splitting needs "
              "pieces shorter than the edge's shortest segment)" for k, ok in sorted(met.items()) if not ok]
    for k, total in totals.items():
        edges[k] = dataclasses.replace(edges[k], ald_estimate=max(1.0 - edges[k].length / total, 0.0))
    return edges, notes
