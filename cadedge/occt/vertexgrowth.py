"""Grading edge ends at shared vertices so neighbouring segments differ by at most ``max_growth``.

Within an edge ``refine_curve`` limits growth; across a vertex the end segments of different edges are
unrelated. Here each edge end gets a cap, ``g`` times the shortest end segment at its vertex, and the
edges are changed until their end segments respect the caps and adjacent segments differ by at most
``g``. Caps are recomputed round after round until nothing changes, since changing an edge's far end
changes the shortest end segment at its other vertex. Two regimes:

- ``g`` at least the golden ratio (the mesh default 2.0): splitting. A segment of length ``L`` too
  long next to an allowed size ``A`` (``g`` times the short neighbour, or the cap) is split into ``A``
  on the short side and ``L - A`` when ``L >= 2 A``, else into two halves; repeated, this grades
  geometrically away from the short side, and the other points stay where they are. No piece is made
  shorter than ``1/g`` of the shortest segment on the edge or at its vertices, nor than ``1/g`` of the
  shortest segment of the whole shape before grading, so it terminates.
- ``g`` below the golden ratio: re-placement. There splitting cannot stop (a segment cut in two
  leaves a far piece of at most ``g / (1 + g)`` of it, which an equal neighbour exceeds ``g``-fold, so
  every segment to the edge's far end is cut, and through the caps every edge beyond: 917_fusee went
  from 3,340 segments to 87,567 at 1.5). An edge over a cap has its nodes re-placed along a size field
  graded from its capped ends (:func:`cadedge.splitting.regrade`), its deficit kept within its target.

New points lie on the curve; vertex points stay bit-identical. Splitting only lengthens the polyline,
so the deficit only falls; a re-placement is checked against the edge's target. Grids are replaced,
never edited in place. Notes name what is left unmet.
"""

from __future__ import annotations

import dataclasses
import math
from collections import defaultdict
from typing import Mapping, Sequence

import numpy as np

from ..explore import Exploration
from ..grid import polyline_length, row_norms
from ..shapegrid import ShapeEdgeGrid
from ..splitting import insert_points, regrade, worst_growth
from ..target import MARGIN
from .edgecurve import EdgeCurve

#: Relative slack on the ratio checks.
SLACK = 1e-6
#: A new piece is a chord just under its allowed length from the segment's end, found by :data:`PLACE_ROUNDS`
#: rounds of :data:`PLACE_SAMPLES` curve samples each (one batched evaluation a round). Placed by arc
#: length along a few samples, pieces came out a hair over their allowed length and were halved instead
#: of grown from, so graded pieces marched on at one size (a 1.1e-5 mm arc left by a union beside a
#: helical sweep: its 36 mm neighbour was cut into 1.1e-5 mm pieces, 5 000 a round, without end).
PLACE_SAMPLES = 7
PLACE_ROUNDS = 12
#: Upper bound on splits per edge and on global rounds (safety bounds; not reached in practice).
MAX_SPLITS = 5000
MAX_ROUNDS = 50
#: A split whose piece on the tight side keeps more than this share of the segment did not shorten it:
#: the segment's end lies off the curve by about its length (a vertex a tolerance away from the curve's
#: end, under a cap smaller than that). The edge keeps what it has; splitting on would repeat forever.
STUCK = 0.75
#: Below this growth (the golden ratio) splitting alone cannot stop: a segment cut in two leaves a far
#: piece of at most ``g / (1 + g)`` of it, which its equal neighbour exceeds ``g``-fold, so every
#: segment to the edge's far end would be cut, and through the vertex caps every edge beyond. There
#: the edges are first re-placed along a size field graded from their vertices.
GOLDEN = (1.0 + math.sqrt(5.0)) / 2.0
#: Samples per segment of the grid on which a re-placement measures arc length.
REGRADE_SAMPLES = 8
#: Ratio of the extra samples' distances from a capped end (they start at a quarter of its size).
END_STEP = 1.25


def _allowed(seg: np.ndarray, g: float, caps: tuple[float | None, float | None]) -> tuple[np.ndarray, np.ndarray]:
    """Per segment: the longest allowed length and whether its tighter neighbour is at its start."""
    inf = np.full(1, np.inf)
    before = g * np.concatenate([inf if caps[0] is None else [caps[0] / g], seg[:-1]])
    after = g * np.concatenate([seg[1:], inf if caps[1] is None else [caps[1] / g]])
    return np.minimum(before, after), before <= after


