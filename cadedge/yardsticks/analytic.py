"""Analytic test curves, each parametrised over [0, 1]: the paper's three and a harder family.

Used by the tests, the paper reproduction and the benchmarks. Every curve is an ordinary vectorised
black box (``evaluate``); the refiners learn nothing else about it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class AnalyticCurve:
    """A named vectorised curve on ``domain``; ``length`` is the known true length where one is."""

    name: str
    fn: Callable[[np.ndarray], np.ndarray]
    domain: tuple[float, float] = (0.0, 1.0)
    length: float | None = None

    def evaluate(self, u: np.ndarray) -> np.ndarray:
        return self.fn(np.asarray(u, dtype=float))


def _xy(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.column_stack([x, y])


def lissajous() -> AnalyticCurve:
    """x = sin(3t + 1), y = sin t, t in [0, 2 pi]: closed, self-intersecting (paper Fig. 6)."""
    return AnalyticCurve("lissajous", lambda u: _xy(np.sin(3 * TWO_PI * u + 1), np.sin(TWO_PI * u)))


def tricuspid() -> AnalyticCurve:
    """Deltoid x = 2cos t + cos 2t, y = 2 sin t - sin 2t: closed, three cusps, length 16 (Fig. 7)."""
    def fn(u):
        t = TWO_PI * u
        return _xy(2 * np.cos(t) + np.cos(2 * t), 2 * np.sin(t) - np.sin(2 * t))
    return AnalyticCurve("tricuspid", fn, length=16.0)


def cochleoid() -> AnalyticCurve:
    """Polar cochleoid r = sin(th)/th, th in (0, 2 pi], limit point (1, 0) at 0 (Fig. 8), length 2.9470.

    The paper prints x = 2t + 3 sin 7t, y = t + 8 cos 3t, a garbled formula (length 22.37 on [0, 1], not
    the table's 2.94); this is the curve that matches its tables (docs/paper.md).
    """
    def fn(u):
        th = TWO_PI * u
        r = np.sinc(th / np.pi)  # sin(th)/th with the limit 1 at th = 0
        return _xy(r * np.cos(th), r * np.sin(th))
    return AnalyticCurve("cochleoid", fn)


def paper_curves() -> list[AnalyticCurve]:
    """The paper's three test curves, in the order of its tables."""
    return [lissajous(), tricuspid(), cochleoid()]


def circle(radius: float = 1.0) -> AnalyticCurve:
    """A full circle: closed, so its first chord has zero length."""
    return AnalyticCurve("circle", lambda u: radius * _xy(np.cos(TWO_PI * u), np.sin(TWO_PI * u)),
                         length=TWO_PI * radius)


def oscillatory(periods: int = 20, amplitude: float = 0.05) -> AnalyticCurve:
    """A low-amplitude sine over a unit straight run: a two-point chord misses it entirely."""
    return AnalyticCurve(f"oscillatory{periods}",
                         lambda u: _xy(u, amplitude * np.sin(periods * TWO_PI * u)))


def astroid() -> AnalyticCurve:
    """x = cos^3 t, y = sin^3 t: closed, four cusps, length 6."""
    def fn(u):
        t = TWO_PI * u
        return _xy(np.cos(t) ** 3, np.sin(t) ** 3)
    return AnalyticCurve("astroid", fn, length=6.0)


def helix(turns: float = 3.0, radius: float = 1.0, pitch: float = 0.5) -> AnalyticCurve:
    """A 3-D helix."""
    def fn(u):
        t = TWO_PI * turns * u
        return np.column_stack([radius * np.cos(t), radius * np.sin(t), pitch * turns * u])
    length = turns * np.hypot(TWO_PI * radius, pitch)
    return AnalyticCurve("helix", fn, length=float(length))


def uneven(power: float = 8.0) -> AnalyticCurve:
    """A half ellipse whose parametrisation crawls then races: speed varies by orders of magnitude."""
    def fn(u):
        s = np.expm1(power * u) / np.expm1(power)  # ds/du ranges over a factor of e^power
        t = np.pi * s
        return _xy(2.0 * np.cos(t), np.sin(t))
    return AnalyticCurve("uneven", fn)


def narrow_bump(width: float = 2e-3, height: float = 0.05, at: float = 0.37) -> AnalyticCurve:
    """A straight unit run with a narrow Gaussian bump that a coarse chord misses."""
    return AnalyticCurve("narrow_bump", lambda u: _xy(u, height * np.exp(-0.5 * ((u - at) / width) ** 2)))


def spiral(turns: float = 4.0) -> AnalyticCurve:
    """Archimedean spiral r = theta from the centre: curvature falls from huge to small."""
    def fn(u):
        th = TWO_PI * turns * u
        return _xy(th * np.cos(th), th * np.sin(th)) / (TWO_PI * turns)
    return AnalyticCurve("spiral", fn)


def family() -> list[AnalyticCurve]:
    """The harder family the target-mode benchmark runs beside the paper's curves."""
    return [oscillatory(), astroid(), helix(), uneven(), narrow_bump(), spiral(), circle()]


def point() -> AnalyticCurve:
    """A degenerate curve: every parameter gives the same point."""
    return AnalyticCurve("point", lambda u: np.tile([1.0, 2.0, 3.0], (len(np.atleast_1d(u)), 1)), length=0.0)
