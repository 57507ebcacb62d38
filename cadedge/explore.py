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

from . import kernels
from .grid import polyline_length, row_norms, unique_sorted

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
#: Most samples one exploration takes.
MAX_SAMPLES = 400_000


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


def root_params(curve, a: float, b: float) -> np.ndarray:
    """Parameters that start the exploration: the curve's own hint, or a uniform grid."""
    hint = getattr(curve, "initial_params", None)
    if hint is not None:
        u = unique_sorted(np.concatenate([[a], np.clip(np.asarray(hint(a, b), dtype=float).ravel(), a, b), [b]]))
        if len(u) >= 2:
            return u
    return np.linspace(a, b, ROOTS + 1)


def explore(ev, a: float, b: float, tol: float, *, max_samples: int = MAX_SAMPLES) -> Exploration:
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
        rem, new_corners, split, gains, scale = kernels.classify(t_ua, t_um, t_ub, t_pa, t_pm, t_pb, t_ratio, tol,
                                                                 scale, min_width, noise, STRAIGHT,
                                                                 ASYMPTOTIC_RATIO)
        remainder += rem
        corners.append(new_corners)
        if not len(split):
            break
        if samples + 2 * len(split) > max_samples:
            remainder += float(np.sum(gains) / 3.0)
            notes.append(f"exploration stopped at {samples} samples; the length estimate may be low")
            break
        # Split: each triple (a, m, b) becomes (a, q1, m) and (m, q3, b); evaluate all quarter points at once.
        q = np.empty(2 * len(split))
        q[0::2] = 0.5 * (t_ua[split] + t_um[split])
        q[1::2] = 0.5 * (t_um[split] + t_ub[split])
        pq = ev(q)
        samples += len(q)
        done_u.append(q)
        done_p.append(pq)
        t_ua, t_um, t_ub, t_pa, t_pm, t_pb, t_ratio = kernels.children(t_ua, t_um, t_ub, t_pa, t_pm, t_pb, split,
                                                                       gains, q, pq)

    u, p = _sorted_unique(np.concatenate(done_u), np.concatenate(done_p))
    dense = polyline_length(p)
    kinks = np.concatenate(corners) if corners else np.zeros(0)
    return Exploration(params=u, points=p, length_estimate=dense + remainder, remainder=remainder,
                       corners=unique_sorted(kinks) if len(kinks) else kinks, notes=notes)
