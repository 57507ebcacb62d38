"""Dense, derivative-free exploration of a curve: where it bends, and how long it really is.

The curve is covered by *triples* (a, m, b), m the parameter midpoint. A triple's gain
``G = |am| + |mb| - |ab|`` is what its midpoint added to the length; on a smooth stretch the deficit
of a chord falls eightfold per halving, so the polyline a-m-b still misses about ``G / 3``
(Richardson). That estimate is trusted only in the asymptotic regime: when a triple is split, the
gains of its two halves must add up to about a quarter of its own (we accept up to 0.35). A chord
that skipped a feature (oscillation, a narrow bump, a cusp between samples) fails that test and is
split again, whatever its gain looks like. All triples of a level are split in one batched evaluation.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .compiled import distance, jit
from .grid import polyline_length, row_norms

#: Root triples for a curve that gives no hint of its own: features narrower than about
#: 1/(2 * ROOTS) of the parameter domain can hide between the first samples.
ROOTS = 64
#: A triple is in the asymptotic regime when its halves' gains add up to at most this share of its own
#: (1/4 on a smooth stretch; 1/2 where a chord skips a cusp, whose deficit only falls with h**2).
ASYMPTOTIC_RATIO = 0.35
#: Gains below this share of the triple's length count as straight (rounding noise, lines).
STRAIGHT = 1e-13
#: Gains below this share of the largest coordinate count as straight too: the points themselves are
#: only that exact, so a small edge far from the origin shows rounding noise that never shrinks.
NOISE = 16 * np.finfo(float).eps


@dataclass
class Exploration:
    """Dense samples of a curve with a Richardson estimate of its length."""

    params: np.ndarray
    points: np.ndarray
    length_estimate: float
    remainder: float  # the part of length_estimate that the samples do not yet show
    corners: np.ndarray = field(default_factory=lambda: np.zeros(0))  # params of kinks that never smoothed out
    notes: list[str] = field(default_factory=list)

    def with_samples(self, params: np.ndarray, points: np.ndarray) -> "Exploration":
        """This exploration with more samples merged in (where a parameter repeats, the old sample stays)."""
        u, p = _sorted_unique(np.concatenate([self.params, params]), np.concatenate([self.points, points]))
        return dataclasses.replace(self, params=u, points=p)

    @cached_property
    def cumulative(self) -> np.ndarray:
        """Polyline length from the first sample to each sample (computed once; ``with_samples``
        returns a new exploration)."""
        return np.concatenate([[0.0], np.cumsum(row_norms(np.diff(self.points, axis=0)))])


def _sorted_unique(u: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Samples sorted by parameter, the first of any repeated parameter kept."""
    order = np.argsort(u, kind="stable")
    u, p = u[order], p[order]
    keep = np.concatenate([[True], np.diff(u) > 0])
    return u[keep], p[keep]


@jit
def _gain(pa, i, pm, j, pb, k):
    """(gain, two half chords) of the triple pa[i], pm[j], pb[k]."""
    two = distance(pa, i, pm, j) + distance(pm, j, pb, k)
    return max(two - distance(pa, i, pb, k), 0.0), two


@jit
def _classify(ua, um, ub, pa, pm, pb, ratio, tol, scale, min_width, noise):
    """One level: which live triples are finished, what they leave unresolved, which split.

    Returns (remainder of the finished, params of new corners, indices to split, their gains, scale);
    ``scale`` < 0 asks for it to be set from this (first) level's half chords.
    """
    n = len(ua)
    g = np.empty(n)
    two = np.empty(n)
    for i in range(n):
        g[i], two[i] = _gain(pa, i, pm, i, pb, i)
    if scale < 0.0:
        scale = max(two.sum(), 0.0)
    remainder = 0.0
    corners = np.empty(n)
    split = np.empty(n, dtype=np.int64)
    n_corners = n_split = 0
    for i in range(n):
        straight = g[i] <= max(STRAIGHT * max(two[i], scale * 1e-3), noise)
        resolved = g[i] / 3.0 <= tol * two[i] and ratio[i] <= ASYMPTOTIC_RATIO
        tiny = (ub[i] - ua[i]) <= min_width
        if straight:
            continue
        if resolved or tiny:
            remainder += g[i] / 3.0
            if tiny and not resolved:
                corners[n_corners] = um[i]
                n_corners += 1
        else:
            split[n_split] = i
            n_split += 1
    return remainder, corners[:n_corners].copy(), split[:n_split].copy(), g[split[:n_split]], scale


@jit
def _quarters(ua, um, ub, split):
    q = np.empty(2 * len(split))
    for k in range(len(split)):
        i = split[k]
        q[2 * k] = 0.5 * (ua[i] + um[i])
        q[2 * k + 1] = 0.5 * (um[i] + ub[i])
    return q


