"""Split edge-grid segments that are much longer than the mesh size around them.

An edge grid meets its ALD with very few segments on straight edges; but a face whose boundary has a
24 mm segment 7 mm from a hole meshed at 0.5 mm can only be filled with slivers next to that
segment, whatever the interior sizes. Before the grids are imposed, every segment longer than
``ratio`` (3) times the size field at its midpoint (graded from all edges' spacings, so a nearby edge
counts even when it is not adjacent) is split into pieces of equal arc length on its OCCT curve
(:mod:`cadedge.splitting`; the curves ``refine_shape`` built, kept on the grid). Edge ends are never
moved, so shared vertices stay bit-identical, and splitting only lowers the ALD.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from ..shapegrid import ShapeGrid, with_edges
from ..splitting import split_segments

#: A segment is split when it is longer than this many times the size field at its midpoint.
RATIO = 3.0
#: Edges whose tolerance exceeds this share of the pieces they would be cut into are left alone: on
#: a loose edge (vertices off the curve, curves off the faces) a new point can fall so far from the
#: face's own boundary that gmsh builds near-degenerate triangles there.
TOLERANCE_SHARE = 1e-3
#: Each pass rebuilds the field from the split grid; sizes settle in a few.
PASSES = 3


def fit_to_sizes(grid: ShapeGrid, make_field: Callable[[ShapeGrid], Callable[[np.ndarray], np.ndarray]], *,
                 ratio: float = RATIO, passes: int = PASSES) -> ShapeGrid:
    """A copy of ``grid`` whose segments are at most ``ratio`` times the size field (``make_field(grid)``)."""
    curves = grid.curves if grid.curves is not None else _LazyCurves(grid)
    edges = list(grid.edges)
    for _ in range(passes):
        field = make_field(dataclasses.replace(grid, edges=edges))
        changed = False
        for i, e in enumerate(edges):
            if e.degenerate or len(e.points) < 2 or not np.all(np.diff(e.params) > 0):
                continue  # nothing to fit, or not a grid (params must increase): gmsh will say so
            seg = e.segment_lengths
            size = field(0.5 * (e.points[:-1] + e.points[1:]))
            pieces = np.where(seg > ratio * size, np.ceil(seg / np.maximum(size, 1e-300)), 1).astype(int)
            if not np.any(pieces > 1) or e.tolerance > TOLERANCE_SHARE * np.min(seg / pieces):
                continue  # nothing to split, or a loose edge: new points would stray from its faces
            params, points = split_segments(e.params, e.points, pieces, curves[e.id].evaluate)
            edges[i] = dataclasses.replace(e, params=params, points=points)
            changed = True
        if not changed:
            break
    return with_edges(grid, edges)


class _LazyCurves(dict):
    """Edge curves of a grid that did not keep those refine_shape built: each built once, on first use."""

    def __init__(self, grid: ShapeGrid):
        super().__init__()
        self._grid = grid
        self._topo = None

    def __missing__(self, edge_id: int):
        from ..occt.edgecurve import EdgeCurve
        from ..occt.topology import Topology

        self._topo = self._topo or Topology(self._grid.shape)
        curve = self[edge_id] = EdgeCurve(self._topo.edges[edge_id - 1], edge_id)
        return curve
