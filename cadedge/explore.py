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

from .grid import polyline_length, row_norms

#: Root triples for a curve that gives no hint of its own: features narrower than about
#: 1/(2 * ROOTS) of the parameter domain can hide between the first samples.
ROOTS = 64
#: A triple is in the asymptotic regime when its halves' gains add up to at most this share of its own
#: (1/4 on a smooth stretch; 1/2 where a chord skips a cusp, whose deficit only falls with h**2).
ASYMPTOTIC_RATIO = 0.35
#: Gains below this share of the triple's length count as straight (rounding noise, lines).
STRAIGHT = 1e-13


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


def _gains(pa: np.ndarray, pm: np.ndarray, pb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gain of each midpoint and the length of the two half chords."""
    two = row_norms(pm - pa) + row_norms(pb - pm)
    return np.maximum(two - row_norms(pb - pa), 0.0), two


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
    pa_all = ev(ua)
    um = 0.5 * (ua[:-1] + ua[1:])
    pm = ev(um)
    min_width = 1e-12 * (b - a)

    # Live triples (one per current leaf interval); finished ones are moved to `done`.
    t_ua, t_ub, t_um = ua[:-1], ua[1:], um
    t_pa, t_pb, t_pm = pa_all[:-1], pa_all[1:], pm
    t_ratio = np.full(len(t_ua), np.nan)  # (G_self + G_sibling) / G_parent; nan for roots
    done_u: list[np.ndarray] = [ua, um]
    done_p: list[np.ndarray] = [pa_all, pm]
    remainder = 0.0
    corners: list[np.ndarray] = []
    samples = len(ua) + len(um)
    scale = None
    while len(t_ua):
        g, two = _gains(t_pa, t_pm, t_pb)
        if scale is None:  # overall size, for the straightness test
            scale = max(float(np.sum(two)), 0.0)
        straight = g <= STRAIGHT * np.maximum(two, scale * 1e-3)
        asymptotic = t_ratio <= ASYMPTOTIC_RATIO
        small = g / 3.0 <= tol * two
        tiny = (t_ub - t_ua) <= min_width
        finished = straight | (small & asymptotic) | tiny
        remainder += float(np.sum(g[finished & ~straight]) / 3.0)
        corners.append(t_um[tiny & ~straight & ~(small & asymptotic)])
        split = ~finished
        if not split.any():
            break
        n_split = int(split.sum())
        if samples + 2 * n_split > max_samples:
            remainder += float(np.sum(g[split]) / 3.0)
            notes.append(f"exploration stopped at {samples} samples; the length estimate may be low")
            break
        # Split: each triple (a, m, b) becomes (a, q1, m) and (m, q3, b); evaluate all quarter points at once.
        sa, sm, sb = t_ua[split], t_um[split], t_ub[split]
        pa, pm_, pb = t_pa[split], t_pm[split], t_pb[split]
        q = np.empty(2 * n_split)
        q[0::2] = 0.5 * (sa + sm)
        q[1::2] = 0.5 * (sm + sb)
        pq = ev(q)
        samples += len(q)
        done_u.append(q)
        done_p.append(pq)
        gl, _ = _gains(pa, pq[0::2], pm_)
        gr, _ = _gains(pm_, pq[1::2], pb)
        gp = g[split]
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(gp > 0, (gl + gr) / gp, np.inf)
        t_ua = np.concatenate([sa, sm])
        t_um = np.concatenate([q[0::2], q[1::2]])
        t_ub = np.concatenate([sm, sb])
        t_pa = np.concatenate([pa, pm_])
        t_pm = np.concatenate([pq[0::2], pq[1::2]])
        t_pb = np.concatenate([pm_, pb])
        t_ratio = np.concatenate([ratio, ratio])

    u, p = _sorted_unique(np.concatenate(done_u), np.concatenate(done_p))
    dense = polyline_length(p)
    return Exploration(params=u, points=p, length_estimate=dense + remainder, remainder=remainder,
                       corners=np.unique(np.concatenate(corners)) if corners else np.zeros(0), notes=notes)
