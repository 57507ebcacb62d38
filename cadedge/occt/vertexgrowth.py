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
segment); vertex points stay bit-identical. Splitting only lengthens the polyline, so the deficit
only falls.
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np

from ..shapegrid import ShapeEdgeGrid
from .edgecurve import EdgeCurve
from .topology import Topology

#: Samples along a segment to place a new point by arc length.
DENSE = 17
#: Relative slack on the ratio checks (chords are placed by arc length, not exactly).
SLACK = 1e-6
#: Upper bound on splits per edge and on global rounds (safety bounds; not reached in practice).
MAX_SPLITS = 5000
MAX_ROUNDS = 50


def _split(e: ShapeEdgeGrid, curve: EdgeCurve, j: int, dist: float, from_start: bool) -> None:
    """Insert a point into segment ``j`` at arc distance ``dist`` from its start (or its end)."""
    u0, u1 = e.params[j], e.params[j + 1]
    us = np.linspace(u0, u1, DENSE) if from_start else np.linspace(u1, u0, DENSE)
    dense = curve.evaluate(us)
    dense[0] = e.points[j] if from_start else e.points[j + 1]
    cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(dense, axis=0), axis=1))])
    u = float(np.interp(dist, cum, us))
    e.params = np.insert(e.params, j + 1, u)
    e.points = np.insert(e.points, j + 1, curve.evaluate(np.array([u]))[0], axis=0)
    e.evaluations += DENSE + 1


def _allowed(seg: np.ndarray, g: float, caps: tuple[float | None, float | None]) -> tuple[np.ndarray, np.ndarray]:
    """Per segment: the longest allowed length and whether its tighter neighbour is at its start."""
    inf = np.full(1, np.inf)
    before = g * np.concatenate([inf if caps[0] is None else [caps[0] / g], seg[:-1]])
    after = g * np.concatenate([seg[1:], inf if caps[1] is None else [caps[1] / g]])
    return np.minimum(before, after), before <= after


def _fix_edge(e: ShapeEdgeGrid, curve: EdgeCurve, g: float, caps: tuple[float | None, float | None],
              floor: float) -> tuple[int, bool]:
    """Split segments of ``e`` until caps and growth hold; returns (points inserted, all limits met).

    No piece shorter than ``floor`` is made, which bounds the work; for ``g < sqrt(2)`` that can
    leave a limit unmet.
    """
    seg = e.segment_lengths
    for count in range(MAX_SPLITS):
        allowed, short_at_start = _allowed(seg, g, caps)
        halves = seg < 2.0 * allowed
        bad = (seg > allowed * (1 + SLACK)) & ~(halves & (0.5 * seg < floor * (1 - SLACK)))
        if not bad.any():
            return count, not np.any(seg > allowed * (1 + SLACK))
        j = int(np.argmax(bad))
        dist = 0.5 * seg[j] if halves[j] else allowed[j]
        _split(e, curve, j, dist, bool(short_at_start[j]))
        seg = e.segment_lengths
    return MAX_SPLITS, False


def _caps(edges: list[ShapeEdgeGrid], g: float) -> dict[int, float]:
    """``g`` times the shortest end segment at each vertex where two or more edge ends meet."""
    ends: dict[int, list[float]] = defaultdict(list)
    for e in edges:
        if not e.degenerate:
            first, last = e.spacing
            ends[e.vertices[0]].append(first)
            ends[e.vertices[1]].append(last)
    return {vid: g * min(s) for vid, s in ends.items() if len(s) > 1}


def grade_vertices(edges: list[ShapeEdgeGrid], topo: Topology, g: float) -> list[str]:
    """Grade every edge against its vertex caps and ``g``; edges are updated in place.

    Returns notes for edges where the limits could not be met within the split budget.
    """
    totals = {k: e.length / (1.0 - e.ald_estimate) for k, e in enumerate(edges)
              if not e.degenerate and e.ald_estimate < 1.0 and e.length > 0.0}
    curves: dict[int, EdgeCurve] = {}
    notes: list[str] = []
    met: dict[int, bool] = {}
    live = [e for e in edges if not e.degenerate and e.segments]
    if not live:
        return []
    lowest = min(float(e.segment_lengths.min()) for e in live) / g
    for _ in range(MAX_ROUNDS):
        caps = _caps(edges, g)
        changed = False
        for k, e in enumerate(edges):
            if e.degenerate or e.segments == 0:
                continue
            curve = curves.setdefault(k, EdgeCurve(topo.edges[k], k + 1))
            ends = (caps.get(e.vertices[0]), caps.get(e.vertices[1]))
            floor = max(lowest, min([float(e.segment_lengths.min())] + [c / g for c in ends if c is not None]) / g)
            inserted, met[k] = _fix_edge(e, curve, g, ends, floor)
            changed = changed or inserted > 0
        if not changed:
            break
    else:
        notes.append(f"max_growth {g:g} across vertices not settled after {MAX_ROUNDS} rounds")
    notes += [f"edge {k + 1}: max_growth {g:g} not met everywhere (below sqrt(2) splitting needs "
              "pieces shorter than the edge's shortest segment)" for k, ok in sorted(met.items()) if not ok]
    for k, total in totals.items():
        edges[k].ald_estimate = max(1.0 - edges[k].length / total, 0.0)
    return notes
