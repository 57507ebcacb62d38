"""Write a :class:`~cadedge.shapegrid.ShapeGrid` to a file; the format comes from the suffix.

``FORMATS`` maps each suffix to a function ``ShapeGrid -> bytes`` (one module per format). Every
write is atomic (:mod:`cadedge.atomic`): a failing export leaves no file behind. JSON and CSV list
every edge; the geometric formats (.vtp .msh .geo .obj .ply) leave degenerate edges' zero-length
polylines out (.msh keeps their curve entities, without elements).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable

from ..atomic import atomic_write_bytes
from ..errors import InputError
from ..shapegrid import ShapeGrid
from . import csv, geo, json, msh, obj, ply, vtp

FORMATS: dict[str, Callable[[ShapeGrid], bytes]] = {
    ".json": json.to_bytes,  # cadedge.edgegrid/1 document
    ".csv": csv.to_bytes,    # one row per grid point
    ".vtp": vtp.to_bytes,    # VTK PolyData XML polylines
    ".msh": msh.to_bytes,    # gmsh MSH 4.1 ASCII 1-D mesh
    ".geo": geo.to_bytes,    # gmsh built-in geometry script
    ".obj": obj.to_bytes,    # Wavefront OBJ polylines
    ".ply": ply.to_bytes,    # PLY vertices + edges
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
    data = FORMATS[suffix_of(path, format)](grid)
    try:
        atomic_write_bytes(path, data)
    except OSError as exc:
        raise InputError(f"{os.fspath(path)}: cannot write: {exc.strerror or exc}") from exc


__all__ = ["FORMATS", "suffix_of", "write"]
