"""Legacy VTK (``.vtk``) exporter, written by meshio (see :mod:`._meshio` for the layout).

An UNSTRUCTURED_GRID of 2-node line cells with cell data ``edge_id``, binary float64 points; for
tools that read only the legacy format. File version 4.2: vtk's legacy reader refuses the
``vtktypeint32`` arrays of meshio's default 5.1 layout, so the ids would be lost. (``cadedge mesh -o x.vtk`` writes triangles instead; that
suffix belongs to the mesher there.)
"""

from __future__ import annotations

from pathlib import Path

from ..shapegrid import ShapeGrid
from . import _meshio


def write(grid: ShapeGrid, path: Path) -> None:
    """Write ``grid`` as a legacy .vtk file of line cells with ``edge_id`` cell data."""
    _meshio.write(grid, path, "vtk42")
