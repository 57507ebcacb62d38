"""gmsh MSH 4.1 ASCII exporter: the edge grids as a 1-D mesh on discrete entities.

Point entity ``k`` is cadedge vertex ``k`` (one node, tag ``k``, and a point element); curve entity
``k`` is cadedge edge ``k``, bounded by its two vertices (start positive, end negative, as gmsh
writes them), holding the edge's interior grid points as nodes and one 2-node line element per
segment. The end nodes of every edge are the shared vertex nodes, so the 1-D mesh is conforming.
Degenerate edges appear as curve entities without nodes or elements.
"""

from __future__ import annotations

import numpy as np

from ..shapegrid import ShapeGrid
from ._common import table

POINT_ELEMENT, LINE_ELEMENT = 15, 1


def _bbox(points: np.ndarray) -> str:
    return " ".join(map(str, np.concatenate([points.min(axis=0), points.max(axis=0)]).tolist()))


def to_bytes(grid: ShapeGrid) -> bytes:
    """MSH 4.1 ASCII: point and curve entities tagged with cadedge ids, nodes, point and line elements."""
    nv = len(grid.vertices)
    vpoints = np.array([np.reshape(v.point, 3) for v in grid.vertices], dtype=float).reshape(-1, 3)
    vids = np.array([v.id for v in grid.vertices], dtype=np.int64)

    entities = [f"{nv} {len(grid.edges)} 0 0"]
    entities += [f"{vid} {x!r} {y!r} {z!r} 0" for vid, (x, y, z) in zip(vids.tolist(), vpoints.tolist())]
    node_blocks = [f"0 {vid} 0 1\n{vid}\n{x!r} {y!r} {z!r}" for vid, (x, y, z) in zip(vids.tolist(),
                                                                                     vpoints.tolist())]
    elem_blocks = [f"0 {vid} {POINT_ELEMENT} 1\n{k + 1} {vid}" for k, vid in enumerate(vids.tolist())]
    next_node, next_elem = int(vids.max(initial=0)) + 1, nv + 1
    for e in grid.edges:
        pts = np.reshape(np.asarray(e.points, dtype=float), (-1, 3))
        first, last = int(e.vertices[0]), int(e.vertices[1])
        entities.append(f"{e.id} {_bbox(pts)} 0 2 {first} {-last}")
        if e.degenerate:
            continue
        inner = pts[1:-1]
        tags = np.arange(next_node, next_node + len(inner), dtype=np.int64)
        next_node += len(inner)
        if len(inner):
            node_blocks.append(f"1 {e.id} 0 {len(inner)}\n" + table([tags]) + table(list(inner.T)).rstrip("\n"))
        chain = np.concatenate(([first], tags, [last]))
        etags = np.arange(next_elem, next_elem + len(chain) - 1, dtype=np.int64)
        next_elem += len(etags)
        elem_blocks.append(f"1 {e.id} {LINE_ELEMENT} {len(etags)}\n"
                           + table([etags, chain[:-1], chain[1:]]).rstrip("\n"))
    n_nodes, n_elems = next_node - 1, next_elem - 1
    text = ("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
            "$Entities\n" + "\n".join(entities) + "\n$EndEntities\n"
            f"$Nodes\n{len(node_blocks)} {n_nodes} {min(1, n_nodes)} {n_nodes}\n"
            + "".join(b + "\n" for b in node_blocks) + "$EndNodes\n"
            f"$Elements\n{len(elem_blocks)} {n_elems} {min(1, n_elems)} {n_elems}\n"
            + "".join(b + "\n" for b in elem_blocks) + "$EndElements\n")
    return text.encode("ascii")
