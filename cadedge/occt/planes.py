"""Faces that are planes, whatever their surface type: a B-spline or an extrusion can be exactly flat.

mesh_T106_V3's two end walls are planar B-spline surfaces and its two side strips extrusions of straight
lines; 917_fusee has 104 planar B-spline faces. Meshed as curved faces they were sized by curvature and
refined against their area, where a plane's triangles cover exactly its boundary polygon. A face is
planar when OCCT's ``GeomLib_IsPlanarSurface`` finds its surface within :data:`PLANAR_TOL` of one plane
(for B-splines and Beziers: every pole).
"""

from __future__ import annotations

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.GeomAbs import GeomAbs_Plane
from OCP.GeomLib import GeomLib_IsPlanarSurface
from .compat import OCCT_ERRORS
from OCP.TopoDS import TopoDS_Face, TopoDS_Shape

from .topology import Topology

#: Largest distance from the plane (model units, OCCT's ``Precision::Confusion``): flat as OCCT's own
#: geometric equality, so the area a plane's triangles cover is the face's area.
PLANAR_TOL = 1e-7

#: A plane as (origin, x direction, y direction), each a (3,) array.
Frame = tuple[np.ndarray, np.ndarray, np.ndarray]


def plane_of(face: TopoDS_Face) -> Frame | None:
    """The plane ``face`` lies in, or None if it is not planar (or its surface cannot be read)."""
    try:
        surface = BRepAdaptor_Surface(face)
        if surface.GetType() == GeomAbs_Plane:
            position = surface.Plane().Position()
        else:
            test = GeomLib_IsPlanarSurface(BRep_Tool.Surface_s(face), PLANAR_TOL)
            if not test.IsPlanar():
                return None
            position = test.Plan().Position()
    except OCCT_ERRORS:
        return None
    return (np.array(position.Location().Coord()), np.array(position.XDirection().Coord()),
            np.array(position.YDirection().Coord()))


def planar_faces(shape: TopoDS_Shape) -> list[int]:
    """Ids (``TopExp::MapShapes`` order, 1-based) of the faces of ``shape`` that are planar."""
    return [i for i, face in enumerate(Topology(shape).faces, start=1) if plane_of(face) is not None]
