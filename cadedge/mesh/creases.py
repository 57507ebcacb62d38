"""Folds of a face of linear extrusion, and the lines of nodes laid along them when it is meshed flat.

A section whose heading turns by :data:`FOLD_TURN` degrees within a small share of the triangles' size
(a V of spline points, a cusp), or by :data:`CORNER_TURN` at a corner (a B-spline's C0 knot), folds the
face: a triangle across the fold has its corners on both
flanks and loses most of its width (cyclo_gear's side at 1e-3: 1.4e-2 short). :mod:`cadedge.mesh.extruded`
finds the folds (:func:`folds`), lays a line of nodes along each in the plane it meshes
(:func:`fold_lines`, :func:`graded_points`), takes the fold's curvature out of the sizes
(:func:`across_folds`) and records the folds (:data:`CREASES`) so that the nodes on them stay there
(:func:`cadedge.mesh.facemesh.crease_nodes`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from .tangles import cross_properly

if TYPE_CHECKING:
    from .extruded import Extrusion

#: The section folds where its heading turns by at least :data:`FOLD_TURN` degrees within
#: :data:`FOLD_SPAN` of the face's typical size (the median of its sizes along ``x``): cyclo_gear's 30
#: valleys, V-shaped spline points 27 degrees apart, turn that much within 0.011-0.044 mm, against
#: sizes of 0.1-0.4 mm. A triangle across such a fold has its corners on both flanks and loses most of
#: its width; a line of nodes along the extrusion at the fold (:func:`fold_lines`) keeps every triangle
#: on one flank. A rounded turn wider than that is left to the curvature sizes, and so is one whose
#: flanks would lose too much beside the line (:data:`FOLD_LOSS`).
FOLD_TURN = 120.0
FOLD_SPAN = 0.25
#: A corner of the section (a B-spline's C0 knot) is a fold too when its heading turns by
#: :data:`CORNER_TURN` degrees or more there: between two samples of the section, which
#: :func:`cadedge.mesh.extruded.extrusion_of` samples until no gap of a smooth section turns more than
#: 5 degrees. A triangle across a corner turning by ``a`` cuts ``1 - cos(a / 2)`` off its width there
#: (29% at 90 degrees: a key blade's side, its notches' corners, 3.2e-2 short at 1e-3); a line along
#: it loses nothing beside it.
CORNER_TURN = 20.0
#: The share of the surface target (of the face's area) the flanks of its folds may lose beside their
#: lines (see :func:`cadedge.mesh.extruded._fold_sizes`).
FOLD_LOSS = 0.25


class Creases(NamedTuple):
    """The folds a face's mesh has lines of nodes along: ``column``, that of its parameters that runs
    along its section; ``at``, the section's parameters at the folds; ``ends``, the boundary nodes the
    lines end at (gmsh node tag -> index into ``at``). The lines' nodes and edges stay
    (:func:`cadedge.mesh.facemesh.crease_nodes`)."""

    column: int
    at: np.ndarray
    ends: dict[int, int]


#: gmsh surface -> its :class:`Creases`.
CREASES: dict[int, Creases] = {}
#: Growth of the sizes along a fold's line from the boundary segments at its ends, where the job has no
#: ``Extend`` field to take it from (:func:`cadedge.mesh.extruded._job_grading`).
GROWTH = 0.25


def folds(ext: Extrusion, table: np.ndarray, budget: float = np.inf) -> tuple[np.ndarray, float]:
    """The arc lengths ``x`` where the section of ``ext`` folds (:data:`FOLD_TURN`, :data:`FOLD_SPAN`),
    with its sizes ``table`` at its samples, and its typical size (the median), the window within which
    its lines and the flanks' sizes are found; one fold per run of samples whose span turns that much,
    where the heading turns fastest. Spans crossing the section's ends are not measured. The sharpest
    folds are kept while what their flanks lose next to the lines (:func:`fold_loss`) stays within
    ``budget`` (an area per unit of the extrusion's length)."""
    x = ext.x
    w = float(np.median(table))
    if not (w > 0 and len(x) > 2):
        return np.zeros(0), w
    span = 0.5 * FOLD_SPAN * w
    step = steps(ext.heading)
    jump = step >= np.radians(CORNER_TURN)
    corner = np.concatenate([jump, [False]]) | np.concatenate([[False], jump])
    sharp = (x - span >= x[0]) & (x + span <= x[-1]) & (_turned(ext, x, span) | corner)
    rate = step / np.maximum(np.diff(x), 1e-300)
    edges = np.diff(np.concatenate([[0], sharp.astype(np.int8), [0]]))
    found, losses = [], []
    for start, stop in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
        i = start + int(np.argmax(rate[start:min(stop, len(rate))])) if start < len(rate) else start
        xf = 0.5 * (x[i] + x[min(i + 1, len(x) - 1)])
        found.append(xf)
        losses.append(fold_loss(ext, xf, span))
    order = np.argsort(losses, kind="stable")
    kept = order[np.cumsum(np.asarray(losses)[order]) <= budget]
    return np.asarray(found)[np.sort(kept)], w


def steps(heading: np.ndarray) -> np.ndarray:
    """The angles (radians) unit headings (n, 3) turn by between consecutive rows (90 degrees beside a
    zero row)."""
    return np.arccos(np.clip(np.einsum("ij,ij->i", heading[:-1], heading[1:]), -1.0, 1.0))


def has_corner(ext: Extrusion) -> bool:
    """Whether the section has a corner turning by :data:`CORNER_TURN` degrees or more."""
    return bool(np.any(steps(ext.heading) >= np.radians(CORNER_TURN)))


def _turn(ext: Extrusion, centre, half) -> np.ndarray:
    """The angles (degrees) the section's heading turns by from ``centre - half`` to ``centre + half``
    (arc lengths, broadcast together; 90 degrees where a sample has no heading)."""
    lo = np.searchsorted(ext.x, centre - half)
    hi = np.searchsorted(ext.x, centre + half, side="right") - 1
    return np.degrees(np.arccos(np.clip(np.einsum("...j,...j->...", ext.heading[lo], ext.heading[hi]), -1.0, 1.0)))


def _turned(ext: Extrusion, centre, half, turn: float = FOLD_TURN) -> np.ndarray:
    """Whether the section's heading turns by ``turn`` degrees or more from ``centre - half`` to
    ``centre + half`` (see :func:`_turn`)."""
    return _turn(ext, centre, half) >= turn


def fold_loss(ext: Extrusion, xf: float, span: float) -> float:
    """What the flanks of the fold at ``xf`` lose next to its line, per unit of the extrusion's length:
    the section turns by ``a`` (:data:`FOLD_TURN`, or less at a corner: most of what it turns by within
    ``span``) within a width ``W`` there (the narrowest centred window that turns that much, at most
    ``2 span``), as a circle of radius ``R = W / a`` (radians) would; a triangle on each side spans the
    rest of that turn, a quarter circle at most, losing ``(pi/2 - sqrt 2) R`` across it. A corner turns
    within one gap of the section's samples: next to nothing."""
    turn = float(_turn(ext, xf, span))
    aim = FOLD_TURN if turn >= FOLD_TURN else 0.9 * turn
    half = np.geomspace(max(float(np.min(np.diff(ext.x))), 1e-12 * span), span, 48)
    turned = _turned(ext, xf, half, aim)
    width = 2.0 * float(half[np.argmax(turned)] if turned.any() else span)
    return 2.0 * (0.5 * np.pi - np.sqrt(2.0)) * width / np.radians(max(aim, 1e-9))


def across_folds(x: np.ndarray, values: np.ndarray, at: np.ndarray, window: float, pick) -> np.ndarray:
    """``values`` at the section's samples ``x`` with each fold's (``at``, :func:`folds`) taken out:
    within half the ``window`` of a fold, ``pick`` (``np.minimum`` or ``np.maximum``) of the values at
    that span's ends."""
    values = np.array(values, dtype=float)
    for xf in at:
        lo, hi = np.searchsorted(x, [xf - 0.5 * window, xf + 0.5 * window])
        lo, hi = max(lo - 1, 0), min(hi, len(x) - 1)
        values[lo:hi + 1] = pick(values[lo], values[hi])
    return values


def graded_points(p: np.ndarray, q: np.ndarray, size_p: float, size_q: float, size: float,
                  growth: float) -> np.ndarray:
    """Points (k, 2) splitting the segment ``p``-``q`` as the job's sizes would: ``size_p`` at ``p`` and
    ``size_q`` at ``q`` (their boundary segments'), growing by ``growth`` per unit distance from them, at
    most ``size``: the nodes are spread evenly in the integral of one over that size. A line split evenly
    at the flanks' size met boundary segments 400 times shorter at its ends: 0.1-degree fans there."""
    length = float(np.linalg.norm(q - p))
    s = np.linspace(0.0, length, 1025)
    h = np.minimum.reduce([np.full_like(s, size), size_p + growth * s, size_q + growth * (length - s)])
    h = np.maximum(h, 1e-12 * max(length, 1.0))
    count = np.concatenate([[0.0], np.cumsum(np.diff(s) / (0.5 * (h[1:] + h[:-1])))])
    pieces = max(1, int(round(count[-1])))
    at = np.interp(np.arange(1, pieces) * count[-1] / pieces, count, s)
    return p + np.outer(at / max(length, 1e-300), q - p)


def _inside(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
    """Whether ``point`` is inside the region bounded by segments ``a``-``b`` (rows): even-odd rule."""
    up = (a[:, 1] > point[1]) != (b[:, 1] > point[1])
    t = (point[1] - a[up, 1]) / (b[up, 1] - a[up, 1])
    return bool(np.count_nonzero(a[up, 0] + t * (b[up, 0] - a[up, 0]) > point[0]) % 2)


def fold_lines(plane: np.ndarray, segments: list[tuple[int, int]], at: np.ndarray,
               window: float) -> list[tuple[int, int, int]]:
    """Straight lines across the plane region bounded by ``segments`` (row pairs of ``plane``) at the
    folds ``at`` (``x``, :func:`folds`, with their ``window``), as (row, row, index of the fold): for
    each fold, the boundary nodes sharing the ``x`` nearest it within its span (:data:`FOLD_SPAN` of the
    window: a line farther off leaves triangles across the fold; a section's edges, split alike, put
    nodes at the same ``x``), joined in pairs along ``y`` where the line between them lies inside the
    region and crosses no boundary segment."""
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    a, b = plane[seg[:, 0]], plane[seg[:, 1]]
    known = {tuple(sorted(pair)) for pair in seg.tolist()}
    tol = 1e-6 * window
    lines: list[tuple[int, int, int]] = []
    for f, xf in enumerate(at):
        near = np.flatnonzero(np.abs(plane[:, 0] - xf) <= 0.5 * FOLD_SPAN * window)
        same = np.zeros(0, dtype=np.int64)
        for i in near[np.argsort(np.abs(plane[near, 0] - xf))]:
            same = near[np.abs(plane[near, 0] - plane[i, 0]) <= tol]
            if len(same) >= 2:
                break
        same = same[np.argsort(plane[same, 1])]
        for lo, hi in zip(same[:-1].tolist(), same[1:].tolist()):
            p, q = plane[lo], plane[hi]
            if (tuple(sorted((lo, hi))) in known or cross_properly(p, q, a, b).any()
                    or not _inside(0.5 * (p + q), a, b)):
                continue
            lines.append((lo, hi, f))
    return lines
