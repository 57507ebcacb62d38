"""The numpy evaluation of OCCT edges agrees with BRepAdaptor_Curve, and the exploration hints are sound."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BRepAdaptor import BRepAdaptor_Curve  # noqa: E402
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_Transform  # noqa: E402
from OCP.GC import GC_MakeArcOfCircle, GC_MakeArcOfEllipse  # noqa: E402
from OCP.Geom import Geom_BezierCurve, Geom_BSplineCurve  # noqa: E402
from OCP.GeomAPI import GeomAPI_Interpolate  # noqa: E402
from OCP.gp import gp_Ax1, gp_Ax2, gp_Circ, gp_Dir, gp_Elips, gp_Pnt, gp_Trsf, gp_Vec  # noqa: E402

from cadedge import refine_curve  # noqa: E402
from cadedge.occt.compat import (TColgp_Array1OfPnt, TColgp_HArray1OfPnt, TColStd_Array1OfInteger,  # noqa: E402
                                 TColStd_Array1OfReal, TopoDS)
from cadedge.occt.edgecurve import EdgeCurve  # noqa: E402
from cadedge.occt.fasteval import fast_evaluator  # noqa: E402
from cadedge.occt.reader import load_shape  # noqa: E402
from cadedge.occt.topology import Topology  # noqa: E402

from conftest import CORPUS  # noqa: E402


def _occt(curve: EdgeCurve, u: np.ndarray) -> np.ndarray:
    return np.array([curve.adaptor.Value(x).Coord() for x in u.tolist()])


def _agree(curve: EdgeCurve, n: int = 57) -> float:
    a, b = curve.domain
    u = np.linspace(a, b, n)
    ref = _occt(curve, u)
    size = max(np.abs(ref).max(), np.ptp(ref, axis=0).max())
    return float(np.abs(curve.evaluate(u) - ref).max() / size)


def _moved(edge, angle: float = 0.7):
    """The edge rotated and translated: its location must be applied."""
    t = gp_Trsf()
    t.SetRotation(gp_Ax1(gp_Pnt(1, 2, 3), gp_Dir(1, 1, 0.3)), angle)
    s = gp_Trsf()
    s.SetTranslation(gp_Vec(5.0, -3.0, 11.0))
    return TopoDS.Edge_s(BRepBuilderAPI_Transform(edge, s.Multiplied(t), False).Shape())


def _spline(points: list[tuple[float, float, float]], periodic: bool = False):
    """The B-spline interpolating ``points`` (what cadquery's ``Edge.makeSpline`` builds)."""
    array = TColgp_HArray1OfPnt(1, len(points))
    for i, p in enumerate(points):
        array.SetValue(i + 1, gp_Pnt(*p))
    interpolate = GeomAPI_Interpolate(array, periodic, 1e-6)
    interpolate.Perform()
    assert interpolate.IsDone()
    return BRepBuilderAPI_MakeEdge(interpolate.Curve()).Edge()


def _bezier(points: list[tuple[float, float, float]]):
    poles = TColgp_Array1OfPnt(1, len(points))
    for i, p in enumerate(points):
        poles.SetValue(i + 1, gp_Pnt(*p))
    return BRepBuilderAPI_MakeEdge(Geom_BezierCurve(poles)).Edge()


def _edges() -> dict:
    """One edge of each type OCCT's numpy evaluators handle, built with plain OCP (as cadquery's
    ``Edge.makeLine``/``makeCircle``/``makeEllipse``/``makeSpline``/``makeBezier`` do), then moved."""
    arc = gp_Circ(gp_Ax2(gp_Pnt(1, 1, 1), gp_Dir(0, 1, 1)), 2.5)
    ellipse = gp_Elips(gp_Ax2(gp_Pnt(0, 0, 1), gp_Dir(1, 0, 1), gp_Dir(1, 0, 0)), 4.0, 1.5)
    out = {
        "line": BRepBuilderAPI_MakeEdge(gp_Pnt(0, 0, 0), gp_Pnt(3, 1, 2)).Edge(),
        "circle": BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(arc, math.radians(30), math.radians(250), True)
                                          .Value()).Edge(),
        "ellipse": BRepBuilderAPI_MakeEdge(GC_MakeArcOfEllipse(ellipse, math.radians(10), math.radians(300), True)
                                           .Value()).Edge(),
        "spline": _spline([(x, math.sin(x), 0.1 * x * x) for x in np.linspace(0, 6, 9)]),
        "periodic": _spline([(math.cos(t), math.sin(t), 0.2 * math.sin(3 * t))
                             for t in np.linspace(0, 2 * math.pi, 9)[:-1]], periodic=True),
        "bezier": _bezier([(0, 0, 0), (1, 2, 0), (3, -1, 1), (4, 0, 0)]),
    }
    out.update({f"moved {k}": _moved(v) for k, v in list(out.items())})
    return out


