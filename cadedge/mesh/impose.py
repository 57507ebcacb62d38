"""Impose cadedge's edge grids on gmsh's curves as their 1-D mesh.

Every gmsh point entity gets one node, shared by the B-rep vertices on it (vertices of one face at one
point are merged into one point: :mod:`cadedge.mesh.coincident`); every edge's interior grid points become
nodes on its gmsh curve (with gmsh parameters), and its line elements start and end on the vertex
nodes. Faces sharing an edge therefore share its nodes. With ``Mesh.MeshOnlyEmpty`` gmsh leaves these
curves alone and meshes only the faces (and the degenerate curves, which carry no grid, and the curves
of edges the mapping could not place, which gmsh meshes itself).
"""

from __future__ import annotations

from dataclasses import dataclass

import gmsh
import numpy as np

from ..shapegrid import ShapeGrid
from .gmsh_model import EntityMap


@dataclass
class ImposedNodes:
    """gmsh node tags of every grid point: ``vertex_nodes[vid]`` and ``edge_nodes[eid]`` (first to last)."""

    vertex_nodes: dict[int, int]
    edge_nodes: dict[int, np.ndarray]
    #: edges left to gmsh's own curve mesh (no matching curve, or an end vertex without a gmsh point)
    skipped: list[int]


def impose_edge_grids(grid: ShapeGrid, emap: EntityMap,
                      adopt: dict[int, tuple[np.ndarray, np.ndarray]] | None = None) -> ImposedNodes:
    """Add the grid nodes and line elements to the gmsh model; returns the node tags used.

    ``adopt[eid] = (points, params)`` replaces edge ``eid``'s grid by a 1-D mesh another gmsh process
    made of its curve (points from the edge's first vertex to its last, ends included, and their gmsh
    parameters; see :func:`cadedge.mesh.worker.changed_edges`)."""
    adopt = adopt or {}
    vertex_nodes: dict[int, int] = {}
    point_node: dict[int, int] = {}  # one node per gmsh point: vertices meshed as one share it
    for v in grid.vertices:
        if v.id not in emap.vertices:
            continue
        point = emap.vertices[v.id]
        if point not in point_node:
            gmsh.model.mesh.addNodes(0, point, [v.id], np.asarray(v.point, dtype=float).tolist())
            point_node[point] = v.id
        vertex_nodes[v.id] = point_node[point]
    next_node = max(vertex_nodes.values(), default=0) + 1
    next_elem = 1
    edge_nodes: dict[int, np.ndarray] = {}
    skipped = []
    for e in grid.edges:
        if e.degenerate:
            continue
        if e.id not in emap.edges or not all(v in vertex_nodes for v in e.vertices):
            skipped.append(e.id)
            continue
        match = emap.edges[e.id]
        points, params = adopt.get(e.id, (np.asarray(e.points, dtype=float), match.params))
        inner = len(points) - 2
        tags = np.arange(next_node, next_node + inner, dtype=np.int64)
        next_node += inner
        chain = np.concatenate([[vertex_nodes[e.vertices[0]]], tags, [vertex_nodes[e.vertices[1]]]])
        edge_nodes[e.id] = chain
        if params[-1] < params[0]:  # gmsh's curve runs the other way: give gmsh its own order
            chain, params, points = chain[::-1], params[::-1], points[::-1]
        if inner:
            gmsh.model.mesh.addNodes(1, match.tag, chain[1:-1].tolist(), points[1:-1].ravel().tolist(),
                                     params[1:-1].tolist())
        n_seg = len(chain) - 1
        conn = np.column_stack([chain[:-1], chain[1:]]).ravel()
        gmsh.model.mesh.addElementsByType(match.tag, 1, list(range(next_elem, next_elem + n_seg)), conn.tolist())
        next_elem += n_seg
    return ImposedNodes(vertex_nodes=vertex_nodes, edge_nodes=edge_nodes, skipped=skipped)
