"""VTK PolyData XML (``.vtp``) exporter: one polyline cell per non-degenerate edge.

Cell data ``edge_id`` (the cadedge edge id), point data ``param`` (the curve parameter of each grid
point). ASCII with full-precision floats, so ParaView/VTK read it without any binary-encoding issue.
"""

from __future__ import annotations

import numpy as np

from ..shapegrid import ShapeGrid
from ._common import polylines, table


def _array(name: str, vtk_type: str, values: np.ndarray, components: int = 1) -> str:
    comps = f' NumberOfComponents="{components}"' if components > 1 else ""
    body = table([np.ravel(values)]) if np.size(values) else ""
    return f'<DataArray type="{vtk_type}" Name="{name}"{comps} format="ascii">\n{body}</DataArray>\n'


def to_bytes(grid: ShapeGrid) -> bytes:
    """VTK XML PolyData: all grid points, one polyline cell per non-degenerate edge."""
    p = polylines(grid, skip_degenerate=True)
    n, m = len(p.params), len(p.edge_ids)
    connectivity = np.arange(n, dtype=np.int64)
    offsets = p.offsets + p.counts
    xml = (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n'
        '<PolyData>\n'
        f'<Piece NumberOfPoints="{n}" NumberOfVerts="0" NumberOfLines="{m}" NumberOfStrips="0" '
        'NumberOfPolys="0">\n'
        '<PointData Scalars="param">\n' + _array("param", "Float64", p.params) + '</PointData>\n'
        '<CellData Scalars="edge_id">\n' + _array("edge_id", "Int32", p.edge_ids) + '</CellData>\n'
        '<Points>\n' + _array("Points", "Float64", p.points, 3) + '</Points>\n'
        '<Lines>\n' + _array("connectivity", "Int64", connectivity) + _array("offsets", "Int64", offsets)
        + '</Lines>\n'
        '</Piece>\n</PolyData>\n</VTKFile>\n'
    )
    return xml.encode("ascii")