@jit
def _children(ua, um, ub, pa, pm, pb, split, gains, q, pq):
    """The live triples of the next level: (a, q1, m) and (m, q3, b) of each split (a, m, b), all
    left halves first, each with (G_left + G_right) / G_parent."""
    n = len(split)
    c_ua, c_um, c_ub = np.empty(2 * n), np.empty(2 * n), np.empty(2 * n)
    c_pa, c_pm, c_pb = np.empty((2 * n, 3)), np.empty((2 * n, 3)), np.empty((2 * n, 3))
    c_ratio = np.empty(2 * n)
    for k in range(n):
        i = split[k]
        gl = _gain(pa, i, pq, 2 * k, pm, i)[0]
        gr = _gain(pm, i, pq, 2 * k + 1, pb, i)[0]
        r = (gl + gr) / gains[k] if gains[k] > 0 else np.inf
        left, right = k, n + k
        c_ua[left], c_um[left], c_ub[left] = ua[i], q[2 * k], um[i]
        c_ua[right], c_um[right], c_ub[right] = um[i], q[2 * k + 1], ub[i]
        for d in range(3):  # element loops: row assignments compile several times slower
            c_pa[left, d], c_pm[left, d], c_pb[left, d] = pa[i, d], pq[2 * k, d], pm[i, d]
            c_pa[right, d], c_pm[right, d], c_pb[right, d] = pm[i, d], pq[2 * k + 1, d], pb[i, d]
        c_ratio[left] = c_ratio[right] = r
    return c_ua, c_um, c_ub, c_pa, c_pm, c_pb, c_ratio


def root_params(curve, a: float, b: float) -> np.ndarray:
    """Parameters that start the exploration: the curve's own hint, or a uniform grid."""
    hint = getattr(curve, "initial_params", None)
    if hint is not None:
        u = np.unique(np.concatenate([[a], np.clip(np.asarray(hint(a, b), dtype=float).ravel(), a, b), [b]]))
        if len(u) >= 2:
            return u
    return np.linspace(a, b, ROOTS + 1)


def explore(ev, a: float, b: float, tol: float, *, max_samples: int = 400_000) -> Exploration:
    """Sample the curve until the estimated remaining deficit is at most ``tol`` of its length.

    ``ev`` is the counting :class:`~cadedge.curves.Evaluator`. The work is bounded: triples narrower
    than ~1e-12 of the domain are not split, and at most ``max_samples`` points are taken (with a
    note when that cap decides the result).
    """
    notes: list[str] = []
    ua = root_params(ev.curve, a, b)
    um = 0.5 * (ua[:-1] + ua[1:])
    first = ev(np.concatenate([ua, um]))  # the roots and their midpoints in one batch
    pa_all, pm = first[:len(ua)], first[len(ua):]
    min_width = 1e-12 * (b - a)
    noise = NOISE * float(np.abs(first).max())

    # Live triples (one per current leaf interval); finished ones leave the live set.
    t_ua, t_ub, t_um = ua[:-1], ua[1:], um
    t_pa, t_pb, t_pm = pa_all[:-1], pa_all[1:], pm
    t_ratio = np.full(len(t_ua), np.nan)  # (G_self + G_sibling) / G_parent; nan for roots
    done_u: list[np.ndarray] = [ua, um]
    done_p: list[np.ndarray] = [pa_all, pm]
    remainder = 0.0
    corners: list[np.ndarray] = []
    samples = len(ua) + len(um)
    scale = -1.0
    while len(t_ua):
        rem, new_corners, split, gains, scale = _classify(t_ua, t_um, t_ub, t_pa, t_pm, t_pb, t_ratio, tol,
                                                          scale, min_width, noise)
        remainder += rem
        corners.append(new_corners)
        if not len(split):
            break
        if samples + 2 * len(split) > max_samples:
            remainder += float(np.sum(gains) / 3.0)
            notes.append(f"exploration stopped at {samples} samples; the length estimate may be low")
            break
        # Split: each triple (a, m, b) becomes (a, q1, m) and (m, q3, b); evaluate all quarter points at once.
        q = _quarters(t_ua, t_um, t_ub, split)
        pq = ev(q)
        samples += len(q)
        done_u.append(q)
        done_p.append(pq)
        t_ua, t_um, t_ub, t_pa, t_pm, t_pb, t_ratio = _children(t_ua, t_um, t_ub, t_pa, t_pm, t_pb, split,
                                                                gains, q, pq)

    u, p = _sorted_unique(np.concatenate(done_u), np.concatenate(done_p))
    dense = polyline_length(p)
    kinks = np.concatenate(corners) if corners else np.zeros(0)
    return Exploration(params=u, points=p, length_estimate=dense + remainder, remainder=remainder,
                       corners=np.unique(kinks) if len(kinks) else kinks, notes=notes)
