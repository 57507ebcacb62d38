"""PLY exporter: the segments as 2-vertex ``face`` records, ASCII, shared vertex nodes.

The layout every common reader opens without failing: meshio's PLY reader accepts only ``vertex``
and ``face`` elements (an ``edge`` element makes ``meshio.read`` exit the process) and turns 2-vertex
faces into ``line`` cells; plyfile reads everything; vtk/pyvista read the segments as 2-point
polygons; trimesh reads the points (a mesh without faces). ASCII, because meshio's binary reader
misreads any face property besides the index list, and shortest round-trip floats keep coordinates
exact. Written here: meshio's PLY writer drops cell data (the edge ids).

Vertex properties: ``x y z`` (double), ``vertex_id`` (B-rep vertex id, 0 for interior points),
``edge_id`` (edge of an interior point, 0 at vertices), ``param`` (NaN at vertices); face
properties: ``vertex_indices`` and ``edge_id``. Point ``k - 1`` is B-rep vertex ``k``.
"""

from __future__ import annotations

import numpy as np

from ..shapegrid import ShapeGrid
from ._common import comment, edge_graph, table


def to_bytes(grid: ShapeGrid) -> bytes:
    """ASCII PLY: vertices with ids and parameters, one 2-vertex face with ``edge_id`` per segment."""
    g = edge_graph(grid)
    header = ("ply\nformat ascii 1.0\n"
              f"comment {comment(grid)}\n"
              f"element vertex {len(g.points)}\nproperty double x\nproperty double y\nproperty double z\n"
              "property int vertex_id\nproperty int edge_id\nproperty double param\n"
              f"element face {len(g.segments)}\nproperty list uchar int vertex_indices\nproperty int edge_id\n"
              "end_header\n")
    vertices = table([g.points[:, 0], g.points[:, 1], g.points[:, 2], g.vertex_id, g.edge_id, g.param])
    faces = table([np.full(len(g.segments), 2), g.segments[:, 0], g.segments[:, 1], g.segment_edge])
    return (header + vertices + faces).encode("ascii")
