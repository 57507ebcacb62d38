"""The geometry of many edges read once into flat arrays, for refining them all in one compiled call.

Each edge whose 3-D curve is a line, circle, ellipse, hyperbola, B-spline or Bezier curve gets a row of
:class:`EdgeTable`'s arrays. Where the shape was read in one call (:mod:`cadedge.occt.shapedump`) the row
is the curve OCCT wrote for the edge, with no OCP call. Otherwise, and for the curves the dump gives differently from the adaptor (periodic splines,
trimmed curves), the row is read through the edge's ``BRepAdaptor_Curve`` (which applies the edge's
location), the adaptors' curve handles written by OCCT in one call and parsed in C
(:mod:`cadedge.occt.curvedump`). The table's evaluation (``cadedge/_batch.c``, the same formulas as
:mod:`cadedge.occt.fasteval`, and OCCT's own for a hyperbola) is then checked against OCCT's (``BRepAdaptor_Curve.D0``, see
:meth:`EdgeTable._check`); an edge that disagrees by more than ``fasteval.RTOL`` of its size, or that
OCCT cannot read, is left out and refined by the per-edge path (:class:`cadedge.occt.edgecurve.EdgeCurve`).
The lengths of ellipses, hyperbolas and splines are integrated on the table's rows in C (``cadedge/_lengths.c``,
within 1e-13 of OCCT's ``GCPnts_AbscissaPoint::Length`` on every corpus edge), OCCT's where that gives none.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.GCPnts import GCPnts_AbscissaPoint
from OCP.Geom import Geom_Circle, Geom_Ellipse, Geom_Hyperbola, Geom_Line
from OCP.gp import gp_Pnt
from OCP.GeomAbs import (GeomAbs_BezierCurve, GeomAbs_BSplineCurve, GeomAbs_Circle, GeomAbs_Ellipse,
                         GeomAbs_Hyperbola, GeomAbs_Line)
from .compat import OCCT_ERRORS

from .. import explore, kernels, target
from .curvedump import CIRCLE, DEGREE, DIM, KIND, KNOTS, PERIODIC, TYPE, CurveSet
from .edgecurve import CONIC_ROOTS, DEFAULT_ROOTS, LENGTH_TOL, SPAN_ROOTS, EdgeCurve
from .fasteval import CHECK_POINTS, RTOL
from .shapedump import ShapeDump

LINE, CONIC, SPLINE, HYPERBOLA = 0, 1, 2, 3
#: The check point (of ``CHECK_POINTS``) a row read from the dump is evaluated at by OCCT: the middle one.
PROBE = CHECK_POINTS // 2
#: The adaptor's curve type of each curve type the table reads, by BinTools type code.
GEOMABS = {1: GeomAbs_Line, 2: GeomAbs_Circle, 3: GeomAbs_Ellipse, 5: GeomAbs_Hyperbola, 6: GeomAbs_BezierCurve,
           7: GeomAbs_BSplineCurve}
#: Their names in :data:`cadedge.occt.topology.CURVE_TYPES` (``curve_type_name`` of the adaptor's type).
NAMES = {1: "Line", 2: "Circle", 3: "Ellipse", 5: "Hyperbola", 6: "BezierCurve", 7: "BSplineCurve"}


def _from_dump(dump: ShapeDump, indices: np.ndarray) -> np.ndarray:
    """Which of the edges ``indices`` the dump gives a row as their adaptor would: a 3-D curve of a type the
    table reads, not periodic (the per-edge path makes a periodic spline's non-periodic copy), not
    wrapped in a trimmed curve (the adaptor unwraps it), and a range the adaptor accepts (first <= last)."""
    c = dump.edge_curve[indices]
    if not len(dump.curves.meta):
        return np.zeros(len(indices), dtype=bool)
    meta = dump.curves.meta[np.maximum(c, 1) - 1]
    first, last = dump.edge_range[indices].T
    return (c > 0) & (meta[:, KIND] >= 0) & (meta[:, PERIODIC] == 0) & (first <= last)


class EdgeTable:
    """Flat geometry of the edges ``rows`` (indices into the caller's edge list) that passed the check.

    ``kind``, ``gofs``, ``ints`` and ``gdata`` are the geometry table of ``cadedge/_batch.c``; ``domain``
    (n, 2), ``exact`` (n, each edge's length or NaN), ``hofs``/``hdata`` (the knots a periodic spline's
    exploration starts from) go with them. ``adaptors[k]``, ``kinds[k]`` and ``names[k]`` (its curve type's
    name) belong to row ``k``.
    """

    def __init__(self, edges: Sequence, indices: list[int], dump: ShapeDump | None = None):
        self._edges = edges
        rows, adaptors, kinds, domain, ids, dumped, splines = [], [], [], [], [], [], {}
        parts = [dump.curves] if dump is not None else []
        base = len(dump.curves.meta) if dump is not None else 0  # the curves' indices continue after the dump's
        if dump is not None:  # the rows the dump holds, without an OCP call
            indices = np.asarray(indices, dtype=np.int64)
            taken = _from_dump(dump, indices)
            rows, ids = indices[taken].tolist(), dump.edge_curve[indices[taken]].tolist()
            domain = dump.edge_range[indices[taken]].tolist()
            kinds = [GEOMABS[t] for t in dump.curves.meta[np.asarray(ids, dtype=np.int64) - 1, TYPE].tolist()]
            adaptors = [None] * len(rows)
            indices = indices[~taken].tolist()
            dumped = [True] * len(rows)
        curves = CurveSet()
        add = curves.add
        for i in indices:
            try:
                ad = BRepAdaptor_Curve(edges[i])
                if not ad.Is3DCurve():
                    continue
                a, b = ad.FirstParameter(), ad.LastParameter()
                t = ad.GetType()
                if t == GeomAbs_Line:
                    curve = Geom_Line(ad.Line())
                elif t == GeomAbs_Circle:
                    curve = Geom_Circle(ad.Circle())
                elif t == GeomAbs_Ellipse:
                    curve = Geom_Ellipse(ad.Ellipse())
                elif t == GeomAbs_Hyperbola:
                    curve = Geom_Hyperbola(ad.Hyperbola())
                elif t == GeomAbs_BSplineCurve or t == GeomAbs_BezierCurve:
                    curve = ad.BSpline() if t == GeomAbs_BSplineCurve else ad.Bezier()
                else:
                    continue
                index = base + add(curve)
            except OCCT_ERRORS:
                continue  # the per-edge path reports what OCCT cannot do
            if t == GeomAbs_BSplineCurve:
                splines[index] = curve
            rows.append(i)
            adaptors.append(ad)
            kinds.append(t)
            ids.append(index)
            domain.append((a, b))
        if dump is not None and len(rows) > len(dumped):  # rows in edge order
            dumped += [False] * (len(rows) - len(dumped))
            order = sorted(range(len(rows)), key=rows.__getitem__)
            rows, adaptors, kinds, ids, domain, dumped = (
                [x[k] for k in order] for x in (rows, adaptors, kinds, ids, domain, dumped))
        #: Row k came from the dump (its ends are checked against its vertices, see _check).
        self.dumped = np.array(dumped + [False] * (len(rows) - len(dumped)), dtype=bool)
        self._dump = dump
        if indices or not parts:  # (OCCT writes the adaptors' curves only when there are some)
            parts.append(curves.curves())
        meta = np.concatenate([p.meta for p in parts])
        shift = np.cumsum([0] + [len(p.numbers) for p in parts])
        begin = np.concatenate([p.offsets[:-1] + at for p, at in zip(parts, shift)])
        end = np.concatenate([p.offsets[1:] + at for p, at in zip(parts, shift)])
        numbers = np.concatenate([p.numbers for p in parts])
        periodic = {}  # curve index -> (period, the same curve made non-periodic)
        for index, curve in splines.items():
            if meta[index - 1, PERIODIC]:
                flat = curve.Copy()
                flat.SetNotPeriodic()  # the same geometry over one period with clamped knots
                periodic[index] = float(curve.Period()), flat
        if periodic:  # their rows come from the non-periodic copies
            flats = CurveSet()
            for _, flat in periodic.values():
                flats.add(flat)
            more = flats.curves()
            at = np.array(list(periodic), dtype=np.int64) - 1
            meta = meta.copy()
            meta[at] = more.meta
            begin[at], end[at] = more.offsets[:-1] + len(numbers), more.offsets[1:] + len(numbers)
            numbers = np.concatenate([numbers, more.numbers])
        c = np.array(ids, dtype=np.int64) - 1
        size = end[c] - begin[c]
        gofs = np.zeros(len(c) + 1, dtype=np.int64)
        np.cumsum(size, out=gofs[1:])
        gdata = numbers[np.repeat(begin[c] - gofs[:-1], size) + np.arange(gofs[-1])]
        hint_sizes, hints = np.zeros(len(c), dtype=np.int64), []
        for r, index in enumerate(ids) if periodic else ():
            if index in periodic:
                gdata[gofs[r]] = periodic[index][0]  # the period slot of the row
                hint = _periodic_knots(splines[index], *domain[r])
                hints += hint
                hint_sizes[r] = len(hint)
        self.rows, self.adaptors, self.kinds = rows, adaptors, kinds  # adaptors[k] None until needed
        self.names = [NAMES[t] for t in meta[c, TYPE].tolist()]
        self.kind = meta[c, KIND].copy()
        self.gofs = gofs
        self.ints = meta[c][:, [DEGREE, KNOTS, DIM]].copy()
        self.gdata = gdata
        self.domain = np.array(domain, dtype=float).reshape(-1, 2)
        self.hofs = np.zeros(len(c) + 1, dtype=np.int64)
        np.cumsum(hint_sizes, out=self.hofs[1:])
        self.hdata = np.array(hints, dtype=float)
        self.exact = np.full(len(rows), math.nan)
        circles = np.flatnonzero(meta[c, TYPE] == CIRCLE)  # closed form, as EdgeCurve.exact_length
        self.exact[circles] = gdata[gofs[circles] + 9] * (self.domain[circles, 1] - self.domain[circles, 0])
        self._lengths(np.flatnonzero((self.kind != LINE) & (meta[c, TYPE] != CIRCLE)))
        self._check()

    def _lengths(self, curved: np.ndarray) -> None:
        """Set the lengths of the rows ``curved`` (ellipses, hyperbolas, splines) by ``cadedge/_lengths.c``'s
        quadrature, or where it gives none by OCCT's (``GCPnts_AbscissaPoint::Length`` to ``LENGTH_TOL``); drop
        a row OCCT cannot measure either (the per-edge path reports it)."""
        if not len(curved):
            return
        got = kernels.edge_lengths(self.kind, self.gofs, self.ints, self.gdata, self.hofs, self.hdata, self.domain,
                                   curved)
        self.exact[curved] = got
        failed = []
        for r in curved[np.isnan(got)].tolist():
            try:
                self.exact[r] = float(GCPnts_AbscissaPoint.Length_s(self.adaptor(r), *self.domain[r], LENGTH_TOL))
            except OCCT_ERRORS:
                failed.append(r)
        if failed:
            self._keep(np.setdiff1d(np.arange(len(self.rows)), failed))

    def __len__(self) -> int:
        return len(self.rows)

    def adaptor(self, r: int) -> BRepAdaptor_Curve:
        """Row ``r``'s ``BRepAdaptor_Curve``, built on first use."""
        ad = self.adaptors[r]
        if ad is None:
            ad = self.adaptors[r] = BRepAdaptor_Curve(self._edges[self.rows[r]])
        return ad

    def evaluate(self, row: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Points (len(u), 3) of the edges of table rows ``row`` (grouped, any order) at ``u``."""
        return kernels.evaluate_edges(self.kind, self.gofs, self.ints, self.gdata, row, u)

    def _check(self) -> None:
        """Drop the rows whose evaluation differs from OCCT's, and set line lengths from the evaluated ends
        (as ``EdgeCurve.exact_length``).

        A row read through its adaptor is checked as ``fasteval.fast_evaluator`` checks an edge: at
        ``CHECK_POINTS`` parameters against ``BRepAdaptor_Curve::D0``, to ``RTOL`` of the curve's size. A row
        read from the dump holds the numbers OCCT itself wrote, in a stream whose every size and count was
        checked; its evaluated ends must lie on its vertices (within their tolerances: that the curve, its
        range and its placement are the edge's) and its middle check point must agree with OCCT's as above
        (that the table evaluates that curve as OCCT does). A dump row whose ends miss its vertices (a
        loose vertex) gets the full check."""
        n = len(self.rows)
        if not n:
            return
        a, b = self.domain[:, 0], self.domain[:, 1]
        u = np.stack([a, a + (b - a) / (CHECK_POINTS - 1) * (PROBE + 0.1234), b], axis=1)  # off the knots
        got = self.evaluate(np.repeat(np.arange(n, dtype=np.int64), 3), u.ravel()).reshape(n, 3, 3)
        probed = self.dumped & self._ends_on_vertices(got[:, [0, 2]])
        ok = np.ones(n, dtype=bool)
        self._build_adaptors()
        one = np.flatnonzero(probed)
        ref = got.copy()  # OCCT's points where checked
        ref[one, 1] = self._occt_points([self.adaptors[r] for r in one.tolist()], u[one, 1].tolist(), ok, one.tolist())
        ok[one] &= _agree(got[one], ref[one])
        full = np.flatnonzero(~probed)
        if len(full):  # every check point, as fast_evaluator
            a, b = a[full], b[full]
            u9 = np.linspace(a, b, CHECK_POINTS, axis=1)
            u9[:, 1:-1] += ((b - a) / (CHECK_POINTS - 1) * 0.1234)[:, None]
            got9 = self.evaluate(np.repeat(full, CHECK_POINTS), u9.ravel()).reshape(len(full), CHECK_POINTS, 3)
            rows = np.repeat(full, CHECK_POINTS).tolist()
            ref9 = self._occt_points([self.adaptors[r] for r in rows], u9.ravel().tolist(), ok, rows)
            ok[full] &= _agree(got9, ref9.reshape(got9.shape))
        lines = np.flatnonzero(self.kind == LINE)
        for r, d in zip(lines.tolist(), got[lines, -1] - got[lines, 0]):  # as EdgeCurve.exact_length: norm's dot
            self.exact[r] = math.sqrt(d.dot(d))
        if not ok.all():
            self._keep(np.flatnonzero(ok))

    def _build_adaptors(self) -> None:
        """Every row's ``BRepAdaptor_Curve`` (the check evaluates each row through its own)."""
        missing = [r for r, ad in enumerate(self.adaptors) if ad is None]
        if missing:
            take = getattr(self._edges, "take", None)
            at = [self.rows[r] for r in missing]
            edges = take(at) if take is not None else [self._edges[i] for i in at]
            for r, edge in zip(missing, edges):
                self.adaptors[r] = BRepAdaptor_Curve(edge)

    @staticmethod
    def _occt_points(adaptors: list, u: list[float], ok: np.ndarray, rows: list[int]) -> np.ndarray:
        """``adaptors[k].D0(u[k])`` for every k, (len(u), 3); where OCCT fails, ``ok[rows[k]]`` is cleared
        (and the point is NaN)."""
        point = gp_Pnt()  # filled by each D0 call: no new point object per evaluation
        coord = point.Coord
        try:
            out = [(ad.D0(x, point), coord())[1] for ad, x in zip(adaptors, u)]
        except OCCT_ERRORS:  # again one by one, to know which
            out = []
            for ad, x, r in zip(adaptors, u, rows):
                try:
                    ad.D0(x, point)
                    out.append(coord())
                except OCCT_ERRORS:
                    ok[r] = False
                    out.append((math.nan,) * 3)
        return np.array(out, dtype=float).reshape(-1, 3)

    def _ends_on_vertices(self, ends: np.ndarray) -> np.ndarray:
        """Rows whose evaluated first and last points ``ends`` (n, 2, 3) lie within their vertices' tolerances of
        them."""
        if self._dump is None:
            return np.zeros(len(ends), dtype=bool)
        d = self._dump
        at = d.edge_vertices[self.rows] - 1
        gap = np.linalg.norm(ends - d.vertex_points[at], axis=2)
        return np.all(gap <= d.vertex_tolerance[at], axis=1)

    def _keep(self, keep: np.ndarray) -> None:
        """Only the rows ``keep`` (increasing)."""
        gofs, hofs = self.gofs, self.hofs
        self.gdata = np.concatenate([self.gdata[gofs[r]:gofs[r + 1]] for r in keep]) if len(keep) else self.gdata[:0]
        self.gofs = np.concatenate([[0], np.cumsum(np.diff(gofs)[keep])]).astype(np.int64)
        self.hdata = np.concatenate([self.hdata[hofs[r]:hofs[r + 1]] for r in keep]) if len(keep) else self.hdata[:0]
        self.hofs = np.concatenate([[0], np.cumsum(np.diff(hofs)[keep])]).astype(np.int64)
        self.kind, self.ints, self.domain, self.exact = (x[keep] for x in (self.kind, self.ints, self.domain, self.exact))
        self.rows = [self.rows[r] for r in keep]
        self.adaptors = [self.adaptors[r] for r in keep]
        self.kinds = [self.kinds[r] for r in keep]
        self.names = [self.names[r] for r in keep]
        self.dumped = self.dumped[keep]


def _agree(got: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Rows (of (n, points, 3)) whose points agree with OCCT's ``ref`` to ``RTOL`` of the row's size (the largest
    coordinate or extent of its points, as ``fasteval``)."""
    n = len(got)
    if not n:
        return np.ones(0, dtype=bool)
    flat = ref.reshape(n, -1)
    size = np.maximum(np.abs(flat).max(axis=1), (ref.max(axis=1) - ref.min(axis=1)).max(axis=1))
    size = np.maximum(size, math.ulp(1.0))
    return (np.abs(got - ref).reshape(n, -1) <= (RTOL * size)[:, None]).all(axis=1)


def _periodic_knots(bs, a: float, b: float) -> list[float]:
    """The distinct knots in [a, b] over all periods, with a and b (as ``EdgeCurve._knots``)."""
    from ..grid import unique_sorted

    k = np.array([bs.Knot(i) for i in range(1, bs.NbKnots() + 1)], dtype=float)
    per = float(bs.Period())
    shifts = np.arange(math.floor((a - k[-1]) / per), math.ceil((b - k[0]) / per) + 1) * per
    k = unique_sorted((k[None, :] + shifts[:, None]).ravel())
    tol = 1e-9 * (b - a)
    return [a, *k[(k > a + tol) & (k < b - tol)].tolist(), b]


class TableCurves(Mapping):
    """Edge id -> :class:`EdgeCurve`, built on first use: from the table (sharing its adaptor and
    evaluating through it) or given ready-made (edges refined by the per-edge path)."""

    def __init__(self, table: EdgeTable, ids: list[int], ready: dict[int, EdgeCurve], edges: list):
        self._table, self._edges = table, edges
        self._row = {eid: r for r, eid in enumerate(ids)}
        self._ready = dict(ready)

    def __getitem__(self, eid: int) -> EdgeCurve:
        curve = self._ready.get(eid)
        if curve is None:
            r = self._row[eid]  # KeyError for an id with no curve
            t = self._table
            curve = EdgeCurve.from_parts(self._edges[t.rows[r]], eid, t.adaptor(r), tuple(t.domain[r].tolist()),
                                         t.kinds[r], lambda u: t.evaluate(np.full(len(u), r, dtype=np.int64), u))
            self._ready[eid] = curve
        return curve

    def __iter__(self):
        return iter(sorted({*self._ready, *self._row}))

    def __len__(self) -> int:
        return len({*self._ready, *self._row})



def _settings() -> np.ndarray:
    """The constants of target mode and the exploration, in the order ``cadedge/_batch.c`` reads them."""
    return np.array([target.EXPLORE_SHARE, target.MARGIN, target.EXACT_MARGIN, target.AGREEMENT, explore.STRAIGHT,
                     explore.ASYMPTOTIC_RATIO, explore.NOISE, target.MAX_TRIALS, explore.MAX_SAMPLES, CONIC_ROOTS,
                     SPAN_ROOTS, DEFAULT_ROOTS], dtype=float)


SETTINGS = _settings()


def refine_table(table: EdgeTable, rows: slice, ald: np.ndarray, first: np.ndarray,
                 last: np.ndarray) -> tuple[np.ndarray, ...]:
    """Target-mode grids of the table's ``rows`` (a slice with a stop) with per-row ``ald`` and vertex points
    ``first`` and ``last`` (len(rows), 3) that the grids end on: see :func:`cadedge.kernels.refine_edges`."""
    g0, g1 = table.gofs[rows.start], table.gofs[rows.stop]
    h0, h1 = table.hofs[rows.start], table.hofs[rows.stop]
    return kernels.refine_edges(table.kind[rows], table.gofs[rows.start:rows.stop + 1] - g0, table.ints[rows],
                                table.gdata[g0:g1], table.hofs[rows.start:rows.stop + 1] - h0, table.hdata[h0:h1],
                                table.domain[rows], ald, table.exact[rows], first, last, SETTINGS)
