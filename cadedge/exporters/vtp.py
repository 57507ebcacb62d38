"""VTK PolyData XML (``.vtp``) exporter: one polyline cell per non-degenerate edge, shared vertex nodes.

Written here because meshio cannot write PolyData and vtk (which can) is a large binary dependency
just for this; the XML is ASCII with shortest round-trip floats, so coordinates are exact. Points:
the B-rep vertices first (point ``k - 1`` is vertex ``k``), then each edge's interior points. Cell
data ``edge_id``; point data ``vertex_id``, ``edge_id`` and ``param`` as in :mod:`._meshio`. vtk,
pyvista and ParaView read it; meshio does not (use .vtu for meshio).
"""

from __future__ import annotations

import numpy as np

from ..shapegrid import ShapeGrid
from ._common import edge_graph, table


def _array(name: str, vtk_type: str, values: np.ndarray, components: int = 1) -> str:
    comps = f' NumberOfComponents="{components}"' if components > 1 else ""
    body = table([np.ravel(values)]) if np.size(values) else ""
    return f'<DataArray type="{vtk_type}" Name="{name}"{comps} format="ascii">\n{body}</DataArray>\n'


def to_bytes(grid: ShapeGrid) -> bytes:
    """VTK XML PolyData: all grid points once, one polyline cell per non-degenerate edge."""
    g = edge_graph(grid)
    n, m = len(g.points), len(g.edge_ids)
    xml = (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n'
        '<PolyData>\n'
        f'<Piece NumberOfPoints="{n}" NumberOfVerts="0" NumberOfLines="{m}" NumberOfStrips="0" '
        'NumberOfPolys="0">\n'
        '<PointData>\n' + _array("vertex_id", "Int32", g.vertex_id) + _array("edge_id", "Int32", g.edge_id)
        + _array("param", "Float64", g.param) + '</PointData>\n'
        '<CellData Scalars="edge_id">\n' + _array("edge_id", "Int32", g.edge_ids) + '</CellData>\n'
        '<Points>\n' + _array("Points", "Float64", g.points, 3) + '</Points>\n'
        '<Lines>\n' + _array("connectivity", "Int64", g.connectivity)
        + _array("offsets", "Int64", g.chain_offsets[1:]) + '</Lines>\n'
        '</Piece>\n</PolyData>\n</VTKFile>\n'
    )
    return xml.encode("ascii")
