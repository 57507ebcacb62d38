"""Exact numpy evaluation of an edge's curve from its OCCT geometry, checked against OCCT.

Lines, circles, ellipses, B-splines (rational or not, periodic or not) and Bezier curves are
evaluated from their definition in one vectorised call instead of one ``BRepAdaptor_Curve.Value``
per point. The geometry is taken from the adaptor (``Line()``, ``Circle()``, ``BSpline()``, ...),
which applies the edge's location; B-splines and Bezier curves are evaluated by de Boor's algorithm
on homogeneous poles, in compiled C (:mod:`cadedge.kernels`; an edge is evaluated a few times
only, so scipy's ``BSpline`` cost more to build than to call). Every evaluator is cross-checked on construction
against ``BRepAdaptor_Curve.Value`` at ``CHECK_POINTS`` parameters of the edge's range; if any point
differs by more than ``RTOL`` of the curve's size, :func:`fast_evaluator` returns ``None`` and the
caller keeps OCCT's per-point loop.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.GeomAbs import (GeomAbs_BezierCurve, GeomAbs_BSplineCurve, GeomAbs_Circle, GeomAbs_Ellipse,
                         GeomAbs_Line)
from .compat import OCCT_ERRORS

from ..kernels import de_boor

#: Parameters of the edge's range at which the numpy evaluation must agree with OCCT.
CHECK_POINTS = 9
#: Largest disagreement with ``BRepAdaptor_Curve.Value``, relative to the curve's size.
RTOL = 1e-9

Points = Callable[[np.ndarray], np.ndarray]


def _xyz(obj) -> np.ndarray:
    return np.array(obj.Coord(), dtype=float)


def _line(ad: BRepAdaptor_Curve) -> Points:
    lin = ad.Line()
    loc, d = _xyz(lin.Location()), _xyz(lin.Direction())
    return lambda u: loc + u[:, None] * d


def _conic(pos, rx: float, ry: float) -> Points:
    loc, x, y = _xyz(pos.Location()), _xyz(pos.XDirection()), _xyz(pos.YDirection())
    return lambda u: loc + (rx * np.cos(u))[:, None] * x + (ry * np.sin(u))[:, None] * y


def _spline(knots: np.ndarray, poles: np.ndarray, weights: np.ndarray | None, degree: int,
            period: float | None) -> Points:
    """de Boor on homogeneous poles; ``period`` wraps parameters into the first period."""
    coef = poles if weights is None else np.column_stack([poles * weights[:, None], weights])
    coef = np.ascontiguousarray(coef, dtype=float)
    start = knots[degree]

    def evaluate(u: np.ndarray) -> np.ndarray:
        if period is not None:
            u = start + np.mod(u - start, period)
        h = de_boor(knots, coef, degree, u)
        return h if weights is None else h[:, :3] / h[:, 3:]

    return evaluate


def _bspline(ad: BRepAdaptor_Curve) -> Points:
    bs = ad.BSpline()
    period = None
    if bs.IsPeriodic():
        period = float(bs.Period())
        bs = bs.Copy()
        bs.SetNotPeriodic()  # the same geometry over one period with clamped knots
    n = bs.NbPoles()
    seq = bs.KnotSequence()  # a copy of the whole sequence per call: take it once
    knots = np.array([seq.Value(i) for i in range(1, n + bs.Degree() + 2)], dtype=float)
    poles = np.array([bs.Pole(i).Coord() for i in range(1, n + 1)], dtype=float)
    weights = np.array([bs.Weight(i) for i in range(1, n + 1)], dtype=float) if bs.IsRational() else None
    return _spline(knots, poles, weights, bs.Degree(), period)


def _bezier(ad: BRepAdaptor_Curve) -> Points:
    bz = ad.Bezier()
    n, k = bz.NbPoles(), bz.Degree()
    poles = np.array([bz.Pole(i).Coord() for i in range(1, n + 1)], dtype=float)
    weights = np.array([bz.Weight(i) for i in range(1, n + 1)], dtype=float) if bz.IsRational() else None
    return _spline(np.array([0.0] * (k + 1) + [1.0] * (k + 1)), poles, weights, k, None)


BUILDERS = {
    GeomAbs_Line: _line,
    GeomAbs_Circle: lambda ad: _conic(ad.Circle().Position(), ad.Circle().Radius(), ad.Circle().Radius()),
    GeomAbs_Ellipse: lambda ad: _conic(ad.Ellipse().Position(), ad.Ellipse().MajorRadius(), ad.Ellipse().MinorRadius()),
    GeomAbs_BSplineCurve: _bspline,
    GeomAbs_BezierCurve: _bezier,
}


def fast_evaluator(adaptor: BRepAdaptor_Curve, domain: tuple[float, float]) -> Points | None:
    """A vectorised ``u -> (n, 3)`` equal to ``adaptor.Value`` to ``RTOL``, or ``None`` to keep OCCT's.

    Only edges with a 3-D curve of a supported type qualify; the check compares both at
    ``CHECK_POINTS`` parameters spread over ``domain`` (ends included).
    """
    if not adaptor.Is3DCurve():
        return None
    build = BUILDERS.get(adaptor.GetType())
    if build is None:
        return None
    try:
        fn = build(adaptor)
        a, b = domain
        u = np.linspace(a, b, CHECK_POINTS)
        u[1:-1] += (b - a) / (CHECK_POINTS - 1) * 0.1234  # off the knots and symmetric points
        ref = np.array([adaptor.Value(x).Coord() for x in u.tolist()], dtype=float)
    except (*OCCT_ERRORS, ValueError):
        return None
    got = np.asarray(fn(u), dtype=float)
    size = max(float(np.abs(ref).max()), float(np.ptp(ref, axis=0).max()), math.ulp(1.0))
    if got.shape != ref.shape or not np.all(np.abs(got - ref) <= RTOL * size):
        return None
    return fn
