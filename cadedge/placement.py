"""Choosing the fewest grid nodes among dense samples for a length budget.

For a chord over a smooth stretch the deficit grows with the cube of its length, so the fewest
segments for a total deficit are those that share it equally. The greedy cover takes, from each
node, the farthest sample whose chord misses at most ``cap`` of the dense polyline's length (farthest
reach is optimal for a per-segment cap because the deficit only grows as a chord is extended); a
bisection on ``cap`` finds the fewest nodes for the total budget. The polish then moves each interior
node to the sample between its neighbours that makes the two chords longest (the paper's Algorithm 1
on samples), odd nodes then even ones, so the length never decreases.

These are tight scalar loops over samples (a few dozen covers and polishes per edge), compiled C
(:mod:`cadedge.kernels`): a profile of the numpy version showed its per-call overhead dominating
whole-model runs. So are the deficit measure and the equidistribution along it, which run once or
twice per edge.
"""

from __future__ import annotations

import math

import numpy as np

from . import kernels
from .grid import polyline_length, unique_sorted


def chord_length(points: np.ndarray, nodes: np.ndarray) -> float:
    """Length of the polyline through ``points[nodes]``."""
    return polyline_length(points[nodes])


def fewest_nodes(points: np.ndarray, cum: np.ndarray, budget: float, *, min_length: float | None = None,
                 max_length: float | None = None, forced: np.ndarray | None = None, drop: bool = True) -> np.ndarray:
    """The fewest node indices (greedy + bisection on the cap, then polish) whose chords miss at most
    ``budget`` of ``cum[-1]``, the samples' polyline length.

    Chords stay at most ``max_length`` long and, where the curve allows, at least ``min_length``;
    ``forced`` sample indices (kinks) are always nodes. If even every sample is not enough
    (min_length), the densest admissible grid is returned. With ``drop`` the polished grid is then tried
    with a node fewer (a greedy cover one shorter, polished), as long as that meets the budget: a second
    bisection per node dropped, about a fifth of a compiled refine. Target mode skips it where its
    equidistributed placement competes (see :func:`cadedge.target.refine_target`).
    """
    points = np.ascontiguousarray(points, dtype=float)
    n = len(points)
    forced = np.zeros(0, dtype=np.int64) if forced is None else np.asarray(forced, dtype=np.int64)
    stops = unique_sorted(np.append(forced, n - 1)) if len(forced) else np.array([n - 1], dtype=np.int64)
    fixed = np.zeros(n, dtype=np.bool_)
    fixed[forced] = True
    return kernels.fewest(points, cum, float(budget), 0.0 if min_length is None else float(min_length),
                          math.inf if max_length is None else float(max_length), stops, fixed, drop)


def deficit_measure(points: np.ndarray, cum: np.ndarray, corners: np.ndarray | None = None) -> np.ndarray:
    """Cumulative measure M along the samples such that a chord spanning dM misses about dM**3.

    For a smooth stretch a chord of arc length S misses ``c * S**3`` (c = curvature**2 / 24). At each
    interior sample the two neighbouring intervals (h1, h2) give ``c`` derivative-free from the
    deficit ``d = 3 c h1 h2 (h1 + h2)`` of the chord that skips the sample. Equal steps of M are then
    the segments that share a deficit budget equally: the fewest for that budget. Samples listed in
    ``corners`` (kinks, which a node must sit on) contribute nothing.
    """
    corners = np.zeros(0, dtype=np.int64) if corners is None else np.asarray(corners, dtype=np.int64)
    return kernels.deficit_measure(points, cum, corners)


def equidistribute(params: np.ndarray, cum: np.ndarray, measure: np.ndarray, count: int,
                   corners: np.ndarray | None = None) -> np.ndarray:
    """``count`` segments' worth of parameters at equal steps of ``measure``, with every corner a node.

    Pieces between corners get whole numbers of segments in proportion to their measure (at least
    one each). Positions between samples are interpolated linearly in arc length, then in parameter.
    """
    last = len(params) - 1
    if corners is None or not len(corners):
        cut, alloc = np.array([0, last]), np.array([max(count, 1) if measure[last] > measure[0] else 1])
    else:
        cut = unique_sorted(np.concatenate([[0], corners, [last]])).astype(np.int64)
        share = np.diff(measure[cut])
        total = share.sum()
        pieces = len(share)
        if total <= 0:
            alloc = np.ones(pieces, dtype=np.int64)
        else:
            raw = share / total * max(count, pieces)
            alloc = np.maximum(np.floor(raw).astype(np.int64), 1)
            short = max(count, pieces) - alloc.sum()
            if short > 0:
                alloc[np.argsort(-(raw - alloc))[:short]] += 1
    return kernels.place(params, cum, measure, cut, alloc)
