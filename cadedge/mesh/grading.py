"""Face-wise boundary grading: each face's boundary segments graded from that face's own spacings.

The proximity split (:mod:`cadedge.mesh.proximity`) sizes boundaries from a global field that also feels
nearby solids, so a face can end up with one finely split side among coarse ones. Grading each face's
boundary from its own boundary points alone removes those jumps (nodes only added, shared edges stay
conforming).
"""

from __future__ import annotations

import dataclasses

import numpy as np


#: Face-wise grading: a boundary segment longer than this many times the size graded from its own face's
#: other boundary spacings is split (the global proximity field also feels nearby solids, so a face can
#: end up with one finely split side among coarse ones: 11-degree triangles on a box beside a cylinder).
GRADE_RATIO = 2.0


def grade_faces(grid, *, growth: float = 0.25, ratio: float = GRADE_RATIO, passes: int = 3):
    """A copy of ``grid`` in which every face's boundary is graded from its own spacings.

    Per face, the size at a boundary segment's midpoint is ``min_i (h_i + growth * d_i)`` over that face's
    own boundary grid points (:class:`~cadedge.mesh.sizes.SizeField` of the face's edges); segments longer
    than ``ratio`` times it are split into pieces of equal arc length on the OCCT curve (ends and grid points
    kept, so shared edges stay conforming). A few passes let the splits spread along the boundary.
    """
    from ..errors import InputError
    from ..shapegrid import end_tolerances, with_edges
    from .proximity import _LazyCurves
    from .sizes import SizeField

    curves = _LazyCurves(grid)  # each edge's OCCT curve built once, on first use
    ends = end_tolerances(grid)
    edges = list(grid.edges)
    by_face: dict[int, list[int]] = {}
    for i, e in enumerate(edges):
        for f in e.faces:
            by_face.setdefault(f, []).append(i)
    vertices = {v.id: v for v in grid.vertices}
    for _ in range(passes):
        pieces = {i: np.ones(max(len(e.points) - 1, 0), dtype=int) for i, e in enumerate(edges)}
        for idx in by_face.values():
            own = [edges[i] for i in idx if not edges[i].degenerate and len(edges[i].points) >= 2]
            if len(own) < 2:
                continue
            vids = {v for e in own for v in e.vertices}
            sub = dataclasses.replace(grid, edges=own, vertices=[vertices[v] for v in sorted(vids) if v in vertices])
            try:
                size = SizeField(sub, growth=growth)
            except InputError:
                continue
            for i in idx:
                e = edges[i]
                if e.degenerate or len(e.points) < 2:
                    continue
                h = size(0.5 * (e.points[:-1] + e.points[1:]))
                need = np.where(e.segment_lengths > ratio * h, np.ceil(e.segment_lengths / np.maximum(h, 1e-300)), 1)
                pieces[i] = np.maximum(pieces[i], need.astype(int))
        changed = False
        for i, k in pieces.items():
            e = edges[i]
            if not np.any(k > 1) or not np.all(np.diff(e.params) > 0):
                continue
            split = split_on_curve(e, curves, k, ends=ends[e.id])
            if split is not None:
                edges[i], changed = split, True
        if not changed:
            break
    return with_edges(grid, edges)


def split_on_curve(e, curves, pieces: np.ndarray, *, ends: float):
    """Edge grid ``e`` with segment ``k`` cut into ``pieces[k]`` pieces of equal arc length on its OCCT
    curve (``curves[e.id]``, grid points kept); None as for :func:`cut_on_curve`."""
    from ..splitting import equal_shares

    return cut_on_curve(e, curves, equal_shares(pieces), ends=ends)


def cut_on_curve(e, curves, cuts: dict[int, np.ndarray], *, ends: float):
    """Edge grid ``e`` with segment ``k`` cut at the shares ``cuts[k]`` (increasing, in (0, 1)) of its arc
    length on its OCCT curve (``curves[e.id]``, grid points kept); None when the curve cannot be built or
    evaluated, or the grid's parameters are not that curve's: its ends further from the curve's than
    ``ends`` allows (:func:`cadedge.shapegrid.end_tolerances`; the edge is then left alone)."""
    from ..errors import GeometryError
    from ..occt.compat import OCCT_ERRORS
    from ..splitting import cut_by_arc, fits_curve, insert_points

    try:
        curve = curves[e.id]
        if not fits_curve(e.params, e.points, curve.evaluate, ends):
            return None
        u, p = cut_by_arc(e.params, e.points, cuts, curve.evaluate)
    except (GeometryError, *OCCT_ERRORS):
        return None
    params, points = insert_points(e.params, e.points, u, p)
    return dataclasses.replace(e, params=params, points=points)
