"""Helpers shared by the exporters: the edge polylines stacked into flat numpy arrays (one run of
points per edge, for the tabular formats), the same grids as a graph with shared vertex nodes (for
the mesh-like formats), and full-precision text tables (Python's shortest round-trip float ``repr``)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

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


@dataclass(frozen=True)
class EdgeGraph:
    """The edge grids with shared vertex nodes, as .msh writes them.

    Point ``k - 1`` is B-rep vertex ``k`` (every edge that meets there uses that one point); the
    interior grid points of the non-degenerate edges follow, edge after edge. Edge ``edge_ids[j]`` is
    the chain ``connectivity[chain_offsets[j]:chain_offsets[j + 1]]`` (from its first vertex to its
    last; a closed edge starts and ends on the same point); ``segments`` lists the same chains as
    2-point cells, ``segment_edge`` their edge ids.
    """

    points: np.ndarray         # (n, 3) float
    vertex_id: np.ndarray      # (n,) int32, B-rep vertex id, 0 for interior points
    edge_id: np.ndarray        # (n,) int32, owning edge of an interior point, 0 for vertex points
    param: np.ndarray          # (n,) float, curve parameter of an interior point, NaN at vertex points
    edge_ids: np.ndarray       # (m,) int32, the non-degenerate edges in id order
    connectivity: np.ndarray   # (sum of chain lengths,) int64
    chain_offsets: np.ndarray  # (m + 1,) int64
    segments: np.ndarray       # (s, 2) int64
    segment_edge: np.ndarray   # (s,) int32


def edge_graph(grid: ShapeGrid) -> EdgeGraph:
    """The non-degenerate edges of ``grid`` on shared vertex nodes (degenerate edges have no cells;
    their vertex is still a point)."""
    index = {v.id: k for k, v in enumerate(grid.vertices)}
    vpoints = np.array([np.reshape(v.point, 3) for v in grid.vertices], dtype=float).reshape(-1, 3)
    live = [e for e in grid.edges if not e.degenerate]
    inner = [np.reshape(np.asarray(e.points, dtype=float), (-1, 3))[1:-1] for e in live]
    counts = np.array([len(p) for p in inner], dtype=np.int64)
    starts = len(vpoints) + np.concatenate(([0], np.cumsum(counts)))
    chains = [np.concatenate(([index[e.vertices[0]]], np.arange(starts[j], starts[j + 1]), [index[e.vertices[1]]]))
              for j, e in enumerate(live)]
    edge_ids = np.array([e.id for e in live], dtype=np.int32)
    lengths = np.array([len(c) for c in chains], dtype=np.int64)
    connectivity = np.concatenate(chains).astype(np.int64) if chains else np.zeros(0, dtype=np.int64)
    segments = (np.concatenate([np.column_stack([c[:-1], c[1:]]) for c in chains]).astype(np.int64)
                if chains else np.zeros((0, 2), dtype=np.int64))
    nv = len(vpoints)
    return EdgeGraph(
        points=np.concatenate([vpoints, *inner]) if live else vpoints,
        vertex_id=np.concatenate([[v.id for v in grid.vertices], np.zeros(counts.sum())]).astype(np.int32),
        edge_id=np.concatenate([np.zeros(nv), np.repeat(edge_ids, counts)]).astype(np.int32),
        param=np.concatenate([np.full(nv, np.nan),
                              *[np.asarray(e.params, dtype=float)[1:-1] for e in live]]),
        edge_ids=edge_ids, connectivity=connectivity,
        chain_offsets=np.concatenate(([0], np.cumsum(lengths))).astype(np.int64),
        segments=segments, segment_edge=np.repeat(edge_ids, lengths - 1).astype(np.int32))


def table(columns: list[np.ndarray], *, delimiter: str = " ") -> str:
    """Rows of ``columns`` as text, one line each with a trailing newline; integer arrays print as
    integers, float arrays with ``repr`` (exact round trip; NaN as ``nan``)."""
    if not len(columns[0]):
        return ""
    text = [list(map(str, np.asarray(c).tolist())) for c in columns]
    return "\n".join(map(delimiter.join, zip(*text))) + "\n"


def comment(grid: ShapeGrid) -> str:
    """A one-line ASCII description of the grid for file headers."""
    text = f"cadedge edge grid of {grid.source} ({grid.units})"
    return " ".join(text.split()).encode("ascii", "replace").decode("ascii")


def bytes_writer(to_bytes: Callable[[ShapeGrid], bytes]) -> Callable[[ShapeGrid, Path], None]:
    """A registry writer ``(grid, path) -> None`` from a ``grid -> bytes`` function (flushed to disk)."""
    def write(grid: ShapeGrid, path: Path) -> None:
        data = to_bytes(grid)
        with open(path, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
    write.__doc__ = to_bytes.__doc__
    return write