@pytest.mark.parametrize("name", list(_edges()))
def test_fast_evaluation_matches_occt(name):
    curve = EdgeCurve(_edges()[name])
    assert curve.fast is not None, f"{name}: no numpy evaluator"
    assert _agree(curve) <= 1e-12


def _rational_periodic():
    """A periodic rational B-spline (a full circle as NURBS) trimmed across its seam."""
    n = 8
    poles, weights = TColgp_Array1OfPnt(1, n), TColStd_Array1OfReal(1, n)
    for i in range(n):
        t = 2 * math.pi * i / n
        r = 1.0 if i % 2 == 0 else 1.0 / math.cos(math.pi / n)
        poles.SetValue(i + 1, gp_Pnt(r * math.cos(t), r * math.sin(t), 0.3 * (i % 3)))
        weights.SetValue(i + 1, 1.0 if i % 2 == 0 else 0.8)
    knots, mults = TColStd_Array1OfReal(1, n + 1), TColStd_Array1OfInteger(1, n + 1)
    for i in range(n + 1):
        knots.SetValue(i + 1, float(i))
        mults.SetValue(i + 1, 1)
    curve = Geom_BSplineCurve(poles, weights, knots, mults, 2, True)
    return BRepBuilderAPI_MakeEdge(curve, 6.5, 10.25).Edge()  # crosses the period end at 8


def test_rational_periodic_spline_across_the_seam():
    curve = EdgeCurve(_rational_periodic())
    assert curve.adaptor.IsRational() and curve.fast is not None
    assert _agree(curve, 101) <= 1e-12
    u = curve.initial_params(*curve.domain)
    assert 8.0 in u and 7.0 in u and 9.0 in u and 10.0 in u  # knots of the next period are roots too


def test_unsupported_type_keeps_occt():
    edge = BRepBuilderAPI_MakeEdge(gp_Pnt(0, 0, 0), gp_Pnt(1, 0, 0)).Edge()
    ad = BRepAdaptor_Curve(edge)
    assert fast_evaluator(ad, (0.0, 1.0)) is not None


@pytest.mark.corpus
def test_hyperbola_keeps_occt():
    hyper = [e for e in Topology(load_shape(CORPUS / "gumyr__build123d__M6-1x12-countersunk-screw.step").shape).edges
             if BRepAdaptor_Curve(e).GetType().name == "GeomAbs_Hyperbola"]
    assert hyper, "the screw has hyperbola edges"
    curve = EdgeCurve(hyper[0])
    assert curve.fast is None
    assert len(curve.initial_params(*curve.domain)) == 65


def test_initial_params_per_type():
    e = _edges()
    a, b = EdgeCurve(e["line"]).domain
    assert list(EdgeCurve(e["line"]).initial_params(a, b)) == [a, b]
    c = EdgeCurve(e["circle"])
    u = c.initial_params(*c.domain)
    assert u[0] == c.domain[0] and u[-1] == c.domain[1] and 4 <= len(u) <= 8
    s = EdgeCurve(e["spline"])
    u = s.initial_params(*s.domain)
    assert np.all(np.diff(u) > 0) and u[0] == s.domain[0] and u[-1] == s.domain[1]
    assert len(u) == 2 * (s.adaptor.NbKnots() - 1) + 1


def test_refined_edge_meets_target_against_occt_length():
    from OCP.GCPnts import GCPnts_AbscissaPoint

    for name, edge in _edges().items():
        curve = EdgeCurve(edge)
        g = refine_curve(curve, curve.domain, ald=1e-4)
        true = GCPnts_AbscissaPoint.Length_s(BRepAdaptor_Curve(curve.edge))
        assert 1 - g.length / true <= 1e-4, name
        np.testing.assert_allclose(g.points, _occt(curve, g.params), rtol=0, atol=1e-12 * max(1.0, true))


@pytest.mark.parametrize("name", ["line", "circle", "moved ellipse", "spline", "periodic", "bezier"])
def test_exact_length_agrees_with_dense_polylines(name):
    curve = EdgeCurve(_edges()[name])
    a, b = curve.domain
    mid = a + 0.37 * (b - a)

    def dense(lo: float, hi: float, n: int) -> float:
        return float(np.linalg.norm(np.diff(curve.evaluate(np.linspace(lo, hi, n)), axis=0), axis=1).sum())

    for lo, hi in ((a, b), (a, mid)):
        coarse, fine = dense(lo, hi, 20001), dense(lo, hi, 40001)
        richardson = fine + (fine - coarse) / 3.0
        assert curve.exact_length(lo, hi) == pytest.approx(richardson, rel=1e-9)
