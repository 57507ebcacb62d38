"""Wavefront OBJ exporter: polylines as ``l`` records, one group ``edge_<id>`` per non-degenerate edge.

trimesh writes OBJ only for triangle meshes, so the few lines are written here; vertices carry full
float precision. Edges do not share vertices (each edge lists its own points), as in the CSV.
"""

from __future__ import annotations

import numpy as np

from ..shapegrid import ShapeGrid
from ._common import comment, polylines, table


def to_bytes(grid: ShapeGrid) -> bytes:
    """OBJ text: ``v`` records, then one ``g edge_<id>`` group with one ``l`` polyline per edge."""
    p = polylines(grid, skip_degenerate=True)
    lines = [f"# {comment(grid)}\n", "o cadedge_edges\n"]
    lines.append(table([np.full(len(p.params), "v"), p.points[:, 0], p.points[:, 1], p.points[:, 2]]))
    for eid, start, count in zip(p.edge_ids.tolist(), p.offsets.tolist(), p.counts.tolist()):
        idx = " ".join(map(str, range(start + 1, start + count + 1)))
        lines.append(f"g edge_{eid}\nl {idx}\n")
    return "".join(lines).encode("utf-8")
