"""How far edges lie from where their faces' boundaries run, measured at their grid nodes.

A face's area (OCCT's, which the surface target is measured against) is bounded by its edges' pcurves
on its surface; its mesh is bounded by the edges' grids, on their 3-D curves. Where the two part, the
area between them is the face's and not the mesh's, or the other way round, and an edge's tolerance
bounds how far they may part. It often says far more than they do: OCCT's sample ``bearing.iges``
carries tolerances up to 0.0022 on edges whose pcurves trace their 3-D curves to 3.4e-6 (only out of
step, :mod:`cadedge.occt.sameparam`), and its faces over the target were excused as "within what its
edges' tolerances allow" on that bound alone; LLNL boxed_sphere's cylinders, 2.7% short, have edges
0.032 from their pcurves' trace (tolerance 0.037). The report measures the faces it would excuse and
excuses only what these distances account for.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.gp import gp_Pnt
from OCP.ShapeAnalysis import ShapeAnalysis_Curve
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE

from .compat import OCCT_ERRORS, TopoDS
from .topology import indexed, orientations_in

#: Nodes of an edge's grid measured at most (evenly picked, its ends always).
MOST_NODES = 65


def _picked(points: np.ndarray) -> np.ndarray:
    """At most :data:`MOST_NODES` of ``points``, evenly spread, the first and last among them."""
    if len(points) <= MOST_NODES:
        return points
    return points[np.unique(np.linspace(0, len(points) - 1, MOST_NODES).round().astype(int))]


def edge_offsets(shape, edges: Iterable, faces: Iterable[int]) -> dict[int, dict[int, float]]:
    """Face id -> {edge id: the largest distance of the edge's grid nodes from the edge's curve on that
    face (its pcurve on the face's surface; a seam's two)}, for the ``faces`` (ids in ``MapShapes``
    order of ``shape``) and those of ``edges`` (grid edges: ``id``, ``faces``, ``points``) that bound
    them. An edge OCCT could not measure is left out (its tolerance stands for it)."""
    wanted = set(faces)
    found, all_edges = indexed(shape, TopAbs_FACE), indexed(shape, TopAbs_EDGE)
    project = ShapeAnalysis_Curve()
    out: dict[int, dict[int, float]] = {}
    for e in edges:
        if not 1 <= e.id <= all_edges.Size() or len(e.points) == 0:
            continue
        edge = TopoDS.Edge_s(all_edges.FindKey(e.id))
        points = [gp_Pnt(x, y, z) for x, y, z in _picked(np.asarray(e.points, dtype=float)).tolist()]
        for f in sorted(set(e.faces) & wanted):
            if not 1 <= f <= found.Size():
                continue
            face = TopoDS.Face_s(found.FindKey(f))
            try:
                traces = [BRepAdaptor_Curve(TopoDS.Edge_s(edge.Oriented(o)), face) for o in orientations_in(face, edge)]
                if traces:
                    out.setdefault(f, {})[e.id] = max(project.Project(trace, p, 0.0, gp_Pnt(), 0.0, True)
                                                      for trace in traces for p in points)
            except OCCT_ERRORS:
                continue
    return out
