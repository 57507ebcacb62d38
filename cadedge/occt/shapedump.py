"""A shape's topology and its edges' geometry read in one OCCT call and one C call.

Walking a B-rep from Python costs an OCP call (0.5-1 us) per item: per edge some 30 of them for its
faces, vertices, curve, range and tolerance. ``BinTools_ShapeSet`` writes the whole shape (without
triangulations) in one C++ call, exactly, and ``parse_shapes`` in ``cadedge/_shapedump.c`` reads that
stream: faces, edges and vertices in ``TopExp::MapShapes`` order (the public ids), each edge's faces,
end vertices, degenerate flag, tolerance, range and 3-D curve (as rows of the edge table's geometry), each
vertex's point and tolerance. OCCT's own ``TopoDS`` objects are built only when asked for
(:class:`LazyShapes`), from the shape set's index.

The reader takes shapes without locations (no ``TopLoc_Location`` anywhere: the parts of a plain STEP
file), no triangulation-only faces, and format versions 2-4 (OCCT 7.6-8.0 write 4). Anything else, or a
stream that does not add up to the layout, makes :func:`read` return None: the caller then walks the shape
through OCP, never from a guess.
"""

from __future__ import annotations

import io
from collections.abc import Sequence

import numpy as np
from OCP.BinTools import BinTools_ShapeSet
from OCP.TopAbs import TopAbs_FORWARD, TopAbs_Orientation

from ..kernels import parse_shapes
from .compat import OCCT_ERRORS, TopoDS
from .curvedump import Curves


#: TopAbs_Orientation by value (building one from an int costs as much as an OCP call).
ORIENTATIONS = [TopAbs_Orientation(k) for k in range(4)]


class LazyShapes(Sequence):
    """OCCT shapes by position, built on first access from a shape set: ``cast(set.Shape(index[i]))`` with
    orientation ``orientation[i]`` (``stored[i]`` is the one the set holds it with)."""

    def __init__(self, shape_set: BinTools_ShapeSet, index: list[int], orientation: list[int], stored: list[int],
                 cast):
        self._set, self._index, self._orientation, self._stored, self._cast = (shape_set, index, orientation,
                                                                                stored, cast)
        self._built: list = [None] * len(index)

    def __len__(self) -> int:
        return len(self._index)

    def __getitem__(self, i):
        try:
            shape = self._built[i]
        except TypeError:  # a slice
            return [self[k] for k in range(*i.indices(len(self)))]
        if shape is None:
            shape = self._build(i)
        return shape

    def _build(self, i: int):
        shape = self._set.Shape(self._index[i])
        if self._orientation[i] != self._stored[i]:
            shape = shape.Oriented(ORIENTATIONS[self._orientation[i]])
        shape = self._built[i] = self._cast(shape)
        return shape

    def take(self, positions: list[int]) -> list:
        """The shapes at ``positions``, as ``[self[i] for i in positions]`` without a Python call per shape."""
        built, shape_at, cast, index = self._built, self._set.Shape, self._cast, self._index
        orientation, stored = self._orientation, self._stored
        for i in positions:
            if built[i] is None:
                shape = shape_at(index[i])
                if orientation[i] != stored[i]:
                    shape = shape.Oriented(ORIENTATIONS[orientation[i]])
                built[i] = cast(shape)
        return [built[i] for i in positions]


class ShapeDump:
    """The parsed stream of one shape (see the module's docstring); arrays in MapShapes order, 0-based.

    ``curves``: the curves (:class:`~cadedge.occt.curvedump.Curves`); ``edge_curve[e]``: edge ``e``'s curve
    (1-based, 0 if it has no 3-D curve); ``edge_range`` (n, 2); ``edge_tolerance``; ``degenerate``;
    ``edge_vertices`` (n, 2) vertex ids (0 where missing); ``edge_faces[e]`` its face ids, increasing;
    ``vertex_points`` (m, 3), ``vertex_tolerance``; ``edges``, ``vertices``, ``faces``: the OCCT shapes.
    """

    def __init__(self, shape_set: BinTools_ShapeSet, raw: tuple):
        (meta, offsets, numbers, edges, ereal, fofs, fids, verts, vreal, faces, orient) = raw
        self.curves = Curves(np.frombuffer(meta, dtype=np.int64).reshape(-1, 6),
                             np.frombuffer(offsets, dtype=np.int64), np.frombuffer(numbers, dtype=float))
        edges = np.frombuffer(edges, dtype=np.int64).reshape(-1, 5)
        ereal = np.frombuffer(ereal, dtype=float).reshape(-1, 3)
        vreal = np.frombuffer(vreal, dtype=float).reshape(-1, 4)
        orient = np.frombuffer(orient, dtype=np.uint8)
        verts, faces = np.frombuffer(verts, dtype=np.int64), np.frombuffer(faces, dtype=np.int64)
        self.edge_curve = edges[:, 1]
        self.edge_vertices = edges[:, 2:4]
        self.degenerate = edges[:, 4].astype(bool)
        self.edge_tolerance = ereal[:, 0]
        self.edge_range = np.ascontiguousarray(ereal[:, 1:])
        self.vertex_tolerance = vreal[:, 0]
        self.vertex_points = np.ascontiguousarray(vreal[:, 1:])
        ids, bounds = np.frombuffer(fids, dtype=np.int64).tolist(), np.frombuffer(fofs, dtype=np.int64).tolist()
        self.edge_faces = [ids[a:b] for a, b in zip(bounds[:-1], bounds[1:])]
        n = len(orient) // 2
        stored = orient[n:]
        self.edges = LazyShapes(shape_set, edges[:, 0].tolist(), [int(TopAbs_FORWARD)] * len(edges),
                                stored[edges[:, 0] - 1].tolist(), TopoDS.Edge_s)
        self.vertices = LazyShapes(shape_set, verts.tolist(), orient[verts - 1].tolist(), stored[verts - 1].tolist(),
                                   TopoDS.Vertex_s)
        self.faces = LazyShapes(shape_set, faces.tolist(), orient[faces - 1].tolist(), stored[faces - 1].tolist(),
                                TopoDS.Face_s)
        self.shape_set = shape_set


def read(shape) -> ShapeDump | None:
    """``shape`` read through OCCT's binary writer, or None where :mod:`cadedge._shapedump` does not take it
    (see the module's docstring)."""
    shape_set = BinTools_ShapeSet()
    shape_set.SetWithTriangles(False)
    try:
        root = shape_set.Add(shape)
        buf = io.BytesIO()
        shape_set.Write(buf)
    except OCCT_ERRORS:
        return None
    try:
        raw = parse_shapes(buf.getvalue(), root, int(shape.Orientation()))
    except ValueError:
        return None
    return ShapeDump(shape_set, raw)
