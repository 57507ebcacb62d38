"""A face's narrow corners: where two of its edges leave a B-rep vertex at a small angle, and the
segments that end there (the corner's *tips*).

Found from the edge grids alone, by the angle between the two edges' first segments; the wedges' grading
(:mod:`cadedge.mesh.wedges`) and the face corners' matching (:func:`cadedge.mesh.widths.match_corners`)
both start from them.
"""

from __future__ import annotations

import dataclasses

import numpy as np

#: Corners of a face narrower than this many degrees (between its two edges' first segments) are graded.
WEDGE_DEG = 20.0


@dataclasses.dataclass(frozen=True)
class Corner:
    """A face's corner at a B-rep vertex: its two sides as (edge index, whether the edge starts there),
    and the angle in degrees between the sides' first segments."""

    face: int
    vertex: int
    sides: tuple[tuple[int, bool], tuple[int, bool]]
    angle: float


def from_vertex(e, at_start: bool) -> np.ndarray:
    """The edge grid's points, ordered from the corner's vertex."""
    return e.points if at_start else e.points[::-1]


def narrow_corners(edges: list, *, below: float = WEDGE_DEG) -> list[Corner]:
    """Every corner where a face's boundary meets a B-rep vertex (degenerate edges and grids of fewer than
    two points left out) between two edge ends whose first segments are under ``below`` degrees apart.
    Where the boundary passes the vertex more than once (a hole touching the outline: four ends, two
    cusps), the ends are paired closest first, each end in one corner."""
    ends: dict[tuple[int, int], list[tuple[int, bool]]] = {}
    for i, e in enumerate(edges):
        if e.degenerate or len(e.points) < 2 or len(e.vertices) < 2:
            continue
        for f in e.faces:
            ends.setdefault((f, e.vertices[0]), []).append((i, True))
            ends.setdefault((f, e.vertices[-1]), []).append((i, False))
    corners = [(key, sides) for key, sides in ends.items() if len(sides) >= 2]
    if not corners:
        return []
    # every side's first segment from the vertex, in one array (calls per corner cost the Koch leader
    # arm's 12 104 edges 10 s over the four passes of its corner matching)
    seg = np.array([(edges[i].points[0], edges[i].points[1]) if s else (edges[i].points[-1], edges[i].points[-2])
                    for _, sides in corners for i, s in sides]).reshape(-1, 2, 3)
    d = seg[:, 1] - seg[:, 0]
    norms = np.linalg.norm(d, axis=1)
    units = d / np.where(norms > 0, norms, 1.0)[:, None]
    count = np.array([len(sides) for _, sides in corners])
    start = np.cumsum(count) - count
    two = start[count == 2]  # most corners: one angle each, all at once
    cos = np.einsum("ij,ij->i", units[two], units[two + 1])
    angle_of = dict(zip(two.tolist(), np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).tolist()))
    out = []
    for ((f, v), sides), at in zip(corners, start.tolist()):
        used = norms[at:at + len(sides)] <= 0
        if len(sides) == 2:
            if angle_of[at] < below and not used.any():
                out.append(Corner(face=f, vertex=v, sides=(sides[0], sides[1]), angle=angle_of[at]))
            continue
        unit = units[at:at + len(sides)]
        angles = np.degrees(np.arccos(np.clip(unit @ unit.T, -1.0, 1.0)))
        pairs = sorted((angles[a, b], a, b) for a, b in zip(*np.triu_indices(len(sides), k=1)))
        for angle, a, b in pairs:
            if angle < below and not used[a] and not used[b]:
                used[[a, b]] = True
                out.append(Corner(face=f, vertex=v, sides=(sides[a], sides[b]), angle=float(angle)))
    return out


def tip_segment(e, at_start: bool) -> int:
    """Index of the edge grid's segment at its start (``at_start``) or end."""
    return 0 if at_start else len(e.points) - 2


def tip_length(e, at_start: bool) -> float:
    """Length of the edge grid's segment at its start (``at_start``) or end."""
    return float(e.segment_lengths[tip_segment(e, at_start)])
