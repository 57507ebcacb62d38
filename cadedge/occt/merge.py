"""Merge B-rep vertices into one (``BRepTools_ReShape``): the shape gmsh meshes when two vertices of a
face lie at one point (see :mod:`cadedge.mesh.coincident`)."""

from __future__ import annotations

from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepTools import BRepTools_ReShape
from OCP.TopAbs import TopAbs_FACE, TopAbs_FORWARD, TopAbs_VERTEX
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS_Shape

from .compat import OCCT_ERRORS, TopTools_IndexedDataMapOfShapeListOfShape, TopTools_IndexedMapOfShape
from .topology import indexed, list_items


def merge_vertices(shape: TopoDS_Shape, into: dict[int, int]) -> tuple[TopoDS_Shape, dict[int, int]]:
    """``shape`` with vertex ``v`` replaced by vertex ``into[v]`` in every edge (ids in ``MapShapes``
    order, each target an id not itself replaced), and the replacements made.

    Every vertex left keeps its order, so the new shape's vertices are the old ones without the
    replaced. The faces around a replaced vertex must pass OCCT's check afterwards, else the shape
    comes back unchanged with no replacement (the caller meshes it as it was)."""
    if not into:
        return shape, {}
    vertices = indexed(shape, TopAbs_VERTEX)
    reshape = BRepTools_ReShape()
    for old, new in sorted(into.items()):
        reshape.Replace(vertices.FindKey(old).Oriented(TopAbs_FORWARD),
                        vertices.FindKey(new).Oriented(TopAbs_FORWARD))
    try:
        merged = reshape.Apply(shape)
    except OCCT_ERRORS:
        return shape, {}
    kept = [vertices.FindKey(i) for i in range(1, vertices.Size() + 1) if i not in into]
    after = indexed(merged, TopAbs_VERTEX)
    if after.Size() != len(kept) or any(after.FindIndex(v) != k for k, v in enumerate(kept, start=1)):
        return shape, {}
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(merged, TopAbs_VERTEX, TopAbs_FACE, ancestors)
    faces = TopTools_IndexedMapOfShape()
    for new in set(into.values()):
        for face in list_items(ancestors.FindFromKey(vertices.FindKey(new))):
            faces.Add(face)
    try:
        if not all(BRepCheck_Analyzer(faces.FindKey(i)).IsValid() for i in range(1, faces.Size() + 1)):
            return shape, {}
    except OCCT_ERRORS:
        return shape, {}
    return merged, dict(into)
