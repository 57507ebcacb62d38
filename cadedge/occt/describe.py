"""What ``cadedge info`` reports about a shape: per-edge curve type, flags, faces, tolerance and true
length, without refining anything.

Lengths are OCCT's (``GCPnts_AbscissaPoint::Length`` on the edge's ``BRepAdaptor_Curve``, i.e.
Gauss integration to its default tolerance), so they are the reference the ALD is measured against.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.GCPnts import GCPnts_AbscissaPoint
from .compat import OCCT_ERRORS
from OCP.TopAbs import TopAbs_SHELL, TopAbs_SOLID

from ..errors import GeometryError
from .loading import count as _count
from .reader import load_shape
from .topology import Topology, curve_type_name


@dataclass
class EdgeDescription:
    """One edge as ``cadedge info`` lists it (ids as in the JSON output)."""

    id: int
    curve: str
    degenerate: bool
    closed: bool
    seam: bool
    vertices: tuple[int, int]
    faces: list[int]
    tolerance: float
    length: float


@dataclass
class ShapeDescription:
    """Counts and per-edge facts of a shape."""

    source: str
    units: str
    edges: list[EdgeDescription]
    vertices: int
    faces: int
    shells: int
    solids: int
    warnings: list[str] = field(default_factory=list)

    @property
    def curve_types(self) -> Counter[str]:
        """Edges per curve type; degenerate edges counted as "(degenerate)"."""
        return Counter("(degenerate)" if e.degenerate else e.curve for e in self.edges)

    @property
    def max_tolerance(self) -> float:
        return max((e.tolerance for e in self.edges), default=0.0)


def describe_edge(topology: Topology, i: int) -> EdgeDescription:
    """Edge ``i`` (0-based) as ``cadedge info`` lists it, from one adaptor: its curve type and OCCT's
    length (0 for a degenerate edge)."""
    edge = topology.edges[i]
    try:
        adaptor = BRepAdaptor_Curve(edge)
        kind = curve_type_name(adaptor.GetType())
    except OCCT_ERRORS as exc:
        raise GeometryError(f"edge {i + 1}: OCCT cannot adapt its curve: {exc}") from exc
    degenerate = topology.is_degenerate(i)
    try:
        length = 0.0 if degenerate else float(GCPnts_AbscissaPoint.Length_s(adaptor))
    except OCCT_ERRORS as exc:
        raise GeometryError(f"edge {i + 1}: OCCT cannot measure its length: {exc}") from exc
    return EdgeDescription(id=i + 1, curve=kind, degenerate=degenerate, closed=topology.is_closed(i),
                           seam=topology.is_seam(i), vertices=topology.edge_vertices[i],
                           faces=list(topology.edge_faces[i]), tolerance=float(BRep_Tool.Tolerance_s(edge)),
                           length=length)


def describe_shape(source: Any, *, allow_partial: bool = False) -> ShapeDescription:
    """Load ``source`` (anything :func:`cadedge.occt.reader.load_shape` accepts, with ``allow_partial``)
    and describe its edges."""
    loaded = load_shape(source, allow_partial=allow_partial)
    topo = Topology(loaded.shape, dump=False)  # (the dump would import numpy: start-up)
    edges = [describe_edge(topo, i) for i in range(len(topo.edges))]
    return ShapeDescription(source=loaded.source, units=loaded.units, edges=edges, vertices=len(topo.vertices),
                            faces=len(topo.faces), shells=_count(loaded.shape, TopAbs_SHELL),
                            solids=_count(loaded.shape, TopAbs_SOLID), warnings=list(loaded.warnings))
