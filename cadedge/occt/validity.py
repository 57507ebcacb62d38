"""OCCT's own check of B-rep faces (``BRepCheck_Analyzer``): when gmsh cannot mesh a face, whether the
face itself is broken.

cadquery sweeps an annulus along a path with a sharp corner into cylinder faces whose wires are not
closed or cross themselves; gmsh alone fails on them as cadedge does ("the 1D mesh seems not to be
forming a closed loop"), and the user's fix is in the model. Each failed face is checked alone, with its
wires, edges and vertices, so a large model pays only for the faces that failed.
"""

from __future__ import annotations

from OCP.BRepCheck import BRepCheck_Analyzer, BRepCheck_Face, BRepCheck_NoError, BRepCheck_Wire
from OCP.TopAbs import TopAbs_WIRE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS_Edge, TopoDS_Shape

from .compat import OCCT_ERRORS, TopoDS
from .topology import Topology

#: BRepCheck's statuses in words; the others by their name without the ``BRepCheck_`` prefix.
WORDS = {
    "NotClosed": "a wire not closed",
    "SelfIntersectingWire": "a wire crossing itself",
    "IntersectingWires": "wires crossing each other",
    "InvalidImbricationOfWires": "wires nested wrongly",
    "BadOrientationOfSubshape": "wires oriented against it",
    "BadOrientation": "a wire oriented against it",
    "EmptyWire": "an empty wire",
}


def _wire_checks(face, wire) -> list:
    """BRepCheck's statuses of ``wire`` on ``face``: closed in 3-D and on the face, oriented, not
    crossing itself."""
    check = BRepCheck_Wire(wire)
    return [check.Closed(False), check.Closed2d(face, False), check.Orientation(face, False),
            check.SelfIntersect(face, TopoDS_Edge(), TopoDS_Edge(), False)]


def face_problems(shape: TopoDS_Shape, faces: list[int]) -> dict[int, str]:
    """Face id -> what BRepCheck finds wrong with it, in words (``"wires oriented against it, a wire
    crossing itself"``), for those of ``faces`` (``TopExp::MapShapes`` order, 1-based) that fail the check.

    ``BRepCheck_Analyzer`` says whether the face passes; what is wrong comes from the face's and its
    wires' own checks (``BRepCheck_Face``, ``BRepCheck_Wire``), which return one status each: the
    analyzer's lists of statuses cannot be read on OCP 8. A face whose faults lie in its edges or
    vertices (curves off the surface, tolerances) is said to have those."""
    topo = Topology(shape)
    out = {}
    for fid in faces:
        if not 1 <= fid <= len(topo.faces):
            continue
        face = topo.faces[fid - 1]
        try:
            if BRepCheck_Analyzer(face).IsValid():
                continue
            check = BRepCheck_Face(face)
            found = [check.IntersectWires(False), check.ClassifyWires(False), check.OrientationOfWires(False)]
            explorer = TopExp_Explorer(face, TopAbs_WIRE)
            while explorer.More():
                found += _wire_checks(face, TopoDS.Wire_s(explorer.Current()))
                explorer.Next()
        except (*OCCT_ERRORS, TypeError) as exc:  # OCCT's failure, or a binding that cannot convert
            out[fid] = f"the check itself failed ({exc})"
            continue
        names = [getattr(s, "name", str(s)).removeprefix("BRepCheck_") for s in found if s != BRepCheck_NoError]
        words = list(dict.fromkeys(WORDS.get(n, n) for n in names))
        out[fid] = ", ".join(words) or "faults in its edges or vertices"
    return out
