"""Helpers shared by the exporters: all edge polylines stacked into flat numpy arrays, and
full-precision text tables (Python's shortest round-trip float ``repr``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..shapegrid import ShapeGrid

@dataclass(frozen=True)
class Polylines:
    """Edge polylines one after another: edge ``k`` owns ``points[offsets[k]:offsets[k] + counts[k]]``."""

    edge_ids: np.ndarray   # (m,) int
    counts: np.ndarray     # (m,) int, points per edge
    offsets: np.ndarray    # (m,) int, first point of each edge
    points: np.ndarray     # (n, 3) float
    params: np.ndarray     # (n,) float
    point_edge: np.ndarray  # (n,) int, edge id of each point
    point_index: np.ndarray  # (n,) int, index of each point within its edge


def polylines(grid: ShapeGrid, *, skip_degenerate: bool) -> Polylines:
    """Stack the edges of ``grid`` (degenerate ones left out if ``skip_degenerate``)."""
    edges = [e for e in grid.edges if not (skip_degenerate and e.degenerate)]
    counts = np.array([len(e.params) for e in edges], dtype=np.int64)
    offsets = np.concatenate(([0], np.cumsum(counts)[:-1])).astype(np.int64)
    ids = np.array([e.id for e in edges], dtype=np.int64)
    if edges:
        points = np.concatenate([np.reshape(np.asarray(e.points, dtype=float), (-1, 3)) for e in edges])
        params = np.concatenate([np.asarray(e.params, dtype=float) for e in edges])
    else:
        points, params = np.zeros((0, 3)), np.zeros(0)
    total = int(counts.sum())
    return Polylines(edge_ids=ids, counts=counts, offsets=offsets, points=points, params=params,
                     point_edge=np.repeat(ids, counts),
                     point_index=np.arange(total, dtype=np.int64) - np.repeat(offsets, counts))


def table(columns: list[np.ndarray], *, delimiter: str = " ") -> str:
    """Rows of ``columns`` as text, one line each with a trailing newline; integer arrays print as
    integers, float arrays with ``repr`` (exact round trip)."""
    if not len(columns[0]):
        return ""
    text = [list(map(str, np.asarray(c).tolist())) for c in columns]
    return "\n".join(map(delimiter.join, zip(*text))) + "\n"


def comment(grid: ShapeGrid) -> str:
    """A one-line ASCII description of the grid for file headers."""
    text = f"cadedge edge grid of {grid.source} ({grid.units})"
    return " ".join(text.split()).encode("ascii", "replace").decode("ascii")
