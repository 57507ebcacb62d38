"""Inside the gmsh job: a developable face laid flat, meshed by gmsh as a plane face in a model of its own,
and the triangles added back to the face.

A developable surface unrolls without stretching, so triangles made in the plane keep their lengths and
angles when they are rolled back onto it: gmsh meshes the plane, where it has no parameters to distort,
and never sees the surface. :mod:`cadedge.mesh.developed` lays out cones with their apex on their
boundary, :mod:`cadedge.mesh.extruded` faces of linear extrusion; both lay the face's boundary nodes out
in the plane and call :func:`mesh_plane`, roll the new nodes back up, then :func:`add_triangles`.
"""

from __future__ import annotations

from typing import Callable

import numpy as np


def loops(segments: list[tuple[int, int]]) -> list[list[int]] | None:
    """The closed chains of ``segments`` (pairs of point keys), each as its segments' indices in order and
    signed (``-i - 1``: segment ``i`` run backwards); None if they do not close."""
    ends: dict[int, list[int]] = {}
    for i, (a, b) in enumerate(segments):
        ends.setdefault(a, []).append(i)
        ends.setdefault(b, []).append(i)
    if any(len(v) != 2 for v in ends.values()):
        return None
    used = [False] * len(segments)
    found = []
    for first in range(len(segments)):
        if used[first]:
            continue
        loop, i, at = [], first, segments[first][0]
        while not used[i]:
            used[i] = True
            a, b = segments[i]
            loop.append(i if a == at else -i - 1)
            at = b if a == at else a
            i = next((j for j in ends[at] if not used[j]), i)
        found.append(loop)
    return found


def loop_areas(plane: np.ndarray, segments, chains: list[list[int]]) -> list[float]:
    """The signed area of each of ``chains`` (:func:`loops` of ``segments``, pairs of rows of ``plane``
    (n, 2)), walked the way it runs: the largest is the outer loop, the others holes."""
    from ..grid import polygon_area

    return [polygon_area(plane[[segments[i][0] if i >= 0 else segments[-i - 1][1] for i in chain]])
            for chain in chains]


def boundary_sizes(plane: np.ndarray, segments: list[tuple[int, int]]) -> np.ndarray:
    """Each point of ``plane`` (n, 2) sized as the mean length of the ``segments`` (row pairs) at it: gmsh
    carries these sizes inwards (``Mesh.MeshSizeExtendFromBoundary``)."""
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    length = np.linalg.norm(plane[seg[:, 0]] - plane[seg[:, 1]], axis=1)
    total = np.bincount(seg.ravel(), weights=np.repeat(length, 2), minlength=len(plane))
    count = np.bincount(seg.ravel(), minlength=len(plane))
    return total / np.maximum(count, 1)


