"""Paper mode: McLaurin & Shontz's Algorithm 2 (adaptive binary refinement) with exactly their criteria.

Start from the single segment [a, b]. Pop a segment from the list (a queue for ``order="breadth"``, a
stack for ``order="depth"``), place its best interior point with Algorithm 1 (:mod:`cadedge.search`),
and split it there when

* **local**: the two new chords exceed the old chord by more than ``local_delta`` of the old chord,
  ``r1 + r2 - c > local_delta * c``;
* **global**: the gain exceeds ``global_delta`` of the current polyline length,
  ``r1 + r2 - c > global_delta * L``;
* **max**: the old chord is longer than ``max_length``;

unless a new segment would be shorter than ``min_length`` (never split then). Nothing else is added.
Both deltas are compared by multiplication, never division: a closed curve's first chord has length 0,
its relative gain is infinite and it is split; a degenerate curve (one point) gains 0 and is not.

Breadth-first order is level order, so each level's searches run as one vectorised batch and the
decisions are then taken one by one in queue order (the global criterion sees the running length
exactly as in the sequential algorithm). Depth-first runs one search at a time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .grid import polyline_length
from .search import DEFAULT_SEARCH_TOL, best_split, golden_search

MAX_SEGMENTS = 100_000
"""Safety cap: beyond this many segments no segment is split (a note says so)."""

RICHARDSON = 4.0 / 3.0
"""On a smooth arc the best split recovers 3/4 of the chord's deficit, so deficit ~ 4/3 x gain."""


@dataclass
class _Segment:
    ua: float
    ub: float
    pa: np.ndarray
    pb: np.ndarray

    @property
    def chord(self) -> float:
        return float(np.linalg.norm(self.pb - self.pa))


class _Criteria:
    """Algorithm 2's split decision, with the running polyline length it needs."""

    def __init__(self, local_delta, global_delta, min_length, max_length, total):
        self.local_delta, self.global_delta = local_delta, global_delta
        self.min_length, self.max_length = min_length, max_length
        self.total = total  # current polyline length (old chords + gains of the splits so far)
        self.segments = 1
        self.capped = False

    def split(self, seg: _Segment, u: float, p: np.ndarray, two: float) -> bool:
        if not seg.ua < u < seg.ub:  # the segment is too narrow for an interior parameter
            return False
        r1, r2 = float(np.linalg.norm(p - seg.pa)), float(np.linalg.norm(seg.pb - p))
        if self.min_length is not None and min(r1, r2) < self.min_length:
            return False
        chord = seg.chord
        gain = two - chord
        wanted = ((self.local_delta is not None and gain > self.local_delta * chord)
                  or (self.global_delta is not None and gain > self.global_delta * self.total)
                  or (self.max_length is not None and chord > self.max_length))
        if wanted and self.segments >= MAX_SEGMENTS:
            self.capped = True
            return False
        if wanted:
            self.segments += 1
            self.total += gain
        return wanted


def refine_paper(ev, a: float, b: float, *, local_delta: float | None = None,
                 global_delta: float | None = None, min_length: float | None = None,
                 max_length: float | None = None, order: str = "breadth",
                 search_tol: float | None = None
                 ) -> tuple[np.ndarray, np.ndarray, float, list[str]]:
    """Algorithm 2 on ``ev`` (an :class:`cadedge.curves.Evaluator`) over [a, b].

    Returns ``(params, points, ald_estimate, notes)``: params strictly increasing from ``a`` to ``b``,
    points exactly as evaluated, and ``ald_estimate`` = ``g / (L + g)`` where ``L`` is the polyline
    length and ``g`` is 4/3 of the summed best-split gains of the final segments (each final segment
    was searched before it was kept, so this costs no evaluation). For smooth curves it tracks the true
    deficit; where a search found only a local maximum it underestimates.
    """
    tol = DEFAULT_SEARCH_TOL if search_tol is None else float(search_tol)
    ends = ev(np.array([a, b], dtype=float))
    root = _Segment(float(a), float(b), ends[0], ends[1])
    crit = _Criteria(local_delta, global_delta, min_length, max_length, root.chord)
    final: list[tuple[_Segment, float]] = []  # kept segments with their best-split gain

    def decide(seg: _Segment, u: float, p: np.ndarray, two: float) -> list[_Segment]:
        if crit.split(seg, u, p, two):
            return [_Segment(seg.ua, u, seg.pa, p), _Segment(u, seg.ub, p, seg.pb)]
        final.append((seg, max(two - seg.chord, 0.0)))
        return []

    if order == "breadth":
        level = [root]
        while level:
            us, ps, twos = golden_search(ev, np.array([s.ua for s in level]), np.array([s.ub for s in level]),
                                         np.array([s.pa for s in level]), np.array([s.pb for s in level]), tol)
            level = [child for s, u, p, f in zip(level, us, ps, twos)
                     for child in decide(s, float(u), p, float(f))]
    elif order == "depth":
        stack = [root]
        while stack:
            s = stack.pop()
            stack.extend(decide(s, *best_split(ev, s.ua, s.ub, s.pa, s.pb, tol)))
    else:
        raise InputError(f"order must be 'breadth' or 'depth', got {order!r}")

    final.sort(key=lambda item: item[0].ua)
    params = np.array([s.ua for s, _ in final] + [float(b)])
    points = np.array([s.pa for s, _ in final] + [final[-1][0].pb])
    length = polyline_length(points)
    g = RICHARDSON * sum(gain for _, gain in final)
    estimate = g / (length + g) if length + g > 0 else 0.0
    notes = []
    if crit.capped:
        notes.append(f"paper mode stopped splitting at the safety cap of {MAX_SEGMENTS} segments; "
                     "the criteria were not met (is the curve fractal or the delta too small?)")
    return params, points, estimate, notes
