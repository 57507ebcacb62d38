"""Write a :class:`~cadedge.shapegrid.ShapeGrid` to a file; the format comes from the suffix.

``FORMATS`` maps each suffix to a writer ``(ShapeGrid, path) -> None`` (one module per format);
:func:`write` hands it a temporary path and renames the file into place only when it is complete
(:mod:`cadedge.atomic`), so a failing export leaves no file behind. JSON and CSV list every edge with
its own points; the geometric formats (.vtp .vtu .vtk .msh .geo .obj .ply) share one node per B-rep
vertex among the edges that meet there and leave degenerate edges' zero-length polylines out (.msh
keeps their curve entities, without elements). Which readers open what is in docs/formats.md.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable

from ..atomic import atomic_path
from ..errors import InputError
from ..shapegrid import ShapeGrid
from . import csv, geo, json, msh, obj, ply, vtk_legacy, vtp, vtu
from ._common import bytes_writer

FORMATS: dict[str, Callable[[ShapeGrid, Path], None]] = {
    ".json": bytes_writer(json.to_bytes),  # cadedge.edgegrid/1 document
    ".csv": bytes_writer(csv.to_bytes),    # one row per grid point
    ".vtp": bytes_writer(vtp.to_bytes),    # VTK XML PolyData, one polyline per edge
    ".vtu": vtu.write,                     # VTK XML UnstructuredGrid, 2-node line cells (meshio)
    ".vtk": vtk_legacy.write,              # legacy VTK UnstructuredGrid, 2-node line cells (meshio)
    ".msh": bytes_writer(msh.to_bytes),    # gmsh MSH 4.1 ASCII 1-D mesh
    ".geo": bytes_writer(geo.to_bytes),    # gmsh built-in geometry script
    ".obj": bytes_writer(obj.to_bytes),    # Wavefront OBJ polylines
    ".ply": bytes_writer(ply.to_bytes),    # PLY vertices + 2-vertex faces (line cells)
}


def suffix_of(path: str | os.PathLike, format: str | None = None) -> str:
    """The registry key for ``path`` (or for ``format``, e.g. ``"json"``); InputError if unsupported.

    Cheap, so callers (the CLI) check the output name before any expensive work.
    """
    key = (format if format.startswith(".") else f".{format}") if format else Path(path).suffix
    key = key.lower()
    if key not in FORMATS:
        what = f"format {format!r}" if format else f"suffix {Path(path).suffix or '(none)'!r}"
        raise InputError(f"{os.fspath(path)}: unsupported output {what}; supported: {' '.join(FORMATS)}")
    return key


def write(grid: ShapeGrid, path: str | os.PathLike, *, format: str | None = None) -> None:
    """Write ``grid`` to ``path`` atomically in the format of its suffix (or ``format``)."""
    writer = FORMATS[suffix_of(path, format)]
    try:
        with atomic_path(path) as tmp:
            writer(grid, tmp)
    except OSError as exc:
        raise InputError(f"{os.fspath(path)}: cannot write: {exc.strerror or exc}") from exc


__all__ = ["FORMATS", "suffix_of", "write"]