def mesh_plane(plane: np.ndarray, segments: list[tuple[int, int]], near: np.ndarray, algorithm: int,
               sizing: Callable[[], None], options: dict[str, float],
               inner: list[tuple[int, int, np.ndarray]] = ()) -> tuple[np.ndarray, np.ndarray] | str:
    """Mesh the plane region bounded by ``segments`` (pairs of rows of ``plane`` (n, 2), closing into
    loops: the outer one and holes) with gmsh's 2-D ``algorithm``, each segment kept whole and each point
    sized ``near``; the lines ``inner`` (two rows and the points (k, 2) between them, inside the region)
    are embedded in it, split at those points, so that no triangle crosses them. In a gmsh model of its
    own: ``options`` (gmsh option -> value) are set for it and ``sizing()`` is called with it current to
    set its size field or callback; the caller's model and options are restored after. Returns the points
    (N, 2), the boundary's ``n`` first then gmsh's new ones, and the triangles (m, 3) as rows of them; or
    why not."""
    import gmsh

    from .generate import OLD_INITIAL_FROM

    chains = loops(segments)
    if not chains:
        return "its boundary does not close when unrolled"
    current = gmsh.model.getCurrent()
    fixed = {"Mesh.MeshSizeExtendFromBoundary": 1, "Mesh.MeshOnlyVisible": 0, "Mesh.MeshOnlyEmpty": 0,
             "Mesh.Algorithm": algorithm, "Mesh.OldInitialDelaunay2D": int(len(plane) >= OLD_INITIAL_FROM),
             **options}
    saved = {o: gmsh.option.getNumber(o) for o in fixed}
    gmsh.model.add("cadedge unrolled face")
    try:
        for o, value in fixed.items():
            gmsh.option.setNumber(o, value)
        points = [gmsh.model.geo.addPoint(px, py, 0.0, h) for (px, py), h in zip(plane, near)]
        lines = [gmsh.model.geo.addLine(points[a], points[b]) for a, b in segments]
        outer = int(np.argmax(np.abs(loop_areas(plane, segments, chains))))
        curve_loops = [gmsh.model.geo.addCurveLoop([lines[i] if i >= 0 else -lines[-i - 1] for i in chains[k]])
                       for k in [outer] + [k for k in range(len(chains)) if k != outer]]
        surface = gmsh.model.geo.addPlaneSurface(curve_loops)
        # the inner lines are split at the points given, not by the size field (gmsh integrates the field
        # along a line to split it): so split, cyclo_gear's first lines ran over the 60 s attempt bound
        embedded = []
        for a, b, between in inner:
            chain = [points[a], *(gmsh.model.geo.addPoint(px, py, 0.0) for px, py in between), points[b]]
            embedded += [gmsh.model.geo.addLine(p, q) for p, q in zip(chain[:-1], chain[1:])]
        gmsh.model.geo.synchronize()
        for line in lines + embedded:
            gmsh.model.mesh.setTransfiniteCurve(line, 2)
        if embedded:
            gmsh.model.mesh.embed(1, embedded, 2, surface)
        sizing()
        try:
            gmsh.model.mesh.generate(2)
        except Exception as err:  # gmsh raises a bare Exception with its last error message
            return f"unrolled: {err}"
        point_nodes = [gmsh.model.mesh.getNodes(0, point)[0] for point in points]
        tags, coords, _ = gmsh.model.mesh.getNodes()
        _, tri = gmsh.model.mesh.getElementsByType(2)
    finally:
        gmsh.model.remove()
        gmsh.model.setCurrent(current)
        for o, value in saved.items():
            gmsh.option.setNumber(o, value)
    if not len(tri):
        return "unrolled: gmsh made no triangles"
    tags = np.asarray(tags, dtype=np.int64)
    xy = np.asarray(coords, dtype=float).reshape(-1, 3)[:, :2]
    row = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    for i, got in enumerate(point_nodes):
        if len(got):
            row[int(got[0])] = i
    inner = row[tags] < 0
    row[tags[inner]] = len(plane) + np.arange(int(inner.sum()))
    out = np.vstack([plane, xy[inner]])
    return out, row[np.asarray(tri, dtype=np.int64)].reshape(-1, 3)


def add_triangles(surface: int, tags: np.ndarray, xyz: np.ndarray, tri: np.ndarray,
                  params: np.ndarray | None = None) -> None:
    """Add triangles ``tri`` (rows of ``xyz`` (N, 3)) to (empty) gmsh surface ``surface``: rows whose
    ``tags`` are positive are the face's boundary nodes, the others new nodes on the surface, at their
    ``params`` (rows (N, 2); found by gmsh's projection if None). The triangles are turned to run as gmsh's
    own do on the surface (:func:`orient`, at their first corners' ``params`` if given)."""
    import gmsh

    tags = np.array(tags, dtype=np.int64)
    fresh = np.flatnonzero(tags <= 0)
    tags[fresh] = int(gmsh.model.mesh.getMaxNodeTag()) + 1 + np.arange(len(fresh))
    if len(fresh):
        uv = (np.asarray(gmsh.model.getParametrization(2, surface, xyz[fresh].ravel().tolist()), dtype=float)
              if params is None else np.asarray(params, dtype=float)[fresh].ravel())
        gmsh.model.mesh.addNodes(2, surface, tags[fresh].tolist(), xyz[fresh].ravel().tolist(), uv.tolist())
    elements = tags[tri]
    orient(surface, elements, xyz[tri], None if params is None else np.asarray(params, dtype=float)[tri[:, 0]])
    gmsh.model.mesh.addElementsByType(surface, 2, [], elements.ravel().tolist())


def orient(surface: int, tri: np.ndarray, corners: np.ndarray, uv: np.ndarray | None = None) -> None:
    """Turn triangles ``tri`` (node tags, in place; their corners' points (m, 3, 3)) to run as gmsh's own
    do on ``surface``: their normals along the surface's, at the parameters ``uv`` (m, 2) if given, else
    at the points of the surface nearest their centres (gmsh's projection: 40 s for 70 000 triangles on
    a 600-point spline's extrusion)."""
    import gmsh

    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    if uv is None:
        _, uv = gmsh.model.getClosestPoint(2, surface, corners.mean(axis=1).ravel().tolist())
    up = np.asarray(gmsh.model.getNormal(surface, np.asarray(uv, dtype=float).ravel().tolist()),
                    dtype=float).reshape(-1, 3)
    if np.sum(np.einsum("ij,ij->i", normal, up)) < 0:
        tri[:, [1, 2]] = tri[:, [2, 1]]
