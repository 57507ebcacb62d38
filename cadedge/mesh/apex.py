"""Boundary segments graded down towards a narrow cone's apex.

A cone unrolls into a sector of angle ``2 pi sin(a)``; at a distance ``r`` from the apex it is
``2 pi sin(a) r`` round. Its seam (or any edge running into the apex) keeps the segments the edges'
ALD and the face's curvature size gave it, the same from the base to the tip: on a 1 x 60 cone at
1e-2, 0.105 long where the cone is 0.01 round, and every triangle on them near the tip a sliver
(23 under 5 degrees, 16 of them not forced by the apex; 0.98% under 20). The interior of an unrolled
cone is already sized at most the sector's width over :data:`~cadedge.mesh.developed.WRAP`
(:mod:`cadedge.mesh.developed`); here the boundary segments are split to the same size, measured at
their end nearer the apex. The segments that touch the apex are kept: the apex's fan has its
smallest angles (the sector over three) whatever their length. Only cones narrower than
:data:`~cadedge.mesh.developed.NARROW` are graded, those meshed unrolled first: on wider ones gmsh
meshes the face in its parameters, and the split changed their meshes both ways (smallest angles of the
hard models' tangent_union at 1e-2 43.0 -> 37.4 degrees, seams_and_poles at 1e-3 30.3 -> 40.0).
"""

from __future__ import annotations

import numpy as np

from ..shapegrid import ShapeGrid, end_tolerances, with_edges
from .developed import NARROW, WRAP
from .grading import split_on_curve
from .proximity import _LazyCurves

#: A segment is cut into at most this many pieces: a cone a thousand times longer than wide would
#: otherwise take thousands of nodes per segment near its apex.
MAX_PIECES = 200


def grade_to_apexes(grid: ShapeGrid, cones: dict[int, tuple[np.ndarray, float]], *,
                    wrap: float = WRAP) -> ShapeGrid:
    """A copy of ``grid`` whose edges on the narrow cone faces of ``cones`` (face id -> (apex, sine of
    the half-angle), :func:`cadedge.occt.cones.apex_cones`) have no segment longer than the cone's
    circumference over ``2 pi wrap`` (the sector's width over ``wrap``) at the segment's end nearer the
    apex, the segments touching the apex left whole. Pieces are of equal arc length on the OCCT curve;
    grid points are kept, so shared edges stay conforming."""
    cones = {f: cone for f, cone in cones.items() if cone[1] < NARROW}
    if not cones:
        return grid
    curves = _LazyCurves(grid)
    ends = end_tolerances(grid)
    edges = list(grid.edges)
    changed = False
    for i, e in enumerate(edges):
        on = [cones[f] for f in e.faces if f in cones]
        if not on or e.degenerate or len(e.points) < 2 or not np.all(np.diff(e.params) > 0):
            continue
        pieces = np.ones(len(e.points) - 1, dtype=int)
        for apex, sine in on:
            rho = np.linalg.norm(e.points - apex, axis=1)
            near = np.minimum(rho[:-1], rho[1:])
            width = 2.0 * np.pi * sine * near / wrap
            tip = near <= max(e.tolerance, 1e-12 * float(rho.max()))  # a segment from the apex: the fan's
            need = np.ceil(e.segment_lengths / np.maximum(width, 1e-300))
            pieces = np.maximum(pieces, np.where(tip, 1, np.minimum(need, MAX_PIECES)).astype(int))
        split = split_on_curve(e, curves, pieces, ends=ends[e.id]) if np.any(pieces > 1) else None
        if split is not None:
            edges[i], changed = split, True
    return with_edges(grid, edges) if changed else grid
