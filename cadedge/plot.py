"""A quick look at a shape's edge grids: a 3-D PNG drawn with matplotlib's Agg canvas.

Polylines in black, B-rep vertices as small open circles, grid points as dots; degenerate edges are
skipped. The figure is built on a bare ``Figure`` (no pyplot state), so it is safe in scripts,
tests and worker processes, and the PNG is written atomically.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .atomic import atomic_path
from .errors import InputError
from .shapegrid import ShapeGrid


def check_plot_path(path: str | os.PathLike) -> None:
    """InputError unless ``path`` ends in .png and its folder exists (cheap; call before refining)."""
    p = Path(path)
    if p.suffix.lower() != ".png":
        raise InputError(f"{os.fspath(path)}: unsupported plot suffix {p.suffix or '(none)'!r}; supported: .png")
    if p.is_dir():
        raise InputError(f"{os.fspath(path)}: is a folder; give a file name")
    if not (p.parent if str(p.parent) else Path(".")).is_dir():
        raise InputError(f"{os.fspath(path)}: folder {os.fspath(p.parent)!r} does not exist")


def plot_grid(grid: ShapeGrid, path: str | os.PathLike, *, title: str | None = None, dpi: int = 150) -> None:
    """Draw the edge grids of ``grid`` in 3-D and write a PNG to ``path`` atomically."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    check_plot_path(path)
    live = [e for e in grid.edges if not e.degenerate]
    fig = Figure(figsize=(7, 6))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection="3d")
    if live:
        ax.add_collection3d(Line3DCollection([np.asarray(e.points) for e in live], colors="black",
                                             linewidths=0.6))
        inner = np.concatenate([np.asarray(e.points)[1:-1] for e in live])
        if len(inner):
            ax.scatter(*inner.T, s=1.5, c="black", depthshade=False)
    vpoints = np.array([np.reshape(v.point, 3) for v in grid.vertices], dtype=float).reshape(-1, 3)
    if len(vpoints):
        ax.scatter(*vpoints.T, s=14, facecolors="none", edgecolors="tab:red", linewidths=0.8, depthshade=False)
    everything = np.concatenate([vpoints, *[np.asarray(e.points) for e in live]]) if live else vpoints
    if len(everything):
        lo, hi = everything.min(axis=0), everything.max(axis=0)
        centre, half = (lo + hi) / 2, max(float((hi - lo).max()) / 2, 1e-12)
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_zlim(centre[2] - half, centre[2] + half)
        ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel(f"x [{grid.units}]")
    ax.set_ylabel(f"y [{grid.units}]")
    ax.set_zlabel(f"z [{grid.units}]")
    ax.set_title(title or f"{grid.source}: {len(grid.edges)} edges, {grid.segments} segments, "
                 f"ALD <= {grid.max_ald_estimate:.2g}", fontsize=9)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi)
