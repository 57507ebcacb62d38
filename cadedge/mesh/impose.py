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
    parameters; see :func:`cadedge.mesh.worker.changed_edges`).

    Everything goes to gmsh in one merged MSH file (:func:`_merge`): ``addElementsByType`` rebuilds
    gmsh's node cache over every node on each call, so one call per curve grew with the square of the
    edges (a lattice of 25 300 edges spent minutes in it)."""
    adopt = adopt or {}
    vertex_nodes: dict[int, int] = {}
    point_node: dict[int, int] = {}  # one node per gmsh point: vertices meshed as one share it
    blocks: list[tuple[int, int, np.ndarray, np.ndarray, np.ndarray | None]] = []  # dim, tag, node tags, xyz, u
    for v in grid.vertices:
        if v.id not in emap.vertices:
            continue
        point = emap.vertices[v.id]
        if point not in point_node:
            blocks.append((0, point, np.array([v.id]), np.asarray(v.point, dtype=float).reshape(1, 3), None))
            point_node[point] = v.id
        vertex_nodes[v.id] = point_node[point]
    next_node = max(vertex_nodes.values(), default=0) + 1
    edge_nodes: dict[int, np.ndarray] = {}
    lines: list[tuple[int, np.ndarray]] = []  # curve tag, its segments' node tags (k, 2)
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
            blocks.append((1, match.tag, chain[1:-1], np.asarray(points[1:-1], dtype=float),
                           np.asarray(params[1:-1], dtype=float)))
        lines.append((match.tag, np.column_stack([chain[:-1], chain[1:]])))
    _merge(blocks, lines)
    return ImposedNodes(vertex_nodes=vertex_nodes, edge_nodes=edge_nodes, skipped=skipped)


def _merge(blocks: list[tuple[int, int, np.ndarray, np.ndarray, np.ndarray | None]],
           lines: list[tuple[int, np.ndarray]]) -> None:
    """Hand gmsh node ``blocks`` (entity dimension and tag, node tags, coordinates, curve parameters or
    None) and line elements (curve tag, node tag pairs; element tags 1, 2, ... in that order) as one
    binary MSH 4.1 file (native byte order, which the file declares; 8-byte tags, as gmsh's 64-bit
    ``size_t``) merged into the current model: gmsh's reader puts them on the model's own entities of
    those tags, as ``addNodes`` and ``addElementsByType`` would, coordinates bit for bit."""
    import os
    import tempfile

    if not blocks and not lines:
        return
    parts = [b"$MeshFormat\n4.1 1 8\n", np.array([1], dtype=np.int32).tobytes(), b"\n$EndMeshFormat\n"]
    if blocks:
        count = sum(len(b[2]) for b in blocks)
        tags = np.concatenate([b[2] for b in blocks])
        parts += [b"$Nodes\n", np.array([len(blocks), count, tags.min(), tags.max()], dtype=np.uint64).tobytes()]
        for dim, tag, nodes, xyz, u in blocks:
            parts += [np.array([dim, tag, u is not None], dtype=np.int32).tobytes(),
                      np.array([len(nodes)], dtype=np.uint64).tobytes(), np.asarray(nodes, dtype=np.uint64).tobytes(),
                      (xyz if u is None else np.column_stack([xyz, u])).astype(np.float64).tobytes()]
        parts.append(b"\n$EndNodes\n")
    if lines:
        total = sum(len(seg) for _, seg in lines)
        parts += [b"$Elements\n", np.array([len(lines), total, 1, total], dtype=np.uint64).tobytes()]
        first = 1
        for tag, seg in lines:
            rows = np.column_stack([np.arange(first, first + len(seg)), seg]).astype(np.uint64)
            parts += [np.array([1, tag, 1], dtype=np.int32).tobytes(), np.array([len(seg)], dtype=np.uint64).tobytes(),
                      rows.tobytes()]
            first += len(seg)
        parts.append(b"\n$EndElements\n")
    with tempfile.TemporaryDirectory(prefix="cadedge-grids-") as tmp:
        path = os.path.join(tmp, "grids.msh")
        with open(path, "wb") as f:
            f.write(b"".join(parts))
        gmsh.merge(path)
