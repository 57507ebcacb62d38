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
#: An edge is not cut into pieces it lies off its faces' boundaries by more than this share of: on a
#: loose edge (vertices off the curve, curves off the faces) a new point can fall so far from the face's
#: own boundary that gmsh builds near-degenerate triangles there. Its segments are cut as far as that
#: allows (:meth:`Looseness.capped`).
TOLERANCE_SHARE = 1e-3
#: An edge whose distance from its faces' boundaries is measured, not bounded, may be cut into pieces down
#: to twenty times that distance (a new point then off the face's boundary by at most 5% of a piece, as
#: the wedges' grading allows, :data:`cadedge.mesh.wedges.LOOSE_SHARE`): dlr_f6.brep at 1e-2 kept
#: segments 2-4 times as long as strips 0.3-0.7 wide along edges measured 0.0007-0.0012 off, and 64
#: triangles under 5 degrees (1.7-1.9) in them; 17 at a hundred times, in strips along edges 0.026-0.041
#: off. A Fusion phone holder's helical strips 0.176 wide, their edges 0.005-0.0066 off them, kept
#: segments of 1.08 at a hundred times (0.66 the shortest): 2.46% of its triangles under 20 degrees, 0.04%
#: at twenty.
MEASURED_SHARE = 5e-2
#: OCCT's ``Precision::Confusion``: no edge is held tighter than this, measured or not, so no piece is cut
#: shorter than a thousand times it (a tee's ellipses, measured to 2e-8, were cut to 2e-5 mm pieces
#: beside the point where its branch touches its run: 1.2-degree triangles).
CONFUSION = 1e-7
#: Each pass rebuilds the field from the split grid; sizes settle in a few.
PASSES = 3


class Looseness:
    """Whether an edge of ``grid`` is too loose to be cut into pieces of a given length: by its tolerance, a
    bound (:data:`TOLERANCE_SHARE`), and where that bound says so, by the distance it is measured to lie
    from its faces' boundaries (:data:`MEASURED_SHARE`; :func:`cadedge.occt.offsets.edge_offsets`, once an
    edge; one with a face left unmeasured keeps its bound). gmsh's benchmark cylinder.brep, a band 0.0005
    tall round a 0.02 cylinder read with edge tolerances of 1e-5, kept its circles' 0.0016 segments and
    9.2% of its triangles under 20 degrees; the circles lie on the band to 1e-15."""

    def __init__(self, grid: ShapeGrid) -> None:
        self.shape = grid.shape
        self.measured: dict[int, float | None] = {}

    def too_loose(self, e, piece: float) -> bool:
        return e.tolerance > TOLERANCE_SHARE * piece and piece < self.shortest(e)

    def capped(self, e, pieces: np.ndarray) -> np.ndarray:
        """``pieces`` (how many pieces each segment of ``e`` is to be cut into) cut back so that none is
        shorter than ``e`` allows: a loose edge is cut as far as it may be, segment by segment, not left
        whole because one segment would be cut too short. A tight edge's ``pieces`` come back as they are."""
        if not np.any(pieces > 1):
            return pieces
        seg = e.segment_lengths
        if not self.too_loose(e, float(np.min(seg / pieces))):
            return pieces
        return np.minimum(pieces, np.maximum(np.floor(seg / self.shortest(e)), 1)).astype(np.int64)

    def shortest(self, e) -> float:
        """The shortest piece edge ``e`` may be cut into (its faces measured on first use)."""
        bound = e.tolerance / TOLERANCE_SHARE
        if self.shape is None or not e.faces:
            return bound
        if e.id not in self.measured:
            from ..occt.offsets import edge_offsets

            per_face = [d[e.id] for d in edge_offsets(self.shape, [e], e.faces).values() if e.id in d]
            whole = len(per_face) == len(set(e.faces))  # every face measured, else the bound stands
            self.measured[e.id] = max(max(per_face), CONFUSION) if whole else None
        measured = self.measured[e.id]
        return bound if measured is None else min(bound, measured / MEASURED_SHARE)


def fit_to_sizes(grid: ShapeGrid, make_field: Callable[[ShapeGrid], Callable[[np.ndarray], np.ndarray]], *,
                 ratio: float = RATIO, passes: int = PASSES) -> ShapeGrid:
    """A copy of ``grid`` whose segments are at most ``ratio`` times the size field (``make_field(grid)``)."""
    curves = grid.curves if grid.curves is not None else _LazyCurves(grid)
    edges = list(grid.edges)
    loose = Looseness(grid)
    for _ in range(passes):
        field = make_field(dataclasses.replace(grid, edges=edges))
        changed = False
        for i, e in enumerate(edges):
            if e.degenerate or len(e.points) < 2 or not np.all(np.diff(e.params) > 0):
                continue  # nothing to fit, or not a grid (params must increase): gmsh will say so
            seg = e.segment_lengths
            size = field(0.5 * (e.points[:-1] + e.points[1:]))
            pieces = np.where(seg > ratio * size, np.ceil(seg / np.maximum(size, 1e-300)), 1).astype(np.int64)
            pieces = loose.capped(e, pieces)  # a loose edge: shorter pieces would stray from its faces
            if not np.any(pieces > 1):
                continue
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