def _chord_under(evaluate, u0: float, u1: float, near: np.ndarray, dist: float, *,
                 from_start: bool) -> tuple[np.ndarray, np.ndarray]:
    """The parameter (1,) and point (1, 3) of the segment [u0, u1] whose chord from ``near`` (the point at
    ``u0`` if ``from_start``, else at ``u1``) is the last sampled under ``dist`` before the first at or
    over it: never over, and within a 8**-12 share of the segment's parameters of it.

    Not :func:`cadedge.splitting.points_at_distances`: its bisection returns the last midpoint, which may
    lie over ``dist``, and takes one curve evaluation per halving; 48 of them per split made grading
    boxed_sphere 2.3x slower (3.7 s against 1.4 s here)."""
    lo, hi = (u0, u1) if from_start else (u1, u0)
    p_lo = near[None, :]
    frac = np.arange(1, PLACE_SAMPLES + 1) / (PLACE_SAMPLES + 1)
    for _ in range(PLACE_ROUNDS):
        t = lo + (hi - lo) * frac
        pts = evaluate(t)
        over = np.flatnonzero(row_norms(pts - near) >= dist)
        k = int(over[0]) if len(over) else PLACE_SAMPLES
        if k > 0:
            lo, p_lo = float(t[k - 1]), pts[k - 1:k]
        if k < PLACE_SAMPLES:
            hi = float(t[k])
    return np.array([lo]), p_lo


