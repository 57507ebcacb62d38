"""Wavefront OBJ exporter: one object ``o edge_<id>`` with one ``l`` polyline per non-degenerate edge.

Vertices are shared (``v`` number ``k`` is B-rep vertex ``k``, interior points follow) and written
with shortest round-trip floats (exact). ``l`` is OBJ's only polyline record, but not every reader
keeps it: vtk/pyvista/ParaView and Blender read the polylines; trimesh's and meshio's OBJ readers
parse faces only, so they return the points without the lines (see docs/formats.md). trimesh writes
OBJ only for triangle meshes and meshio only for polygons, hence this writer. Objects (``o``), not
groups (``g``): vtk's OBJ reader turns groups of lines into an empty ``GroupIds`` array that pyvista
warns about on every read.
"""

from __future__ import annotations

import numpy as np

from ..shapegrid import ShapeGrid
from ._common import comment, edge_graph, table


def to_bytes(grid: ShapeGrid) -> bytes:
    """OBJ text: ``v`` records, then per edge an ``o edge_<id>`` line and its ``l`` polyline."""
    g = edge_graph(grid)
    lines = [f"# {comment(grid)}\n", "# v k = cadedge vertex k for k <= number of vertices\n"]
    lines.append(table([np.full(len(g.points), "v"), g.points[:, 0], g.points[:, 1], g.points[:, 2]]))
    for j, eid in enumerate(g.edge_ids.tolist()):
        chain = g.connectivity[g.chain_offsets[j]:g.chain_offsets[j + 1]] + 1
        lines.append(f"o edge_{eid}\nl {' '.join(map(str, chain.tolist()))}\n")
    return "".join(lines).encode("utf-8")
