"""Edge grids of a whole B-rep shape: plain data, no OCCT.

Filled by :func:`cadedge.refine_shape` (the OCCT layer) and consumed by the exporters, the mesher and
the CLI. Ids are 1-based in ``TopExp::MapShapes`` order (docs/api.md).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .grid import Polyline, row_norms

SCHEMA = "cadedge.edgegrid/1"


@dataclass
class VertexGrid:
    """A B-rep vertex: its point and the spacing a surface mesher should use there."""

    id: int
    point: np.ndarray
    spacing: float | None = None
    tolerance: float = 0.0


@dataclass
class ShapeEdgeGrid(Polyline):
    """The grid on one B-rep edge. Degenerate edges carry their single point twice and no length."""

    id: int
    vertices: tuple[int, int]
    curve: str
    degenerate: bool
    closed: bool
    faces: list[int]
    params: np.ndarray
    points: np.ndarray
    ald_estimate: float
    evaluations: int = 0
    tolerance: float = 0.0

    @property
    def segments(self) -> int:
        """Number of segments; none on a degenerate edge."""
        return 0 if self.degenerate else super().segments

    @property
    def spacing(self) -> tuple[float, float]:
        """Lengths of the first and last segments; zero on a degenerate edge."""
        return (0.0, 0.0) if self.degenerate else super().spacing


def vertex_spacings(edges: list[ShapeEdgeGrid]) -> dict[int, float]:
    """Vertex id -> shortest end segment among the non-degenerate edges meeting there (the contract's
    ``vertices[].spacing``: the spacing a surface mesher should use at that vertex). The end segments of
    all edges are measured in one batch on their points put end to end (``ShapeEdgeGrid.spacing`` per
    edge, the same values), and the shortest at each vertex taken in one ``np.minimum.at``."""
    live = [e for e in edges if not e.degenerate and len(e.points) >= 2]
    if not live:
        return {}
    points = [e.points for e in live]
    sizes = np.array([len(p) for p in points], dtype=np.int64)
    stop = np.cumsum(sizes)
    start = stop - sizes
    flat = np.concatenate(points).astype(float, copy=False)
    # each edge's first segment (start, start + 1), then its last (stop - 2, stop - 1)
    lengths = row_norms(flat[np.column_stack([start + 1, stop - 1]).ravel()]
                        - flat[np.column_stack([start, stop - 2]).ravel()])
    ids = np.array([e.vertices for e in live], dtype=np.int64).ravel()
    shortest = np.full(int(ids.max()) + 1, np.inf)
    np.minimum.at(shortest, ids, lengths)
    ids = np.unique(ids)
    return dict(zip(ids.tolist(), shortest[ids].tolist()))


def end_tolerances(grid: "ShapeGrid") -> dict[int, float]:
    """Edge id -> how far its grid's ends may lie from its curve's ends: the larger of the edge's tolerance
    and its vertices' (a grid ends on its vertices' points; dlr_f6.brep's edge 278, tolerance 2e-7, ends
    3.4e-5 off its curve at vertices of 2e-4 and 1e-3)."""
    vertex = {v.id: v.tolerance for v in grid.vertices}
    return {e.id: max([e.tolerance] + [vertex.get(v, 0.0) for v in e.vertices]) for e in grid.edges}


def recorded_targets(grid: "ShapeGrid") -> dict[int, float]:
    """Edge id -> the arc-length deficit its grid was refined to, as the options record it: ``ald``, or
    the finest local target (``ald_for``, by edge or by face) that reaches it; inf where they name none.
    (:func:`cadedge.occt.localald.edge_targets` makes them from the settings before refining.)"""
    ald = float(grid.options.get("ald") or np.inf)
    named = {(r["kind"], int(r["id"])): float(r["ald"]) for r in grid.options.get("ald_for") or ()}
    return {e.id: min([ald, named.get(("edge", e.id), np.inf)]
                      + [named.get(("face", f), np.inf) for f in e.faces]) for e in grid.edges}


def with_edges(grid: "ShapeGrid", edges: list[ShapeEdgeGrid]) -> "ShapeGrid":
    """A new ``grid`` holding ``edges`` instead of its own, its vertex spacings measured on them."""
    spacing = vertex_spacings(edges)
    vertices = [replace(v, spacing=spacing.get(v.id, v.spacing)) for v in grid.vertices]
    return replace(grid, edges=edges, vertices=vertices)


@dataclass
class ShapeGrid:
    """Edge grids of every edge of a shape, with vertices, adjacency, units and options.

    ``shape`` keeps the OCCT ``TopoDS_Shape`` the grids were made from (for the mesher) and ``curves``
    the edges' curves by edge id (evaluators with ``evaluate(u)``, built once by ``refine_shape``, for
    splitting the grids later); neither is exported. ``write(path)`` picks the format from the suffix (see :mod:`cadedge.exporters`).
    """

    source: str
    units: str
    options: dict[str, Any]
    vertices: list[VertexGrid]
    edges: list[ShapeEdgeGrid]
    faces: int = 0
    seconds: float = 0.0
    warnings: list[str] = field(default_factory=list)
    shape: Any = field(default=None, repr=False, compare=False)
    curves: Any = field(default=None, repr=False, compare=False)

    @property
    def segments(self) -> int:
        return sum(e.segments for e in self.edges)

    @property
    def max_ald_estimate(self) -> float:
        vals = [e.ald_estimate for e in self.edges if not e.degenerate]
        return float(max(vals)) if vals else 0.0

    def summary(self) -> dict[str, Any]:
        """The ``summary`` block of the JSON schema."""
        return {"edges": len(self.edges), "segments": self.segments,
                "max_ald_estimate": self.max_ald_estimate, "seconds": self.seconds}

    def write(self, path: str | os.PathLike, *, format: str | None = None) -> None:
        """Write atomically; ``format`` (a suffix such as ``"json"``) overrides the path's suffix."""
        from .exporters import write
        write(self, path, format=format)

    def __repr__(self) -> str:
        return (f"ShapeGrid(source={self.source!r}, edges={len(self.edges)}, vertices={len(self.vertices)}, "
                f"segments={self.segments}, max_ald_estimate={self.max_ald_estimate:.3g})")
