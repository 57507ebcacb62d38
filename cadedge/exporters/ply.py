"""PLY exporter: polylines as the ``edge`` element (``vertex1``, ``vertex2``), binary little-endian.

Written here rather than by trimesh's path exporter because that one stores float32 coordinates and
drops the edge ids; the layout is the one trimesh reads back as a ``Path3D``. Vertices carry float64
``x y z``, the curve parameter ``param`` and the cadedge ``edge_id``; degenerate edges are left out.
"""

from __future__ import annotations

import numpy as np

from ..shapegrid import ShapeGrid
from ._common import comment, polylines

VERTEX = np.dtype([("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("param", "<f8"), ("edge_id", "<i4")])
EDGE = np.dtype([("vertex1", "<i4"), ("vertex2", "<i4")])


def to_bytes(grid: ShapeGrid) -> bytes:
    """Binary PLY: float64 vertices with ``param`` and ``edge_id``, and 2-vertex ``edge`` records."""
    p = polylines(grid, skip_degenerate=True)
    vertices = np.empty(len(p.params), dtype=VERTEX)
    vertices["x"], vertices["y"], vertices["z"] = p.points.T
    vertices["param"], vertices["edge_id"] = p.params, p.point_edge
    # segment k joins point k and k + 1 unless k is the last point of its edge
    last = p.offsets + p.counts - 1
    start = np.setdiff1d(np.arange(len(p.params)), last)
    edges = np.empty(len(start), dtype=EDGE)
    edges["vertex1"], edges["vertex2"] = start, start + 1
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"comment {comment(grid)}\n"
              f"element vertex {len(vertices)}\nproperty double x\nproperty double y\nproperty double z\n"
              "property double param\nproperty int edge_id\n"
              f"element edge {len(edges)}\nproperty int vertex1\nproperty int vertex2\n"
              "end_header\n")
    return header.encode("ascii") + vertices.tobytes() + edges.tobytes()
