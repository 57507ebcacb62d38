"""Cone faces that close at their apex: where each lies, and how narrow it is.

A cone unrolls into a circular sector of angle ``2 pi sin(a)`` (``a`` the half-angle); near the apex a
narrow cone is a sliver of a sector, and the boundary segments along it must shrink with the distance
from the apex (:mod:`cadedge.mesh.apex`). Only faces whose surface is an OCCT cone and that have a
B-rep vertex at the apex (within the vertex's tolerance, or :data:`APEX_TOL` of the cone's size) are
listed.
"""

from __future__ import annotations

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.GeomAbs import GeomAbs_Cone
from OCP.TopAbs import TopAbs_VERTEX
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS_Shape

from .compat import OCCT_ERRORS, TopoDS
from .topology import Topology

#: A vertex this close to a cone's apex, as a share of the apex's distance from the cone's reference
#: circle, is at the apex (as in :data:`cadedge.mesh.developed.APEX_TOL`).
APEX_TOL = 1e-7


def apex_cones(shape: TopoDS_Shape, faces: list[int] | None = None) -> dict[int, tuple[np.ndarray, float]]:
    """Face id (``TopExp::MapShapes`` order, 1-based) -> (apex point (3,), sine of the half-angle) for the
    cone faces of ``shape`` with a vertex at their apex, among ``faces`` (ids; default every face: a
    caller that knows the surface types passes its cones, and none is looked at when it has none)."""
    if faces is not None and not faces:
        return {}
    out = {}
    all_faces = Topology(shape).faces
    for i in (range(1, len(all_faces) + 1) if faces is None else faces):
        face = all_faces[i - 1]
        try:
            surface = BRepAdaptor_Surface(face)
            if surface.GetType() != GeomAbs_Cone:
                continue
            cone = surface.Cone()
            apex = cone.Apex()
            sine = abs(float(np.sin(cone.SemiAngle())))
            near = APEX_TOL * apex.Distance(cone.Location())
            explorer = TopExp_Explorer(face, TopAbs_VERTEX)
            while explorer.More():
                vertex = TopoDS.Vertex_s(explorer.Current())
                if BRep_Tool.Pnt_s(vertex).Distance(apex) <= max(BRep_Tool.Tolerance_s(vertex), near):
                    out[i] = (np.array(apex.Coord()), sine)
                    break
                explorer.Next()
        except OCCT_ERRORS:
            continue
    return out
