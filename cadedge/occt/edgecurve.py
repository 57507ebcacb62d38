"""An OCCT edge as a cadedge black-box curve: parameter in, 3-D point out, nothing else.

Evaluation goes through ``BRepAdaptor_Curve``, which also handles edges that carry only curves on
surfaces (no 3-D curve) and applies the edge's location. Lines, conics, B-splines and Bezier curves
are evaluated in one numpy call by :mod:`cadedge.occt.fasteval` (checked against OCCT on
construction); other edges, and any that fail that check, use OCCT's per-point loop.
:meth:`EdgeCurve.initial_params` tells the exploration where the curve's pieces start and end.
"""

from __future__ import annotations

import math

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.GeomAbs import GeomAbs_BezierCurve, GeomAbs_BSplineCurve, GeomAbs_Circle, GeomAbs_Ellipse, GeomAbs_Line
from OCP.GCPnts import GCPnts_AbscissaPoint
from .compat import OCCT_ERRORS
from OCP.TopoDS import TopoDS_Edge

from ..errors import GeometryError
from ..grid import unique_sorted
from .fasteval import fast_evaluator
from .topology import forward

#: Root intervals per full turn of a circle or ellipse, and per knot span of a spline.
CONIC_ROOTS, SPAN_ROOTS = 8, 2
#: Tolerance of OCCT's length integration in :meth:`EdgeCurve.exact_length`.
LENGTH_TOL = 1e-12
#: Root intervals for any other curve (as the exploration's own default).
DEFAULT_ROOTS = 64
_SPAN_STEPS = np.arange(SPAN_ROOTS) / SPAN_ROOTS


class EdgeCurve:
    """Edge ``edge`` in its FORWARD orientation: ``domain`` runs from its first vertex to its last.

    ``edge_id`` only names the edge in error messages. OCCT failures raise :class:`GeometryError`.
    """

    def __init__(self, edge: TopoDS_Edge, edge_id: int | None = None):
        self.edge = forward(edge)
        self.edge_id = edge_id
        try:
            self.adaptor = BRepAdaptor_Curve(self.edge)
            self.domain = (float(self.adaptor.FirstParameter()), float(self.adaptor.LastParameter()))
            self.kind = self.adaptor.GetType()
        except OCCT_ERRORS as exc:
            raise GeometryError(f"{self._name()}: OCCT cannot adapt its curve: {exc}") from exc
        self.fast = fast_evaluator(self.adaptor, self.domain)

    @classmethod
    def from_parts(cls, edge: TopoDS_Edge, edge_id: int | None, adaptor: BRepAdaptor_Curve,
                   domain: tuple[float, float], kind, fast) -> "EdgeCurve":
        """The curve of a FORWARD ``edge`` whose adaptor, domain, type and checked fast evaluator were
        already made (by :class:`cadedge.occt.edgetable.EdgeTable`), without building them again."""
        curve = cls.__new__(cls)
        curve.edge, curve.edge_id, curve.adaptor, curve.domain, curve.kind, curve.fast = (
            edge, edge_id, adaptor, domain, kind, fast)
        return curve

    def _name(self) -> str:
        return f"edge {self.edge_id}" if self.edge_id is not None else "edge"

    def evaluate(self, u: np.ndarray) -> np.ndarray:
        """Points at parameters ``u`` (1-D), shape (len(u), 3)."""
        u = np.asarray(u, dtype=float).ravel()
        if self.fast is not None:
            return self.fast(u)
        out = np.empty((len(u), 3))
        value = self.adaptor.Value
        try:
            for k, uk in enumerate(u.tolist()):
                out[k] = value(uk).Coord()
        except OCCT_ERRORS as exc:
            raise GeometryError(f"{self._name()}: OCCT failed to evaluate u={uk!r}: {exc}") from exc
        return out

    def initial_params(self, a: float, b: float) -> np.ndarray:
        """Where the exploration starts: the ends of a line; a few uniform steps on a conic; each knot
        span of a spline in ``SPAN_ROOTS`` pieces; ``DEFAULT_ROOTS`` uniform steps otherwise."""
        if self.kind == GeomAbs_Line and self.adaptor.Is3DCurve():
            return np.array([a, b])
        if self.kind in (GeomAbs_Circle, GeomAbs_Ellipse):
            return np.linspace(a, b, max(2, math.ceil(CONIC_ROOTS * (b - a) / (2 * math.pi))) + 1)
        if self.kind in (GeomAbs_BSplineCurve, GeomAbs_BezierCurve) and self.adaptor.Is3DCurve():
            knots = self._knots(a, b)
            u = (knots[:-1, None] + np.diff(knots)[:, None] * _SPAN_STEPS[None, :]).ravel()
            return np.append(u, b)  # sorted and distinct, as the knots are
        return np.linspace(a, b, DEFAULT_ROOTS + 1)

    def exact_length(self, a: float, b: float) -> float | None:
        """The length of the edge between ``a`` and ``b``: closed form for a line or circle; over the whole
        domain of a curve the edge table takes, the table's (``cadedge/_lengths.c``'s quadrature, as the
        compiled path has it); else OCCT's adaptive Gauss integration (``GCPnts_AbscissaPoint::Length``) to
        ``LENGTH_TOL``, which agrees with Richardson-extrapolated dense polylines to about 1e-9 on the corpus."""
        try:
            if self.fast is not None and self.kind == GeomAbs_Line:
                return float(np.linalg.norm(np.diff(self.fast(np.array([a, b])), axis=0)))
            if self.fast is not None and self.kind == GeomAbs_Circle:
                return float(self.adaptor.Circle().Radius() * (b - a))
            if (a, b) == self.domain:
                from .edgetable import EdgeTable  # (which builds on this module)

                table = EdgeTable([self.edge], [0])
                if len(table):
                    return float(table.exact[0])
            return float(GCPnts_AbscissaPoint.Length_s(self.adaptor, a, b, LENGTH_TOL))
        except OCCT_ERRORS:
            return None  # the refiner then relies on its own estimate

    def _knots(self, a: float, b: float) -> np.ndarray:
        """The distinct knots in [a, b] (all periods of a periodic spline), with a and b."""
        if self.kind == GeomAbs_BezierCurve:
            return np.array([a, b])
        bs = self.adaptor.BSpline()
        k = np.array([bs.Knot(i) for i in range(1, bs.NbKnots() + 1)], dtype=float)  # increasing
        if bs.IsPeriodic():
            per = float(bs.Period())
            shifts = np.arange(math.floor((a - k[-1]) / per), math.ceil((b - k[0]) / per) + 1) * per
            k = unique_sorted((k[None, :] + shifts[:, None]).ravel())  # the period's ends coincide
        tol = 1e-9 * (b - a)  # a knot a hair inside an end would only make a sliver of a span
        return np.concatenate([[a], k[(k > a + tol) & (k < b - tol)], [b]])

    def __repr__(self) -> str:
        return f"EdgeCurve({self._name()}, domain={self.domain})"
