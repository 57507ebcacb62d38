"""Split edge-grid segments that are much longer than the mesh size around them.

An edge grid meets its ALD with very few segments on straight edges; but a face whose boundary has a
24 mm segment 7 mm from a hole meshed at 0.5 mm can only be filled with slivers next to that
segment, whatever the interior sizes. Before the grids are imposed, every segment longer than
``ratio`` (3) times the size field at its midpoint (graded from all edges' spacings, so a nearby edge
counts even when it is not adjacent) is split into equal parameter steps on its OCCT curve. Edge
ends are never moved, so shared vertices stay bit-identical, and splitting only lowers the ALD.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from ..shapegrid import ShapeGrid, vertex_spacings

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
    from ..occt.edgecurve import EdgeCurve
    from ..occt.topology import Topology

    topo = None
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
            topo = topo or Topology(grid.shape)
            new_u = np.concatenate([e.params[k] + (e.params[k + 1] - e.params[k]) * np.arange(1, n) / n
                                    for k, n in enumerate(pieces) if n > 1])
            new_p = EdgeCurve(topo.edges[e.id - 1], e.id).evaluate(new_u)
            at = np.repeat(np.arange(1, len(e.params)), pieces - 1)
            edges[i] = dataclasses.replace(e, params=np.insert(e.params, at, new_u),
                                           points=np.insert(e.points, at, new_p, axis=0))
            changed = True
        if not changed:
            break
    spacing = vertex_spacings(edges)
    vertices = [dataclasses.replace(v, spacing=spacing.get(v.id, v.spacing)) for v in grid.vertices]
    return dataclasses.replace(grid, edges=edges, vertices=vertices)
