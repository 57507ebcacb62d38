"""An OCCT edge as a cadedge black-box curve: parameter in, 3-D point out, nothing else.

Evaluation goes through ``BRepAdaptor_Curve``, which also handles edges that carry only curves on
surfaces (no 3-D curve) and applies the edge's location. The per-point loop lives in one method,
:meth:`EdgeCurve.evaluate`, so a batched evaluator can replace it without touching the refiners.
"""

from __future__ import annotations

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.Standard import Standard_Failure
from OCP.TopoDS import TopoDS_Edge

from ..errors import GeometryError
from .topology import forward


class EdgeCurve:
    """Edge ``edge`` in its FORWARD orientation: ``domain`` runs from its first vertex to its last.

    ``edge_id`` only names the edge in error messages. OCCT failures raise :class:`GeometryError`.
    """

    def __init__(self, edge: TopoDS_Edge, edge_id: int | None = None):
        self.edge = forward(edge)
        self.edge_id = edge_id
        try:
            self.adaptor = BRepAdaptor_Curve(self.edge)
            self.domain = (float(self.adaptor.FirstParameter()), float(self.adaptor.LastParameter()))
        except Standard_Failure as exc:
            raise GeometryError(f"{self._name()}: OCCT cannot adapt its curve: {exc}") from exc

    def _name(self) -> str:
        return f"edge {self.edge_id}" if self.edge_id is not None else "edge"

    def evaluate(self, u: np.ndarray) -> np.ndarray:
        """Points at parameters ``u`` (1-D), shape (len(u), 3)."""
        u = np.asarray(u, dtype=float).ravel()
        out = np.empty((len(u), 3))
        value = self.adaptor.Value
        try:
            for k, uk in enumerate(u.tolist()):
                out[k] = value(uk).Coord()
        except Standard_Failure as exc:
            raise GeometryError(f"{self._name()}: OCCT failed to evaluate u={uk!r}: {exc}") from exc
        return out

    def __repr__(self) -> str:
        return f"EdgeCurve({self._name()}, domain={self.domain})"
