"""IGES and BREP files written by OCCT from every corpus STEP file, set against that STEP.

BREP keeps the model as it is: the same edges, vertices and faces in the same MapShapes order. IGES
does too, except where the STEP model stores a wire REVERSED (a STEP face bound whose orientation
differs from its face's same_sense): an IGES loop (entity 508) has no orientation of its own, so
OCCT's writer stores the loop's edges in the order the wire is walked (``BRepTools_WireExplorer`` on
the forward face, the outer wire first) and the reader builds a forward wire in that order. For
those models the test checks that the IGES edges are exactly the STEP edges in that walked order;
for all others, the same signature as the STEP.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BRepTools import BRepTools_WireExplorer  # noqa: E402
from OCP.ShapeAnalysis import ShapeAnalysis  # noqa: E402
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_FORWARD, TopAbs_WIRE  # noqa: E402
from OCP.TopExp import TopExp  # noqa: E402
from OCP.TopoDS import TopoDS_Iterator, TopoDS_Shape  # noqa: E402

import cadedge  # noqa: E402
from cadedge.occt.compat import TopoDS, TopTools_IndexedMapOfShape  # noqa: E402
from cadedge.occt.reader import load_shape  # noqa: E402
from conftest import corpus_params  # noqa: E402
from test_input_formats import _signature, write_brep, write_iges  # noqa: E402


def _children(shape: TopoDS_Shape) -> list[TopoDS_Shape]:
    it, out = TopoDS_Iterator(shape), []
    while it.More():
        out.append(it.Value())
        it.Next()
    return out


def iges_edge_order(shape: TopoDS_Shape) -> list[int]:
    """The STEP model's MapShapes edge indices in the order an IGES loop stores them: the edges first
    met walking the model as OCCT's IGES writer does (each face forward, its outer wire first, each wire
    by ``BRepTools_WireExplorer``), MapShapes order everywhere else."""
    edges = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_EDGE, edges)
    seen: dict[int, None] = {}

    def walk(s: TopoDS_Shape) -> None:
        if s.ShapeType() == TopAbs_EDGE:
            seen.setdefault(edges.FindIndex(s))
            return
        if s.ShapeType() != TopAbs_FACE:
            for child in _children(s):
                walk(child)
            return
        face = TopoDS.Face_s(s.Oriented(TopAbs_FORWARD))
        outer = ShapeAnalysis.OuterWire_s(face)
        for child in sorted(_children(face), key=lambda w: not w.IsSame(outer)):
            if child.ShapeType() != TopAbs_WIRE:
                walk(child)
                continue
            explorer = BRepTools_WireExplorer(TopoDS.Wire_s(child), face)
            while explorer.More():
                walk(explorer.Current())
                explorer.Next()

    walk(shape)
    return list(seen)


@pytest.mark.parametrize("step", corpus_params())
def test_iges_and_brep_give_the_step_edges_in_the_step_order(tmp_path, step):
    a = cadedge.refine_shape(step, ald=1e-2)
    brep = cadedge.refine_shape(write_brep(step, tmp_path / f"{step.stem}.brep"), ald=1e-2)
    assert _signature(brep) == _signature(a)
    iges = cadedge.refine_shape(write_iges(step, tmp_path / f"{step.stem}.igs"), ald=1e-2)
    assert len(iges.edges) == len(a.edges) and len(iges.vertices) == len(a.vertices)
    order = iges_edge_order(load_shape(step).shape)
    assert sorted(order) == list(range(1, len(a.edges) + 1))
    if order == sorted(order):  # no wire that an IGES loop cannot store as the STEP does
        assert _signature(iges) == _signature(a)
        expected = a.edges
    else:
        expected = [a.edges[i - 1] for i in order]
    for ea, eb in zip(expected, iges.edges):
        assert eb.curve == ea.curve and eb.degenerate == ea.degenerate
        assert eb.length == pytest.approx(ea.length, rel=1e-6, abs=1e-9)
        if not ea.degenerate:
            assert np.allclose(eb.points[[0, -1]], ea.points[[0, -1]], rtol=0, atol=1e-6)
