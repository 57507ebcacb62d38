"""Edges whose curves on their faces run out of step with the edge's own curve, put back in step before
gmsh meshes them.

An edge has one 3-D curve and, on each of its faces, a curve in the face's parameters (its pcurve);
OCCT wants the two to give the same point at the same parameter ("same parameter"), to within the
edge's tolerance. Some files meet that only by a loose tolerance: OCCT's own sample ``bearing.iges``
has edges whose pcurve at a parameter lies up to 0.0022 (22 of the edge grid's segments) along the
edge from the 3-D curve there, though both lie on the face. gmsh places an edge node in a face's
parameters by the pcurve at the node's parameter, and cadedge places it in space by the 3-D curve: the
node stood in the face's parameters 0.2 of the face's width from where it is, the face's triangles
crossed each other to reach it (0.1-degree slivers, a mesh 11% larger than the face). Such edges get
new pcurves, made in step with the 3-D curve by OCCT (``BRepLib::SameParameter``, forced), in the copy
of the shape gmsh meshes; the 3-D curves, and so the edge grids, stay as they are.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Curve2d, BRepAdaptor_Surface
from OCP.BRepLib import BRepLib
from OCP.BRepTools import BRepTools_ReShape
from OCP.ShapeBuild import ShapeBuild_Edge
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_FORWARD, TopAbs_VERTEX
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS_Edge, TopoDS_Face, TopoDS_Iterator, TopoDS_Shape

from .compat import OCCT_ERRORS, TopoDS, TopTools_IndexedDataMapOfShapeListOfShape
from .topology import indexed, list_items, orientations_in

#: An edge is out of step where its pcurve's point lies farther than this share of the edge grid's
#: shortest segment from the 3-D curve's point at the same parameter: a node then stands in the face's
#: parameters that share of a segment away from where it is in space.
STEP_SHARE = 0.05
#: Parameters at which an edge's pcurves are compared with its 3-D curve.
SAMPLES = 33


@dataclass
class Restepped:
    """An edge given new pcurves: its id, how far out of step it was and is at most, and the tolerance
    OCCT gave it with them (what it needs now, down from the tolerance that covered the old pcurves)."""

    edge: int
    before: float
    after: float
    tolerance: float


def _out_of_step(edge: TopoDS_Edge, uses: list[tuple[TopoDS_Face, list]]) -> float:
    """The largest distance between the edge's 3-D curve and its pcurves (on their faces' surfaces) at
    the same parameter, over :data:`SAMPLES` parameters; ``uses`` the faces and the orientations in
    which each holds the edge (a seam's two pcurves both)."""
    curve = BRepAdaptor_Curve(edge)
    ts = np.linspace(curve.FirstParameter(), curve.LastParameter(), SAMPLES)
    worst = 0.0
    for face, orientations in uses:
        surface = BRepAdaptor_Surface(face, False)
        for orientation in orientations:
            pcurve = BRepAdaptor_Curve2d(TopoDS.Edge_s(edge.Oriented(orientation)), face)
            lo, hi = sorted((pcurve.FirstParameter(), pcurve.LastParameter()))
            for t in ts.tolist():
                uv = pcurve.Value(min(max(t, lo), hi))
                worst = max(worst, curve.Value(t).Distance(surface.Value(uv.X(), uv.Y())))
    return worst


def _copied(edge: TopoDS_Edge) -> TopoDS_Edge:
    """A new edge with the same curves (its pcurves copies) and the same vertices, in the same order:
    the order in which ``MapShapes`` meets the shape's vertices, which gmsh's point tags follow, stays."""
    forward = TopoDS.Edge_s(edge.Oriented(TopAbs_FORWARD))
    new = TopoDS.Edge_s(forward.EmptyCopied())
    builder = BRep_Builder()
    children = TopoDS_Iterator(forward, False, False)
    while children.More():
        builder.Add(new, children.Value())
        children.Next()
    ShapeBuild_Edge().CopyPCurves(new, forward)  # the new pcurves never touch the shape's own
    return new


def in_step(shape: TopoDS_Shape, shortest: Mapping[int, float]) -> tuple[TopoDS_Shape, list[Restepped]]:
    """``shape`` with the pcurves of its edges that are out of step (:data:`STEP_SHARE` of
    ``shortest[edge id]``, the edge grid's shortest segment; ids in ``MapShapes`` order) rebuilt in step,
    and those edges. Only edges whose tolerance allows them to be that far out of step are looked at (a
    valid edge lies within its tolerance); an edge is changed only if its new pcurves are in step, and
    the shape comes back as it was (no edge changed) if its faces, edges or vertices would not keep their
    order."""
    edges = indexed(shape, TopAbs_EDGE)
    suspects = [i for i, length in shortest.items()
                if 1 <= i <= edges.Size() and length > 0
                and BRep_Tool.Tolerance_s(TopoDS.Edge_s(edges.FindKey(i))) > STEP_SHARE * length]
    if not suspects:
        return shape, []
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, ancestors)
    reshape = BRepTools_ReShape()
    done: list[Restepped] = []
    for i in suspects:
        edge = TopoDS.Edge_s(edges.FindKey(i))
        faces: list[TopoDS_Face] = []
        for f in list_items(ancestors.FindFromKey(edge)):  # a seam's face is listed twice
            if not any(f.IsSame(g) for g in faces):
                faces.append(TopoDS.Face_s(f))
        uses = [(face, orientations_in(face, edge)) for face in faces]
        bound = STEP_SHARE * shortest[i]
        try:
            before = _out_of_step(edge, uses)
            if before <= bound:
                continue
            new = _copied(edge)
            BRepLib.SameParameter_s(new, min(BRep_Tool.Tolerance_s(new), 0.1 * bound), True)  # forced
            after = _out_of_step(new, uses)
        except OCCT_ERRORS:
            continue
        if after <= bound:
            reshape.Replace(edge.Oriented(TopAbs_FORWARD), new)
            done.append(Restepped(i, before, after, BRep_Tool.Tolerance_s(new)))
    if not done:
        return shape, []
    try:
        out = reshape.Apply(shape)
    except OCCT_ERRORS:
        return shape, []
    for kind in (TopAbs_FACE, TopAbs_EDGE, TopAbs_VERTEX):
        if indexed(out, kind).Size() != indexed(shape, kind).Size():
            return shape, []
    vertices, moved = indexed(shape, TopAbs_VERTEX), indexed(out, TopAbs_VERTEX)
    if any(not vertices.FindKey(k).IsSame(moved.FindKey(k)) for k in range(1, vertices.Size() + 1)):
        return shape, []
    changed = indexed(out, TopAbs_EDGE)
    if any(not changed.FindKey(r.edge).IsSame(reshape.Value(edges.FindKey(r.edge))) for r in done):
        return shape, []
    return out, done
