"""Triangle quality: angles per triangle and per face, and which small angles the B-rep forces.

A triangle's quality here is its smallest interior angle. Simulation wants none below 5 degrees and
at least 99% at 20 degrees or more. A face corner sharper than 5 degrees (two boundary edges meeting
almost tangentially) forces a small angle on whatever triangle fills it: such triangles are named with
that reason instead of counted against the mesher.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Below this many degrees a triangle is a sliver unless the B-rep forces it.
SLIVER_DEG = 5.0
#: The share of triangles at or above this many degrees is the quality figure (target: 99%).
GOOD_DEG = 20.0


def triangle_angles(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Interior angles (m, 3) in degrees; column ``k`` is the angle at corner ``k``."""
    p = np.asarray(nodes, dtype=float)[np.asarray(triangles, dtype=np.int64).reshape(-1, 3)]
    out = np.empty((len(p), 3))
    for k in range(3):
        a = p[:, (k + 1) % 3] - p[:, k]
        b = p[:, (k + 2) % 3] - p[:, k]
        cross = np.linalg.norm(np.cross(a, b), axis=1)
        out[:, k] = np.degrees(np.arctan2(cross, np.einsum("ij,ij->i", a, b)))
    return out


@dataclass
class SmallAngle:
    """A triangle under :data:`SLIVER_DEG`: its face, its angle, and whether (and why) the B-rep forces it."""

    face: int
    angle: float
    forced: bool
    reason: str


def small_angles(nodes: np.ndarray, triangles: np.ndarray, triangle_faces: np.ndarray,
                 vertex_points: np.ndarray, angles: np.ndarray | None = None) -> list[SmallAngle]:
    """Every triangle under :data:`SLIVER_DEG`, worst first.

    Forced: its smallest angle sits on a B-rep vertex (a node at one of ``vertex_points``) where the face's
    corner, the sum of that face's triangle angles at the node, is itself under :data:`SLIVER_DEG`.
    """
    tris = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    ang = triangle_angles(nodes, tris) if angles is None else angles
    low = np.flatnonzero(ang.min(axis=1) < SLIVER_DEG)
    if not len(low):
        return []
    faces = np.asarray(triangle_faces, dtype=np.int64)
    nodes = np.asarray(nodes, dtype=float)
    vpts = np.asarray(vertex_points, dtype=float).reshape(-1, 3)
    out = []
    for t in low[np.argsort(ang[low].min(axis=1))]:
        k = int(np.argmin(ang[t]))
        node = tris[t, k]
        at_vertex = len(vpts) and np.min(np.linalg.norm(vpts - nodes[node], axis=1)) <= 1e-9 * (
            1.0 + np.abs(nodes[node]).max())
        reason = "not forced by the B-rep"
        forced = False
        if at_vertex:
            same = (faces == faces[t]) & np.any(tris == node, axis=1)
            corner = float(np.sum(ang[same][tris[same] == node]))
            if corner < SLIVER_DEG:
                forced = True
                reason = f"the face's corner at that B-rep vertex is {corner:.2g} deg"
        out.append(SmallAngle(face=int(faces[t]), angle=float(ang[t, k]), forced=forced, reason=reason))
    return out
