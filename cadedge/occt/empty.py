"""Empty solids and shells (no face in them) taken out of a shape before gmsh imports it.

OCCT reads them (OCCT's own sample Axis_of_bearing.brep holds a solid with no shell), but gmsh's
import stops on one ("Inserting (null or degenerate) shape with void bounding box") and its ``.msh``
writer then fails without a message: every face had been meshed, and all were lost. An empty container
holds no geometry, so leaving it out loses nothing; the faces, edges and vertices keep their
``MapShapes`` order, which the ids of the mesh's groups and gmsh's point tags rely on.
"""

from __future__ import annotations

from OCP.BRepTools import BRepTools_ReShape
from .compat import OCCT_ERRORS
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_SHELL, TopAbs_SOLID, TopAbs_VERTEX
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS_Shape

from .topology import indexed

_KINDS = {TopAbs_SOLID: "solid", TopAbs_SHELL: "shell"}


def _has_face(shape: TopoDS_Shape) -> bool:
    return TopExp_Explorer(shape, TopAbs_FACE).More()


def without_empty(shape: TopoDS_Shape) -> tuple[TopoDS_Shape, list[str]]:
    """``shape`` without its solids and shells that hold no face, and what was left out ("2 empty
    solids"); the shape unchanged (and nothing left out) when there are none, or when leaving them out
    would change the order of its faces, edges or vertices."""
    empty = {kind: [s for s in _all(shape, kind) if not _has_face(s)] for kind in _KINDS}
    if not any(empty.values()):
        return shape, []
    reshape = BRepTools_ReShape()
    for found in empty.values():
        for s in found:
            reshape.Remove(s)
    try:
        pruned = reshape.Apply(shape)
    except OCCT_ERRORS:
        return shape, []
    for kind in (TopAbs_FACE, TopAbs_EDGE, TopAbs_VERTEX):
        before, after = indexed(shape, kind), indexed(pruned, kind)
        if before.Size() != after.Size() or any(not before.FindKey(i).IsSame(after.FindKey(i))
                                                for i in range(1, before.Size() + 1)):
            return shape, []
    return pruned, [f"{len(found)} empty {_KINDS[kind]}{'s' * (len(found) > 1)}"
                    for kind, found in empty.items() if found]


def _all(shape: TopoDS_Shape, kind) -> list[TopoDS_Shape]:
    """The distinct sub-shapes of ``kind`` (a solid inside a compound once, however often it is used)."""
    found = indexed(shape, kind)
    return [found.FindKey(i) for i in range(1, found.Size() + 1)]
