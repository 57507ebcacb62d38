"""Edge lengths integrated in C (cadedge/_lengths.c) against OCCT's ``GCPnts_AbscissaPoint::Length``: on every
curved edge of the fixtures and the corpus, and on one edge of each curve type the table takes (rational,
periodic across its seam, Bezier, hyperbola, moved), to 1e-12 of the length."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.GCPnts import GCPnts_AbscissaPoint  # noqa: E402

from cadedge import kernels  # noqa: E402
from cadedge.occt.edgecurve import LENGTH_TOL, EdgeCurve  # noqa: E402
from cadedge.occt.edgetable import LINE, EdgeTable  # noqa: E402
from cadedge.occt.reader import load_shape  # noqa: E402
from cadedge.occt.topology import Topology  # noqa: E402
from conftest import CORPUS_FILES, FIXTURE_FILES, corpus_params  # noqa: E402

RTOL = 1e-12


def _c_and_occt(table: EdgeTable) -> tuple[np.ndarray, np.ndarray]:
    """The C lengths of every row but lines (circles included) and OCCT's."""
    rows = np.flatnonzero(table.kind != LINE)
    got = kernels.edge_lengths(table.kind, table.gofs, table.ints, table.gdata, table.hofs, table.hdata,
                               table.domain, rows)
    ref = np.array([GCPnts_AbscissaPoint.Length_s(table.adaptor(r), *table.domain[r], LENGTH_TOL)
                    for r in rows.tolist()])
    return got, ref


def _model(path) -> None:
    topo = Topology(load_shape(path).shape)
    table = EdgeTable(topo.edges, [i for i in range(len(topo.edges)) if not topo.is_degenerate(i)], topo.dump)
    got, ref = _c_and_occt(table)
    assert np.all(np.abs(got - ref) <= RTOL * ref), np.max(np.abs(got - ref) / ref)


@pytest.mark.parametrize("path", FIXTURE_FILES, ids=lambda p: p.name)
def test_fixture_lengths_agree_with_occt(path):
    _model(path)


@pytest.mark.parametrize("path", corpus_params(CORPUS_FILES))
def test_corpus_lengths_agree_with_occt(path):
    _model(path)


def test_each_curve_type_agrees_with_occt():
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
    from OCP.gp import gp_Ax2, gp_Dir, gp_Hypr, gp_Pnt

    from test_fasteval import _edges, _rational_periodic

    edges = {**_edges(), "rational periodic across the seam": _rational_periodic(),
             "hyperbola": BRepBuilderAPI_MakeEdge(gp_Hypr(gp_Ax2(gp_Pnt(1, 2, 3), gp_Dir(0.2, 0.3, 1.0)), 2.0, 0.7),
                                                  -1.3, 2.1).Edge()}
    names = list(edges)
    table = EdgeTable([EdgeCurve(edges[n]).edge for n in names], list(range(len(names))))
    assert table.rows == list(range(len(names)))
    got, ref = _c_and_occt(table)
    assert len(got) == len(names) - 2  # every type but the two lines
    assert np.all(np.abs(got - ref) <= RTOL * ref), dict(zip([n for n in names if "line" not in n], got / ref - 1))


def test_table_and_per_edge_lengths_are_one():
    """The compiled path and the per-edge path take the same length (their grids are the same)."""
    from test_fasteval import _edges

    for name, edge in _edges().items():
        curve = EdgeCurve(edge)
        table = EdgeTable([curve.edge], [0])
        assert table.exact[0] == curve.exact_length(*curve.domain), name


def test_a_curve_it_cannot_integrate_gives_nan():
    """NaN, which the table replaces by OCCT's length: a range that is not finite, a line (not integrated)."""
    from test_fasteval import _edges

    curve = EdgeCurve(_edges()["spline"])
    table = EdgeTable([curve.edge, EdgeCurve(_edges()["line"]).edge], [0, 1])
    domain = table.domain.copy()
    domain[0, 1] = np.inf
    got = kernels.edge_lengths(table.kind, table.gofs, table.ints, table.gdata, table.hofs, table.hdata, domain,
                               np.array([0, 1]))
    assert np.isnan(got).all()


def test_where_c_gives_none_the_table_takes_occts_length(monkeypatch):
    from test_fasteval import _edges

    edge = EdgeCurve(_edges()["ellipse"]).edge
    monkeypatch.setattr(kernels, "edge_lengths", lambda *args: np.full(len(args[-1]), np.nan))
    table = EdgeTable([edge], [0])
    assert table.exact[0] == GCPnts_AbscissaPoint.Length_s(table.adaptor(0), *table.domain[0], LENGTH_TOL)
