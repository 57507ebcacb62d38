"""Pictures of edge grids and surface meshes: a static PNG (matplotlib) or an interactive HTML page
(plotly) that turns in 3-D and works offline, chosen by the file's suffix.

:func:`check_plot_path` is cheap, so the CLI checks the name before any work. The drawing libraries
are imported only when a picture is drawn, so importing :mod:`cadedge` or starting the CLI does not
pay for them. Every file is written atomically (:mod:`cadedge.atomic`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import InputError
from ..shapegrid import ShapeGrid

if TYPE_CHECKING:
    from ..mesh import MeshResult

SUFFIXES = (".png", ".html", ".htm")
COLOR_BY = ("segments", "ald")


def check_plot_path(path: str | os.PathLike) -> str:
    """The plot kind (``"png"`` or ``"html"``) of ``path``; InputError unless the suffix is supported and
    its folder exists."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in SUFFIXES:
        raise InputError(f"{os.fspath(path)}: unsupported plot suffix {p.suffix or '(none)'!r}; "
                         f"supported: {' '.join(SUFFIXES)}")
    if p.is_dir():
        raise InputError(f"{os.fspath(path)}: is a folder; give a file name")
    if not (p.parent if str(p.parent) else Path(".")).is_dir():
        raise InputError(f"{os.fspath(path)}: folder {os.fspath(p.parent)!r} does not exist")
    return "png" if suffix == ".png" else "html"


def _check_color_by(color_by: str) -> None:
    if color_by not in COLOR_BY:
        raise InputError(f"color_by must be one of {', '.join(COLOR_BY)}, got {color_by!r}")


def plot_grid(grid: ShapeGrid, path: str | os.PathLike, *, color_by: str = "segments",
              title: str | None = None) -> None:
    """Draw the edge grids of ``grid`` to ``path`` (.png or .html).

    ``color_by`` (``"segments"`` or ``"ald"``) colours the edges in the HTML page by their number of
    segments or their estimated arc-length deficit; the page can switch between the two. The PNG
    draws the polylines in black.
    """
    kind = check_plot_path(path)
    _check_color_by(color_by)
    if kind == "html":
        from .html import grid_html
        grid_html(grid, path, color_by=color_by, title=title)
    else:
        from .png import grid_png
        grid_png(grid, path, title=title)


def plot_mesh(result: MeshResult, path: str | os.PathLike, *, color_by: str = "segments",
              title: str | None = None) -> None:
    """Draw the surface mesh of ``result`` (triangles coloured by B-rep face) with its edge grids to
    ``path`` (.png or .html); ``color_by`` as in :func:`plot_grid`."""
    kind = check_plot_path(path)
    _check_color_by(color_by)
    if kind == "html":
        from .html import mesh_html
        mesh_html(result, path, color_by=color_by, title=title)
    else:
        from .png import mesh_png
        mesh_png(result, path, title=title)


__all__ = ["COLOR_BY", "SUFFIXES", "check_plot_path", "plot_grid", "plot_mesh"]
