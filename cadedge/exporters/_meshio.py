"""The edge grids as a :class:`meshio.Mesh` of 2-node ``line`` cells on shared vertex nodes.

Used by the .vtu and legacy .vtk exporters, which meshio writes correctly: float64 points in binary
(exact), integer and float data arrays. meshio has no polyline cell, so each grid segment is one
cell; cell data ``edge_id`` says which cadedge edge it belongs to. Point data: ``vertex_id`` (the
B-rep vertex id, 0 for interior points), ``edge_id`` (the edge of an interior point, 0 at vertices)
and ``param`` (the curve parameter of an interior point; NaN at vertices, which several edges share).
"""

from __future__ import annotations

from pathlib import Path

from ..shapegrid import ShapeGrid
from ._common import edge_graph


def write(grid: ShapeGrid, path: Path, file_format: str) -> None:
    """Write ``grid`` to ``path`` with meshio's ``file_format`` writer."""
    import meshio

    g = edge_graph(grid)
    mesh = meshio.Mesh(g.points, [("line", g.segments)],
                       point_data={"vertex_id": g.vertex_id, "edge_id": g.edge_id, "param": g.param},
                       cell_data={"edge_id": [g.segment_edge]})
    meshio.write(str(path), mesh, file_format=file_format)
