"""OCCT's binary curve writer parsed (cadedge/occt/curvedump.py) against the same numbers read one OCP call
at a time: every type the edge table reads, rational and periodic splines, and a curve two edges share."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BRepAdaptor import BRepAdaptor_Curve  # noqa: E402
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge  # noqa: E402
from OCP.Geom import Geom_Circle, Geom_Ellipse, Geom_Line  # noqa: E402
from OCP.GeomAbs import GeomAbs_BezierCurve, GeomAbs_BSplineCurve, GeomAbs_Circle, GeomAbs_Line  # noqa: E402

from cadedge.kernels import parse_curves  # noqa: E402
from cadedge.occt.curvedump import (BEZIER, BSPLINE, CIRCLE, DEGREE, DIM, ELLIPSE, KNOTS, LINE, PERIODIC,  # noqa: E402
                                    TYPE, CurveSet)
from cadedge.occt.edgetable import EdgeTable  # noqa: E402
from test_fasteval import _edges, _rational_periodic  # noqa: E402


def _handle(ad: BRepAdaptor_Curve):
    t = ad.GetType()
    if t == GeomAbs_Line:
        return Geom_Line(ad.Line())
    if t == GeomAbs_Circle:
        return Geom_Circle(ad.Circle())
    if t == GeomAbs_BSplineCurve:
        return ad.BSpline()
    if t == GeomAbs_BezierCurve:
        return ad.Bezier()
    return Geom_Ellipse(ad.Ellipse())


def _by_calls(curve) -> tuple[list[float], list[float]]:
    """(knots, homogeneous poles) of a spline or Bezier curve, one OCP call per number."""
    n = curve.NbPoles()
    if hasattr(curve, "NbKnots"):  # each knot as often as its multiplicity (periodic or not)
        knots = [curve.Knot(i) for i in range(1, curve.NbKnots() + 1) for _ in range(curve.Multiplicity(i))]
    else:
        knots = [0.0] * (curve.Degree() + 1) + [1.0] * (curve.Degree() + 1)
    poles: list[float] = []
    for i in range(1, n + 1):
        x, y, z = curve.Pole(i).Coord()
        w = curve.Weight(i)
        poles += (x * w, y * w, z * w, w) if curve.IsRational() else (x, y, z)
    return knots, poles


@pytest.mark.parametrize("name", [*_edges(), "rational periodic"])
def test_parsed_curve_equals_the_numbers_read_one_call_at_a_time(name):
    edge = _rational_periodic() if name == "rational periodic" else _edges()[name]
    ad = BRepAdaptor_Curve(edge)
    handle = _handle(ad)
    curves = CurveSet()
    assert curves.add(handle) == 1
    got = curves.curves()
    assert got.meta.shape == (1, 6) and got.offsets[0] == 0
    meta, row = got.meta[0].tolist(), got.numbers[got.offsets[0]:got.offsets[1]].tolist()
    t = ad.GetType()
    if t == GeomAbs_Line:
        lin = ad.Line()
        assert meta[TYPE] == LINE and row == [*lin.Location().Coord(), *lin.Direction().Coord()]
    elif t in (GeomAbs_BSplineCurve, GeomAbs_BezierCurve):
        assert meta[TYPE] == (BSPLINE if t == GeomAbs_BSplineCurve else BEZIER)
        knots, poles = _by_calls(handle)
        assert meta[DEGREE] == handle.Degree() and meta[DIM] == (4 if handle.IsRational() else 3)
        assert meta[PERIODIC] == (t == GeomAbs_BSplineCurve and handle.IsPeriodic())
        assert math.isnan(row[0]) and row[1:] == knots + poles and meta[KNOTS] == len(knots)
    else:
        conic = ad.Circle() if t == GeomAbs_Circle else ad.Ellipse()
        pos = conic.Position()
        radii = [conic.Radius()] * 2 if t == GeomAbs_Circle else [conic.MajorRadius(), conic.MinorRadius()]
        assert meta[TYPE] == (CIRCLE if t == GeomAbs_Circle else ELLIPSE)
        assert row == [*pos.Location().Coord(), *pos.XDirection().Coord(), *pos.YDirection().Coord(), *radii]


def test_a_truncated_stream_is_an_error_not_a_read_past_its_end():
    curves = CurveSet()
    curves.add(BRepAdaptor_Curve(_edges()["spline"]).BSpline())
    buf = io.BytesIO()
    curves._set.Write(buf)
    data = buf.getvalue()
    start = data.index(b"\n") + 1
    for cut in (start + 1, start + 13, len(data) - 1):
        with pytest.raises(ValueError, match="ends inside an item"):
            parse_curves(data[:cut], start, 1)


def test_a_shared_curve_is_written_once_and_both_edges_are_refined_from_it():
    curve = BRepAdaptor_Curve(_edges()["spline"]).BSpline()
    a, b = curve.FirstParameter(), curve.LastParameter()
    edges = [BRepBuilderAPI_MakeEdge(curve, a, (a + b) / 2).Edge(), BRepBuilderAPI_MakeEdge(curve, (a + b) / 2, b).Edge()]
    curves = CurveSet()
    assert [curves.add(BRepAdaptor_Curve(e).BSpline()) for e in edges] == [1, 1]
    table = EdgeTable(edges, [0, 1])
    assert table.rows == [0, 1]
    g = table.gofs
    assert np.array_equal(table.gdata[g[0]:g[1]], table.gdata[g[1]:g[2]], equal_nan=True)  # NaN: no period
