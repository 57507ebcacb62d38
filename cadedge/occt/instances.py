"""Faces that are one B-rep face placed again: an assembly's repeated parts.

A STEP assembly that places a part several times (the servos and screws of a robot arm) gives OCCT one
face (``TopoDS_TShape``) under several locations; ``TopExp::MapShapes`` tells them apart by location, so
cadedge gives each its own id. :func:`face_placements` finds them, so that the mesher can mesh one and
move its triangles to the others (:mod:`cadedge.mesh.instances`).
"""

from __future__ import annotations

import numpy as np
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_FORWARD
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS_Shape

from .compat import TopTools_IndexedMapOfShape
from .topology import indexed

#: A placement is rigid when its scale is 1 within this (a scaled copy's grids are not the same).
SCALE_TOLERANCE = 1e-9


def face_placements(shape: TopoDS_Shape) -> dict[int, tuple[int, np.ndarray]]:
    """Face id -> ``(first, matrix)`` for every face (``MapShapes`` order, 1-based) that is the same B-rep
    face, in the same orientation, as the earlier face ``first``, placed by a rigid motion without
    mirroring: ``matrix`` (3, 4) maps ``first``'s points onto this face's (``x' = A x + b``). Faces met
    once, or placed by a scaling or mirroring location, are left out."""
    return _placements(shape, TopAbs_FACE, oriented=True)


def edge_placements(shape: TopoDS_Shape) -> dict[int, tuple[int, np.ndarray]]:
    """Edge id -> ``(first, matrix)``, as :func:`face_placements` for edges, in either orientation (an
    edge's grid runs along its curve's parameter either way)."""
    return _placements(shape, TopAbs_EDGE, oriented=False)


def same_faces(shape: TopoDS_Shape) -> dict[int, int]:
    """Face id -> the earlier face it is, placed again by a rigid motion, in either orientation (for
    what a motion and a flip keep: a face's area)."""
    return {face: first for face, (first, _) in _placements(shape, TopAbs_FACE, oriented=False).items()}


def _placements(shape: TopoDS_Shape, kind, *, oriented: bool) -> dict[int, tuple[int, np.ndarray]]:
    shapes = indexed(shape, kind)
    bare = TopTools_IndexedMapOfShape()  # one entry per TShape (and orientation)
    first: dict[int, int] = {}
    out: dict[int, tuple[int, np.ndarray]] = {}
    for i in range(1, shapes.Extent() + 1):
        item = shapes.FindKey(i)
        key = bare.Add(item.Located(TopLoc_Location()).Oriented(TopAbs_FORWARD))
        key = 2 * key + (oriented and item.Orientation() != TopAbs_FORWARD)
        if key not in first:
            first[key] = i
            continue
        move = item.Location().Transformation().Multiplied(
            shapes.FindKey(first[key]).Location().Transformation().Inverted())
        if abs(move.ScaleFactor() - 1.0) > SCALE_TOLERANCE or move.IsNegative():
            continue
        out[i] = (first[key], np.array([[move.Value(r, c) for c in range(1, 5)] for r in range(1, 4)]))
    return out
