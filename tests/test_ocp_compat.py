"""cadedge on the installed OCP line (7.9 or 8.0): the compat names work, and no module uses one that is gone.

The static check reads every module of cadedge/ and scripts/, so an OCP name imported lazily inside a
function, which the other tests may never reach, still fails here on the line that lacks it.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

pytest.importorskip("OCP")

from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder  # noqa: E402
from OCP.Geom import Geom_BSplineCurve  # noqa: E402
from OCP.gp import gp_Pnt  # noqa: E402
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX  # noqa: E402
from OCP.TopExp import TopExp  # noqa: E402

from cadedge.occt import compat  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
STATIC = re.compile(r"\b([A-Z][A-Za-z0-9]*(?:_[A-Za-z0-9]+)*)\.([A-Za-z0-9]+_s)\b")


def _ocp_modules() -> list[Path]:
    """Every module of cadedge/ and scripts/ that mentions OCP, compat.py aside."""
    return [p for folder in ("cadedge", "scripts") for p in sorted((ROOT / folder).rglob("*.py"))
            if p.name != "compat.py" and "OCP" in p.read_text(encoding="utf-8")]


def test_compat_collections_and_casts():
    box = BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape()
    edges, vertices = compat.TopTools_IndexedMapOfShape(), compat.TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(box, TopAbs_EDGE, edges)
    TopExp.MapShapes_s(box, TopAbs_VERTEX, vertices)
    assert (edges.Extent(), vertices.Extent()) == (12, 8)
    faces_of = compat.TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(box, TopAbs_EDGE, TopAbs_FACE, faces_of)
    assert all(faces_of.FindFromIndex(i).Size() == 2 for i in range(1, 13))
    edge = compat.TopoDS.Edge_s(edges.FindKey(1))
    assert edge.ShapeType() == TopAbs_EDGE and not compat.TopoDS.Vertex_s(vertices.FindKey(1)).IsNull()
    assert compat.TopoDS.Face_s(faces_of.FindFromIndex(1).First()).ShapeType() == TopAbs_FACE
    assert compat.TopTools_ListOfShape().Size() == 0 and compat.TColStd_SequenceOfAsciiString().Size() == 0


def test_occt_errors_hold_the_occt_exceptions_ocp_binds_apart():
    """OCP binds each OCCT exception as its own subclass of Exception (a Standard_NumericError is no
    Standard_Failure in Python); ``OCCT_ERRORS`` holds them all, and a failure OCCT raises is caught."""
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.Standard import Standard_Failure, Standard_NumericError, Standard_OutOfRange
    from OCP.StdFail import StdFail_NotDone

    assert not issubclass(Standard_NumericError, Standard_Failure)
    assert {Standard_Failure, Standard_NumericError, Standard_OutOfRange, StdFail_NotDone} <= set(compat.OCCT_ERRORS)
    assert all(issubclass(c, Exception) and c.__module__.startswith("OCP") for c in compat.OCCT_ERRORS)
    with pytest.raises(compat.OCCT_ERRORS):
        BRepMesh_IncrementalMesh(BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape(), 0.0, False, 0.5, False)


def test_no_module_catches_standard_failure_alone():
    """``except Standard_Failure`` misses the other OCCT exceptions (see above): ``OCCT_ERRORS`` instead."""
    bad = [f"{p.relative_to(ROOT)}:{i}" for p in _ocp_modules()
           for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), start=1)
           if re.search(r"except\b.*\bStandard_Failure\b", line)]
    assert not bad


def test_compat_arrays_build_a_bspline():
    poles = compat.TColgp_Array1OfPnt(1, 3)
    for i, (x, y) in enumerate([(0.0, 0.0), (1.0, 2.0), (2.0, 0.0)], start=1):
        poles.SetValue(i, gp_Pnt(x, y, 0.0))
    knots, mults = compat.TColStd_Array1OfReal(1, 2), compat.TColStd_Array1OfInteger(1, 2)
    for i, (k, m) in enumerate([(0.0, 3), (1.0, 3)], start=1):
        knots.SetValue(i, k)
        mults.SetValue(i, m)
    curve = Geom_BSplineCurve(poles, knots, mults, 2)
    assert curve.Value(0.5).Y() == pytest.approx(1.0)


def test_cylinder_edges_cast_both_ways():
    cyl = BRepPrimAPI_MakeCylinder(1.0, 2.0).Shape()
    m = compat.TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(cyl, TopAbs_EDGE, m)
    assert m.Extent() == 3 and all(not compat.TopoDS.Edge_s(m.FindKey(i)).IsNull() for i in range(1, 4))


@pytest.mark.parametrize("path", _ocp_modules(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_ocp_name_exists_on_this_ocp(path):
    """Imports from OCP name classes this OCP has, static methods exist, casts go through compat."""
    import importlib

    text = path.read_text(encoding="utf-8")
    missing = []
    imported: dict[str, object] = {}
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("OCP"):
            module = importlib.import_module(node.module)
            for alias in node.names:
                if not hasattr(module, alias.name):
                    missing.append(f"{node.module}.{alias.name}")
                elif alias.name == "TopoDS" and node.module == "OCP.TopoDS":
                    missing.append("OCP.TopoDS.TopoDS (use cadedge.occt.compat.TopoDS: OCP 8.0 drops the _s casts)")
                else:
                    imported[alias.asname or alias.name] = getattr(module, alias.name)
    for cls, method in sorted(set(STATIC.findall(text))):
        if cls in imported and not hasattr(imported[cls], method):
            missing.append(f"{cls}.{method}")
    assert not missing, (f"{path.name}: {', '.join(missing)}: missing on this OCP line or not portable; "
                         "take it from cadedge/occt/compat.py (add it there)")
