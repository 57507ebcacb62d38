"""B-rep vertices of one face that lie at one point: meshed as one node.

A boolean can leave two vertices at one point of a face: a tee whose run cylinder has its seam
through the tangent point of the branch keeps the seam's vertex and the intersection loop's vertex
apart there (OCCT's check passes the model). The face's parametric domain is then pinched at that
point, and gmsh, given one node per vertex, joins the two coinciding nodes with zero-area triangles:
a crack in the shell and triangles at 0 degrees, with gmsh's own curve meshes as with cadedge's.
Meshed as one vertex (:func:`cadedge.occt.merge.merge_vertices` on the shape gmsh imports), the same
faces mesh cleanly in all three of gmsh's 2-D algorithms.

The grid keeps every vertex id; ``coincident`` maps each vertex merged away to the vertex it is meshed
as (the lowest id of its group).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ..shapegrid import ShapeGrid


def coincident_vertices(grid: ShapeGrid) -> dict[int, int]:
    """Vertex id -> id of the vertex it is meshed as, for vertices that bound a common face and lie
    within the larger of their tolerances of each other, and are not the two ends of one edge (a
    zero-length edge between them would vanish). Each group goes to its lowest id.

    >>> from cadedge.shapegrid import VertexGrid
    >>> v = [VertexGrid(id=i, point=np.array(p, float), tolerance=1e-7)
    ...      for i, p in enumerate([(0, 0, 0), (1, 0, 0), (0, 0, 0)], start=1)]
    >>> coincident_vertices(ShapeGrid(source="s", units="mm", options={}, vertices=v, edges=[]))
    {}
    """
    if len(grid.vertices) < 2:
        return {}
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    ids = np.array([v.id for v in grid.vertices], dtype=np.int64)
    points = np.array([np.asarray(v.point, dtype=float).reshape(3) for v in grid.vertices])
    tol = np.array([max(float(v.tolerance), 0.0) for v in grid.vertices])
    pairs = cKDTree(points).query_pairs(r=float(tol.max()), output_type="ndarray")
    if not len(pairs):
        return {}
    near = np.linalg.norm(points[pairs[:, 0]] - points[pairs[:, 1]], axis=1) <= np.maximum(tol[pairs[:, 0]],
                                                                                           tol[pairs[:, 1]])
    pairs = pairs[near]
    if not len(pairs):
        return {}
    faces: dict[int, set[int]] = {}
    joined: set[tuple[int, int]] = set()
    for e in grid.edges:
        for v in e.vertices:
            faces.setdefault(int(v), set()).update(e.faces)
        if len(e.vertices) == 2:
            joined.add((min(e.vertices), max(e.vertices)))
    keep = [(a, b) for a, b in pairs
            if faces.get(int(ids[a]), set()) & faces.get(int(ids[b]), set())
            and (min(ids[a], ids[b]), max(ids[a], ids[b])) not in joined]
    if not keep:
        return {}
    a, b = np.array(keep, dtype=np.int64).T
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(len(ids), len(ids)))
    _, label = connected_components(graph, directed=False)
    lowest = {}
    for k in np.argsort(ids):
        lowest.setdefault(int(label[k]), int(ids[k]))
    return {int(i): lowest[int(label[k])] for k, i in enumerate(ids) if lowest[int(label[k])] != int(i)}


def merged_shape(grid: ShapeGrid) -> tuple[Any, dict[int, int]]:
    """``grid.shape`` with its :func:`coincident_vertices` merged (:func:`cadedge.occt.merge.merge_vertices`)
    and the merges made: none, and the shape as it was, where OCCT's check refuses the merged faces."""
    into = coincident_vertices(grid)
    if not into:
        return grid.shape, {}
    from ..occt.merge import merge_vertices

    return merge_vertices(grid.shape, into)


def point_tags(grid: ShapeGrid, coincident: dict[int, int]) -> dict[int, int]:
    """Vertex id -> tag of its point in the shape with the ``coincident`` vertices merged: that shape's
    ``MapShapes`` order is the old one without the vertices merged away (each group's lowest id comes
    first in it), and gmsh numbers its points in that order.

    >>> from cadedge.shapegrid import VertexGrid
    >>> v = [VertexGrid(id=i, point=np.zeros(3)) for i in (1, 2, 3, 4)]
    >>> point_tags(ShapeGrid(source="s", units="mm", options={}, vertices=v, edges=[]), {3: 1})
    {1: 1, 2: 2, 3: 1, 4: 3}
    """
    ids = sorted(v.id for v in grid.vertices)
    tag = {vid: k for k, vid in enumerate((i for i in ids if i not in coincident), start=1)}
    return {vid: tag[coincident.get(vid, vid)] for vid in ids}


def meshed_as(grid: ShapeGrid, coincident: dict[int, int]) -> ShapeGrid:
    """``grid`` with each vertex merged away, and the ends of its edges, moved onto the point of the
    vertex it is meshed as (within tolerance of where they were): the mesh has one node there."""
    if not coincident:
        return grid
    where = {v.id: np.asarray(v.point, dtype=float) for v in grid.vertices}
    vertices = [dataclasses.replace(v, point=where[coincident[v.id]].copy()) if v.id in coincident else v
                for v in grid.vertices]
    edges = []
    for e in grid.edges:
        if not set(e.vertices) & set(coincident) or not len(e.points):
            edges.append(e)
            continue
        points = np.array(e.points, dtype=float)
        points[0] = where[coincident.get(e.vertices[0], e.vertices[0])]
        points[-1] = where[coincident.get(e.vertices[-1], e.vertices[-1])]
        edges.append(dataclasses.replace(e, points=points))
    return dataclasses.replace(grid, vertices=vertices, edges=edges)
