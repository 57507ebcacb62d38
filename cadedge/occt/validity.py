"""OCCT's own check of B-rep faces (``BRepCheck_Analyzer``): when gmsh cannot mesh a face, whether the
face itself is broken.

cadquery sweeps an annulus along a path with a sharp corner into cylinder faces whose wires are not
closed or cross themselves; gmsh alone fails on them as cadedge does ("the 1D mesh seems not to be
forming a closed loop"), and the user's fix is in the model. Each failed face is checked alone, with its
wires, edges and vertices, so a large model pays only for the faces that failed.
"""

from __future__ import annotations

from OCP.BRepCheck import BRepCheck_Analyzer, BRepCheck_NoError
from OCP.Standard import Standard_Failure
from OCP.TopAbs import TopAbs_EDGE, TopAbs_VERTEX, TopAbs_WIRE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS_Shape

from .topology import Topology

#: BRepCheck's statuses in words; the others by their name without the ``BRepCheck_`` prefix.
WORDS = {
    "NotClosed": "a wire not closed",
    "SelfIntersectingWire": "a wire crossing itself",
    "IntersectingWires": "wires crossing each other",
    "UnorientableShape": "not orientable",
    "BadOrientationOfSubshape": "wires oriented against it",
    "InvalidCurveOnSurface": "an edge off its surface",
    "InvalidCurveOnClosedSurface": "an edge off its closed surface",
    "InvalidSameParameterFlag": "an edge's curves out of step",
    "InvalidToleranceValue": "a tolerance smaller than its parts'",
    "EmptyWire": "an empty wire",
    "InvalidImbricationOfWires": "wires nested wrongly",
}


def _names(statuses) -> list[str]:
    """The statuses' names without the ``BRepCheck_`` prefix, :data:`BRepCheck_NoError` left out."""
    return [getattr(s, "name", str(s)).removeprefix("BRepCheck_") for s in statuses if s != BRepCheck_NoError]


def face_problems(shape: TopoDS_Shape, faces: list[int]) -> dict[int, str]:
    """Face id -> what BRepCheck finds wrong with it, in words (``"a wire not closed, not orientable"``),
    for those of ``faces`` (``TopExp::MapShapes`` order, 1-based) that fail the check."""
    topo = Topology(shape)
    out = {}
    for fid in faces:
        if not 1 <= fid <= len(topo.faces):
            continue
        face = topo.faces[fid - 1]
        try:
            analyzer = BRepCheck_Analyzer(face)
            if analyzer.IsValid():
                continue
            found = []
            result = analyzer.Result(face)
            if result is not None:
                found += _names(result.Status())
            for kind in (TopAbs_WIRE, TopAbs_EDGE, TopAbs_VERTEX):
                explorer = TopExp_Explorer(face, kind)
                while explorer.More():
                    sub = analyzer.Result(explorer.Current())
                    if sub is not None:
                        sub.InitContextIterator()
                        while sub.MoreShapeInContext():
                            found += _names(sub.StatusOnShape())
                            sub.NextShapeInContext()
                    explorer.Next()
        except Standard_Failure as exc:
            out[fid] = f"the check itself failed ({exc})"
            continue
        words = list(dict.fromkeys(WORDS.get(n, n) for n in found))
        out[fid] = ", ".join(words) or "invalid"
    return out
