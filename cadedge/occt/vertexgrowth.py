"""Grading edge ends at shared vertices so neighbouring end segments differ by at most ``max_growth``.

Within an edge, ``refine_curve`` limits growth; across a vertex the end segments of different edges
are unrelated. For each vertex, with ``s`` the shortest end segment there, every end segment longer
than ``g * s`` is split, from the vertex outwards, into pieces ``g s, g^2 s, ...`` followed by equal
pieces no longer than the next graded size. Consecutive new pieces grow by at most ``g`` (and
shrink by at most ``2 / g``, so for ``g >= sqrt(2)`` the whole run respects ``g``). Positions are
placed by arc length along a dense sampling of the split segment; new points lie on the curve and
the vertex point itself is kept bit-identical. Splitting only lengthens the polyline, so the
deficit only falls.
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from ..shapegrid import ShapeEdgeGrid
from .edgecurve import EdgeCurve
from .topology import Topology

#: Samples along a segment to place new points by arc length.
DENSE = 65


def _end_length(e: ShapeEdgeGrid, at_start: bool) -> float:
    seg = e.points[[0, 1]] if at_start else e.points[[-1, -2]]
    return float(np.linalg.norm(seg[1] - seg[0]))


def graded_positions(length: float, first: float, g: float) -> list[float]:
    """Distances from the vertex of the new points splitting an end segment of ``length``.

    Pieces ``first, first g, first g^2, ...`` while the rest can still take a piece ``g`` times the
    next, then the rest in equal pieces no longer than the next graded size.
    """
    pos, piece, out = 0.0, first, []
    while pos + piece + g * piece <= length:
        pos += piece
        out.append(pos)
        piece *= g
    rest = length - pos
    k = max(math.ceil(rest / piece - 1e-12), 1)
    out.extend(pos + rest * j / k for j in range(1, k))
    return out


def _split_end(e: ShapeEdgeGrid, curve: EdgeCurve, at_start: bool, first: float, g: float) -> None:
    """Split the end segment of ``e`` at its start or end vertex; updates ``e`` in place."""
    ua, ub = (e.params[0], e.params[1]) if at_start else (e.params[-1], e.params[-2])
    us = np.linspace(ua, ub, DENSE)
    dense = curve.evaluate(us)
    dense[0] = e.points[0] if at_start else e.points[-1]
    cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(dense, axis=0), axis=1))])
    pos = graded_positions(float(cum[-1]), first, g)
    if not pos:
        return
    new_u = np.interp(pos, cum, us)
    new_p = curve.evaluate(new_u)
    old_len = e.length
    if at_start:
        e.params = np.concatenate([e.params[:1], new_u, e.params[1:]])
        e.points = np.concatenate([e.points[:1], new_p, e.points[1:]])
    else:
        e.params = np.concatenate([e.params[:-1], new_u[::-1], e.params[-1:]])
        e.points = np.concatenate([e.points[:-1], new_p[::-1], e.points[-1:]])
    e.evaluations += DENSE + len(new_u)
    if old_len > 0.0 and e.ald_estimate < 1.0:
        total = old_len / (1.0 - e.ald_estimate)
        e.ald_estimate = max(1.0 - e.length / total, 0.0)


def grade_vertices(edges: list[ShapeEdgeGrid], topo: Topology, g: float) -> None:
    """Split end segments longer than ``g`` times the shortest end segment at their vertex."""
    ends: dict[int, list[tuple[int, bool]]] = defaultdict(list)
    for k, e in enumerate(edges):
        if not e.degenerate:
            ends[e.vertices[0]].append((k, True))
            ends[e.vertices[1]].append((k, False))
    curves: dict[int, EdgeCurve] = {}
    for vid in sorted(ends):
        at = ends[vid]
        if len(at) < 2:
            continue
        shortest = min(_end_length(edges[k], s) for k, s in at)
        cap = g * shortest
        for k, at_start in at:
            if _end_length(edges[k], at_start) > cap * (1.0 + 1e-9):
                curve = curves.setdefault(k, EdgeCurve(topo.edges[k], k + 1))
                _split_end(edges[k], curve, at_start, cap, g)