def _fix_edge(e: ShapeEdgeGrid, curves: Mapping[int, EdgeCurve], g: float, caps: tuple[float | None, float | None],
              floor: float) -> tuple[ShapeEdgeGrid, int, bool]:
    """``e`` split on its curve (``curves[e.id]``, built only when a split is needed: most edges take
    none, and the compiled path builds none) until caps and growth hold: (the new grid, points
    inserted, all limits met).

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
        near = points[j] if fwd else points[j + 1]
        u_new, p_new = _chord_under(curves[e.id].evaluate, params[j], params[j + 1], near, dist, from_start=fwd)
        evaluations += PLACE_SAMPLES * PLACE_ROUNDS
        if np.linalg.norm(p_new[0] - near) > STUCK * seg[j]:
            break  # the segment's end lies off its curve by about its length: no split shortens it
        longer = insert_points(params, points, u_new, p_new)
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


def _end_segments(edges: list[ShapeEdgeGrid]) -> dict[int, list[float]]:
    """Vertex id -> the lengths of the end segments meeting there (non-degenerate edges)."""
    ends: dict[int, list[float]] = defaultdict(list)
    for e in edges:
        if not e.degenerate and e.segments:
            first, last = e.spacing
            ends[e.vertices[0]].append(first)
            ends[e.vertices[1]].append(last)
    return ends


def _caps(edges: list[ShapeEdgeGrid], g: float) -> dict[int, float]:
    """``g`` times the shortest end segment at each vertex where two or more edge ends meet."""
    return {vid: g * min(s) for vid, s in _end_segments(edges).items() if len(s) > 1}


def _regraded(e: ShapeEdgeGrid, curve: EdgeCurve, g: float, sizes: tuple[float | None, float | None],
              target: float, total: float) -> ShapeEdgeGrid:
    """``e`` with its nodes re-placed along a size field graded from ``sizes`` at its ends, its deficit
    against ``total`` kept within the edge's target (or its deficit before, if that was over).

    Arc length is measured on ``REGRADE_SAMPLES`` samples per segment of the grid; the ends (the vertex
    points) stay as they are.
    """
    calls = 0

    def evaluate(u: np.ndarray) -> np.ndarray:
        nonlocal calls
        calls += len(u)
        return curve.evaluate(u)

    u, p = e.params, e.points
    t = np.arange(1, REGRADE_SAMPLES) / REGRADE_SAMPLES
    mid = (u[:-1, None] + np.diff(u)[:, None] * t[None, :]).ravel()
    ex = Exploration(params=u, points=p, length_estimate=total, remainder=0.0).with_samples(mid, evaluate(mid))
    # near a capped end the field grows from a size far below the grid's: samples at geometric steps
    # from there, so the placement resolves it
    cum, reach = ex.cumulative, []
    for end, size in enumerate(sizes):
        if size is not None and size < cum[-1]:
            steps = (0.25 * size) * END_STEP ** np.arange(int(math.log(2.0 * cum[-1] / size) / math.log(END_STEP)) + 1)
            steps = steps[steps < 0.5 * cum[-1]]
            reach.append(steps if end == 0 else cum[-1] - steps)
    if reach:
        extra = np.interp(np.concatenate(reach), cum, ex.params)
        ex = ex.with_samples(extra, evaluate(extra))
    limit = max(target * (1.0 - MARGIN), e.ald_estimate) * total
    params, points = regrade(evaluate, ex, np.zeros(0, dtype=int), u, p, g, target, total, limit, end_sizes=sizes)
    if total - polyline_length(points) > limit * (1 + 1e-12):
        return e
    return dataclasses.replace(e, params=params, points=points, evaluations=e.evaluations + calls)


def _regrade_ends(edges: list[ShapeEdgeGrid], curves: Mapping[int, EdgeCurve], g: float,
                  targets: Sequence[float], totals: Mapping[int, float]) -> tuple[list[ShapeEdgeGrid], list[str]]:
    """Re-place the edges whose end segments exceed their vertex caps along size fields that start at
    ``sqrt(g)`` times the shortest end segment at each capped end (midway, on a log scale, between
    that segment and its cap), round after round until no end exceeds its cap: (new edges, notes).

    No splitting follows: below the golden ratio it would cascade (:data:`GOLDEN`). The notes name
    what is left unmet.
    """
    edges = list(edges)
    for _ in range(MAX_ROUNDS):
        caps = _caps(edges, g)
        changed = False
        for k, e in enumerate(edges):
            if e.degenerate or e.segments == 0 or k not in totals:
                continue
            ends = (caps.get(e.vertices[0]), caps.get(e.vertices[1]))
            if not any(c is not None and s > c * (1 + SLACK) for s, c in zip(e.spacing, ends)):
                continue
            sizes = (None if ends[0] is None else ends[0] / math.sqrt(g),
                     None if ends[1] is None else ends[1] / math.sqrt(g))
            edges[k] = _regraded(e, curves[e.id], g, sizes, float(targets[k]), totals[k])
            changed = changed or edges[k] is not e
        if not changed:
            break
    ends_at = _end_segments(edges)
    notes = [f"vertex {v}: max_growth {g:g} across vertices not met: its end segments differ up to "
             f"{max(s) / min(s):.3g}-fold" for v, s in sorted(ends_at.items())
             if len(s) > 1 and max(s) > g * min(s) * (1 + SLACK)]
    for k, e in enumerate(edges):
        if not e.degenerate and e.segments > 1 and worst_growth(e.points) > g * (1 + SLACK):
            notes.append(f"edge {k + 1}: max_growth {g:g} not met everywhere: worst ratio of adjacent "
                         f"segments is {worst_growth(e.points):.3g}")
    return edges, notes


def grade_vertices(edges: list[ShapeEdgeGrid], curves: Mapping[int, EdgeCurve], g: float,
                   targets: Sequence[float]) -> tuple[list[ShapeEdgeGrid], list[str]]:
    """Grade every edge against its vertex caps and ``g``: (new edge list, notes).

    ``curves`` maps edge ids to their curves (those refine_shape built), ``targets`` gives each edge's
    ALD target (kept when edges are re-placed, below the golden ratio). The notes name edges where the
    limits could not be met.
    """
    edges = list(edges)
    totals = {k: e.length / (1.0 - e.ald_estimate) for k, e in enumerate(edges)
              if not e.degenerate and e.ald_estimate < 1.0 and e.length > 0.0}
    live = [e for e in edges if not e.degenerate and e.segments]
    if not live:
        return edges, []
    if g < GOLDEN:
        edges, notes = _regrade_ends(edges, curves, g, targets, totals)
    else:
        edges, notes = _split_ends(edges, curves, g, live)
    for k, total in totals.items():
        edges[k] = dataclasses.replace(edges[k], ald_estimate=max(1.0 - edges[k].length / total, 0.0))
    return edges, notes


def _split_ends(edges: list[ShapeEdgeGrid], curves: Mapping[int, EdgeCurve], g: float,
                live: list[ShapeEdgeGrid]) -> tuple[list[ShapeEdgeGrid], list[str]]:
    """Split every edge until its vertex caps and ``g`` hold, round after round (``g`` at least the
    golden ratio, where splitting settles): (new edges, notes)."""
    notes: list[str] = []
    met: dict[int, bool] = {}
    settled: dict[int, tuple[float | None, float | None]] = {}  # edge -> the caps under which it took no split
    lowest = min(float(e.segment_lengths.min()) for e in live) / g
    for _ in range(MAX_ROUNDS):
        caps = _caps(edges, g)
        changed = False
        for k, e in enumerate(edges):
            if e.degenerate or e.segments == 0:
                continue
            ends = (caps.get(e.vertices[0]), caps.get(e.vertices[1]))
            if settled.get(k) == ends:  # the same edge under the same caps takes no split again (the
                continue  # tetrakaidecahedron lattice's refinement: 71 -> 69 s, the splits being most of it)
            floor = max(lowest, min([float(e.segment_lengths.min())] + [c / g for c in ends if c is not None]) / g)
            edges[k], inserted, met[k] = _fix_edge(e, curves, g, ends, floor)
            changed = changed or inserted > 0
            if inserted:
                settled.pop(k, None)
            else:
                settled[k] = ends
        if not changed:
            break
    else:
        notes.append(f"max_growth {g:g} across vertices not settled after {MAX_ROUNDS} rounds")
    notes += [f"edge {k + 1}: max_growth {g:g} not met everywhere (splitting would need pieces shorter "
              "than the edge's shortest segment)" for k, ok in sorted(met.items()) if not ok]
    return edges, notes
