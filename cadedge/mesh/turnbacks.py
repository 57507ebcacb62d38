"""Edge-grid points where the edge's curve turns back on itself, dropped before the grids are imposed.

A B-spline edge may run out and come back along its own path: a SolidWorks 2019 DIN-rail mount's
helical thread edges each hook back 0.0004-0.0005 mm once a turn (60 edges), a TraceParts USB socket's
edge leaves its vertex, runs 0.0064 mm out and returns. The refined grid follows the curve, so at 1e-3
a point stands at the hook's tip, its two segments nearly on each other (they turn by 180 degrees).
Both faces on the edge then fill the hook with the same triangle, back to back: the segment at its base
carries four triangles and the check fails (48 such places on the mount at 1e-3, exit 1).

Such a point is dropped from the grid imposed on the faces, the two segments becoming one chord across
the hook's base, which both faces share: a point whose segments turn by more than :data:`TURN_BACK`
degrees and one of whose sides is short (:data:`HOOK_SHARE`; a curve's own sharp tip, a razor-thin wing
section's trailing edge, has two long sides and stays), again until none is left (a hook of several
points loses its tip first). A smooth curve's grid turns that far only where a chord falls 26% short of
its arc (two chords of an arc turn by the angle each spans), so grids refined to an ALD under
:data:`MAX_ALD` are looked at. The edge's ends stay, so shared vertices stay bit-identical. This runs
after every split: a split of the chord evaluates the curve inside the hook and would put the tip back.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..shapegrid import ShapeGrid, with_edges

#: A grid point whose two segments turn by more than this many degrees is a hook's tip.
TURN_BACK = 150.0
#: Grids refined to this ALD or more are left as they are: their arcs' chords may turn that far.
MAX_ALD = 0.2
#: ... where one side of the tip, up to where the polyline turns by more than 90 degrees or ends, is at
#: most this share of the edge: the hooks above are 0.04% and 4% of their edges.
HOOK_SHARE = 0.05


def _turns(points: np.ndarray, degrees: float) -> np.ndarray:
    """Whether each inner point of ``points`` (n, 3) turns its polyline by more than ``degrees`` (n - 2,)."""
    d = np.diff(points, axis=0)
    n = np.linalg.norm(d, axis=1)
    dot = np.einsum("ij,ij->i", d[:-1], d[1:])
    return (dot < np.cos(np.radians(degrees)) * n[:-1] * n[1:]) & (n[:-1] > 0) & (n[1:] > 0)


def turn_backs(points: np.ndarray, *, closed: bool = False) -> np.ndarray:
    """Indices of the inner ``points`` (n, 3) at a hook's tip: their two segments turn by more than
    :data:`TURN_BACK` degrees, and the polyline on one side of them, followed until it turns by more than
    90 degrees or ends, is at most :data:`HOOK_SHARE` of the whole. A curve's own sharp tip (a razor-thin
    wing's ridge, an airfoil's trailing edge on one edge) has two long sides and stays; on a ``closed``
    polyline (first point = last) a side runs on across its ends (the wing's section, closed near its
    trailing edge, has one segment between the edge's tip and its end).

    >>> turn_backs(np.array([[0.0, 0, 0], [1, 0, 0], [0.9, 0.001, 0], [2, 0, 0], [3, 0, 0]]))
    array([1, 2])
    >>> turn_backs(np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 0.01, 0], [0, 0.02, 0]]))
    array([], dtype=int64)
    """
    p = np.asarray(points, dtype=float)
    if len(p) < 3:
        return np.zeros(0, dtype=np.int64)
    tips = np.flatnonzero(_turns(p, TURN_BACK)) + 1
    if not len(tips):
        return tips
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    bends = np.flatnonzero(_turns(p, 90.0)) + 1  # where a side ends
    short = HOOK_SHARE * seg.sum()
    hooks = []
    for i in tips.tolist():
        before = bends[bends < i]
        after = bends[bends > i]
        back = seg[(before.max() if len(before) else 0):i].sum()
        ahead = seg[i:(after.min() if len(after) else len(p) - 1)].sum()
        if closed:  # a side with no bend before the end runs on from the other end
            back += 0.0 if len(before) else seg[(bends.max() if len(bends) else 0):].sum()
            ahead += 0.0 if len(after) else seg[:(bends.min() if len(bends) else 0)].sum()
        if min(back, ahead) <= short:
            hooks.append(i)
    return np.array(hooks, dtype=np.int64)


def drop_turn_backs(grid: ShapeGrid) -> tuple[ShapeGrid, list[int]]:
    """``grid`` without the points where its edges' curves turn back on themselves (module doc), and the
    ids of the edges that lost any; ``grid`` itself if it was refined to :data:`MAX_ALD` or more."""
    if float(grid.options.get("ald") or np.inf) >= MAX_ALD:
        return grid, []
    edges = list(grid.edges)
    changed = []
    for i, e in enumerate(edges):
        if e.degenerate or len(e.points) < 3:
            continue
        keep = np.ones(len(e.points), dtype=bool)
        while True:
            inner = np.flatnonzero(keep)
            tips = turn_backs(e.points[inner], closed=e.closed)
            if not len(tips):
                break
            keep[inner[tips[0]]] = False  # one at a time: its neighbours' turns change
        if not keep.all():
            edges[i] = dataclasses.replace(e, params=e.params[keep], points=e.points[keep])
            changed.append(e.id)
    return (with_edges(grid, edges) if changed else grid), changed
