"""Write a :class:`~cadedge.shapegrid.ShapeGrid` to a file; the format comes from the suffix.

``FORMATS`` maps each suffix to a writer ``(ShapeGrid, path) -> None`` (one module per format,
imported when its writer is first used); :func:`write` hands it a temporary path and renames the
file into place only when it is complete (:mod:`cadedge.atomic`), so a failing export leaves no file
behind. JSON and CSV list every edge with its own points; the geometric formats (.vtp .vtu .vtk .msh
.geo .obj .ply) share one node per B-rep vertex among the edges that meet there and leave degenerate
edges' zero-length polylines out (.msh keeps their curve entities, without elements).
Which readers open what is in docs/formats.md.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Iterator

from ..atomic import atomic_path
from ..errors import InputError

if TYPE_CHECKING:
    from ..shapegrid import ShapeGrid

Writer = Callable[["ShapeGrid", Path], None]

#: Suffix -> (module of this package, its function). ``to_bytes(grid) -> bytes`` functions are wrapped
#: by :func:`~cadedge.exporters._common.bytes_writer`; ``write(grid, path)`` ones write the file themselves.
_WRITERS = {
    ".json": ("json", "to_bytes"),       # cadedge.edgegrid/1 document
    ".csv": ("csv", "to_bytes"),         # one row per grid point
    ".vtp": ("vtp", "to_bytes"),         # VTK XML PolyData, one polyline per edge
    ".vtu": ("vtu", "write"),            # VTK XML UnstructuredGrid, 2-node line cells (meshio)
    ".vtk": ("vtk_legacy", "write"),     # legacy VTK UnstructuredGrid, 2-node line cells (meshio)
    ".msh": ("msh", "to_bytes"),         # gmsh MSH 4.1 ASCII 1-D mesh
    ".geo": ("geo", "to_bytes"),         # gmsh built-in geometry script
    ".obj": ("obj", "to_bytes"),         # Wavefront OBJ polylines
    ".ply": ("ply", "to_bytes"),         # PLY vertices + 2-vertex faces (line cells)
}


@lru_cache(maxsize=None)
def _writer(suffix: str) -> Writer:
    """The writer of ``suffix``, its module imported now: a command pays only for the format it writes."""
    module, name = _WRITERS[suffix]
    function = getattr(importlib.import_module(f".{module}", __name__), name)
    if name == "to_bytes":
        from ._common import bytes_writer
        return bytes_writer(function)
    return function


class _Formats(Mapping[str, Writer]):
    """Suffix -> writer ``(ShapeGrid, path) -> None``; a format's module is imported when its writer is
    first looked up, so checking a suffix (``in``, iteration) imports nothing."""

    def __getitem__(self, suffix: str) -> Writer:
        if suffix not in _WRITERS:
            raise KeyError(suffix)
        return _writer(suffix)

    def __contains__(self, suffix: object) -> bool:
        return suffix in _WRITERS

    def __iter__(self) -> Iterator[str]:
        return iter(_WRITERS)

    def __len__(self) -> int:
        return len(_WRITERS)


FORMATS: Mapping[str, Writer] = _Formats()


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
