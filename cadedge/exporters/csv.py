"""CSV exporter: one row per grid point (``edge_id,index,param,x,y,z``) after a header row.

Degenerate edges are included (their single point twice) so every edge id of the shape appears.
"""

from __future__ import annotations

from ..shapegrid import ShapeGrid
from ._common import polylines, table

HEADER = "edge_id,index,param,x,y,z\n"


def to_bytes(grid: ShapeGrid) -> bytes:
    """CSV text: header, then ``edge_id,index,param,x,y,z`` per grid point, edges in id order."""
    p = polylines(grid, skip_degenerate=False)
    body = table([p.point_edge, p.point_index, p.params, p.points[:, 0], p.points[:, 1], p.points[:, 2]],
                 delimiter=",")
    return (HEADER + body).encode("ascii")
