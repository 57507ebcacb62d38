"""Static PNG pictures drawn with matplotlib's Agg canvas.

Polylines in black, B-rep vertices as small open circles, grid points as dots; degenerate edges are
skipped; a mesh's triangles are shaded by B-rep face under the edges. Figures are built on a bare
``Figure`` (no pyplot state), so this is safe in scripts, tests and worker processes.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from ..atomic import atomic_path
from ..shapegrid import ShapeGrid

if TYPE_CHECKING:
    from ..mesh import MeshResult


def _axes(grid: ShapeGrid) -> tuple[Any, Any]:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 6))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection="3d")
    ax.set_xlabel(f"x [{grid.units}]")
    ax.set_ylabel(f"y [{grid.units}]")
    ax.set_zlabel(f"z [{grid.units}]")
    return fig, ax


def _edges(ax: Any, grid: ShapeGrid) -> np.ndarray:
    """Draw the polylines, grid points and vertices; return every point drawn."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    live = [e for e in grid.edges if not e.degenerate]
    if live:
        ax.add_collection3d(Line3DCollection([np.asarray(e.points) for e in live], colors="black",
                                             linewidths=0.6))
        inner = np.concatenate([np.asarray(e.points)[1:-1] for e in live])
        if len(inner):
            ax.scatter(*inner.T, s=1.5, c="black", depthshade=False)
    vpoints = np.array([np.reshape(v.point, 3) for v in grid.vertices], dtype=float).reshape(-1, 3)
    if len(vpoints):
        ax.scatter(*vpoints.T, s=14, facecolors="none", edgecolors="tab:red", linewidths=0.8, depthshade=False)
    return np.concatenate([vpoints, *[np.asarray(e.points) for e in live]]) if live else vpoints


def _frame(ax: Any, points: np.ndarray) -> None:
    """Equal scales on the three axes around ``points``."""
    if not len(points):
        return
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre, half = (lo + hi) / 2, max(float((hi - lo).max()) / 2, 1e-12)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))


def _save(fig: Any, path: str | os.PathLike, dpi: int) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi)


def grid_png(grid: ShapeGrid, path: str | os.PathLike, *, title: str | None = None, dpi: int = 150) -> None:
    """Draw the edge grids of ``grid`` in 3-D and write a PNG to ``path`` atomically."""
    fig, ax = _axes(grid)
    _frame(ax, _edges(ax, grid))
    ax.set_title(title or f"{grid.source}: {len(grid.edges)} edges, {grid.segments} segments, "
                 f"ALD <= {grid.max_ald_estimate:.2g}", fontsize=9)
    _save(fig, path, dpi)


def mesh_png(result: MeshResult, path: str | os.PathLike, *, title: str | None = None, dpi: int = 150) -> None:
    """Draw the triangles of ``result`` (shaded by B-rep face) and its edge grids; write a PNG atomically."""
    from matplotlib import colormaps
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    grid = result.grid
    fig, ax = _axes(grid)
    nodes, triangles = np.asarray(result.nodes, dtype=float), np.asarray(result.triangles)
    if len(triangles):
        faces = np.asarray(result.triangle_faces)
        colours = colormaps["tab20"](faces % 20)
        ax.add_collection3d(Poly3DCollection(nodes[triangles], facecolors=colours, edgecolors="none",
                                             alpha=0.55))
    drawn = _edges(ax, grid)
    _frame(ax, np.concatenate([drawn, nodes.reshape(-1, 3)]))
    ax.set_title(title or f"{result.source}: {len(triangles)} triangles on "
                 f"{len(np.unique(result.triangle_faces))} faces, {grid.segments} edge segments", fontsize=9)
    _save(fig, path, dpi)
