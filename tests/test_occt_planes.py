"""Faces that are planes whatever their surface type (cadedge.occt.planes) and how the mesher treats them."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace  # noqa: E402
from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism  # noqa: E402
from OCP.GeomAPI import GeomAPI_PointsToBSplineSurface  # noqa: E402
from OCP.gp import gp_Pnt, gp_Vec  # noqa: E402

from cadedge.mesh.fidelity import meshed_kinds, settings, surface_types  # noqa: E402
from cadedge.occt.compat import TColgp_Array2OfPnt  # noqa: E402
from cadedge.occt.planes import plane_of, planar_faces  # noqa: E402


def bspline_face(height):
    """A 9 x 9-pole B-spline face over 40 x 40 at z = height(x, y)."""
    poles = TColgp_Array2OfPnt(1, 9, 1, 9)
    for i in range(9):
        for j in range(9):
            x, y = 5.0 * i, 5.0 * j
            poles.SetValue(i + 1, j + 1, gp_Pnt(x, y, height(x, y)))
    return BRepBuilderAPI_MakeFace(GeomAPI_PointsToBSplineSurface(poles).Surface(), 1e-7).Face()


def test_a_tilted_planar_bspline_face_is_a_plane_and_a_wavy_one_is_not():
    face = bspline_face(lambda x, y: 0.5 * x - 0.25 * y + 3.0)
    origin, xdir, ydir = plane_of(face)
    normal = np.cross(xdir, ydir)
    assert abs(abs(normal @ np.array([0.5, -0.25, -1.0])) / np.linalg.norm([0.5, -0.25, -1.0]) - 1.0) < 1e-9
    assert abs(origin @ normal - np.array([0.0, 0.0, 3.0]) @ normal) < 1e-7  # the plane through (0, 0, 3)
    assert plane_of(bspline_face(lambda x, y: 0.01 * math.sin(0.3 * x))) is None


def test_a_planar_bspline_face_is_meshed_as_a_plane_but_named_by_its_type():
    """A prism on a planar B-spline face: its two B-spline caps are fitted, sized and grown as planes (not
    curved faces of the surface target), while the report keeps OCCT's type names."""
    cap = bspline_face(lambda x, y: 0.0)
    prism = BRepPrimAPI_MakePrism(cap, gp_Vec(0.0, 0.0, 10.0)).Shape()
    kinds = surface_types(prism)
    planar = planar_faces(prism)
    assert sorted(kinds[f - 1] for f in planar).count("BSplineSurface") == 2 and len(planar) == 6
    meshed = meshed_kinds(prism)
    assert meshed == ["Plane"] * 6
    assert settings(1e-3, np.ones(6), meshed)["curved_faces"] == []
