"""VTK XML UnstructuredGrid (``.vtu``) exporter, written by meshio (see :mod:`._meshio` for the layout).

The VTK format that meshio, vtk, pyvista and ParaView all read: one 2-node line cell per segment
with cell data ``edge_id``; binary, zlib-compressed, float64 points.
"""

from __future__ import annotations

from pathlib import Path

from ..shapegrid import ShapeGrid
from . import _meshio


def write(grid: ShapeGrid, path: Path) -> None:
    """Write ``grid`` as a .vtu file of line cells with ``edge_id`` cell data."""
    _meshio.write(grid, path, "vtu")
