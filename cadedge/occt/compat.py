"""The OCP names that differ between the OCP 7.9 and 8.0 lines, under their 7.9 names.

OCP 8.0 (OpenCASCADE 8.0: build123d 0.13) no longer binds OCCT's typedef'd collection classes
(``TopTools_IndexedMapOfShape``, ``TColStd_Array1OfReal``, ...); the same template instances are in
``OCP.collections`` under their template names. OCP 7.9 (cadquery 2.8, build123d 0.12) has only the
typedef names. OCP 8.0 also binds ``TopoDS`` (the down-casts) as a namespace whose functions lose the
``_s`` of static methods: ``TopoDS.Edge`` where 7.9 has ``TopoDS.Edge_s``; :data:`TopoDS` here answers
to the 7.9 spelling on both lines. Every other OCP class and method cadedge uses is the same on both.

Also :data:`OCCT_ERRORS`, the OCCT exceptions as OCP binds them on both lines: each its own class.
"""

from __future__ import annotations

try:  # OCP 8.0
    from OCP.collections import Array1_double as TColStd_Array1OfReal
    from OCP.collections import Array2_double as TColStd_Array2OfReal
    from OCP.collections import Array1_gp_Pnt as TColgp_Array1OfPnt
    from OCP.collections import Array2_gp_Pnt as TColgp_Array2OfPnt
    from OCP.collections import HArray1_gp_Pnt as TColgp_HArray1OfPnt
    from OCP.collections import Array1_int as TColStd_Array1OfInteger
    from OCP.collections import \
        IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as \
        TopTools_IndexedDataMapOfShapeListOfShape
    from OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as TopTools_IndexedMapOfShape
    from OCP.collections import List_TopoDS_Shape as TopTools_ListOfShape
    from OCP.collections import Sequence_TCollection_AsciiString as TColStd_SequenceOfAsciiString
    from OCP.collections import Sequence_TDF_Label as TDF_LabelSequence
except ImportError:  # OCP 7.9
    from OCP.TColgp import TColgp_Array1OfPnt, TColgp_Array2OfPnt
    from OCP.TColgp import TColgp_HArray1OfPnt
    from OCP.TDF import TDF_LabelSequence
    from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal, TColStd_Array2OfReal
    from OCP.TColStd import TColStd_SequenceOfAsciiString
    from OCP.TopTools import (TopTools_IndexedDataMapOfShapeListOfShape, TopTools_IndexedMapOfShape,
                              TopTools_ListOfShape)

from OCP import TopoDS as _topods_module


class _TopoDSNamespace:
    """``TopoDS.Edge_s(shape)`` and the other down-casts on OCP 8.0, where they are ``TopoDS.Edge(shape)``."""

    def __getattr__(self, name: str):
        if name.endswith("_s"):
            return getattr(_topods_module.TopoDS, name[:-2])
        raise AttributeError(name)


TopoDS = _topods_module.TopoDS if hasattr(_topods_module.TopoDS, "Edge_s") else _TopoDSNamespace()


def _occt_errors() -> tuple[type[Exception], ...]:
    """Every OCCT exception class OCP binds, found in its modules (``OCP.OCP``'s on both lines).

    OCP binds each OCCT exception as its own subclass of Python's ``Exception``: ``Standard_NumericError``
    is a ``Standard_Failure`` in C++ but not in Python, and ``except Standard_Failure`` let it through.
    SparkFun's FlexyPin STEP file has a face whose area check gave ``BRepMesh_IncrementalMesh`` a
    deflection it refused (``Standard_NumericError``): ``cadedge mesh`` stopped with an internal error."""
    import types

    import OCP
    from OCP.Standard import Standard_Failure

    found = {Standard_Failure}
    for root in {OCP, getattr(OCP, "OCP", OCP)}:
        for name in dir(root):
            module = getattr(root, name, None)
            if isinstance(module, types.ModuleType) and module.__name__.startswith("OCP"):
                found.update(v for v in vars(module).values()
                             if isinstance(v, type) and issubclass(v, Exception) and v.__module__.startswith("OCP"))
    return tuple(sorted(found, key=lambda c: c.__name__))


#: Every OCCT exception OCP raises (see :func:`_occt_errors`): ``except OCCT_ERRORS`` where OCCT may fail.
OCCT_ERRORS = _occt_errors()

__all__ = ["OCCT_ERRORS", "TopoDS", "TColStd_Array1OfInteger", "TColStd_Array1OfReal", "TColStd_Array2OfReal",
           "TColStd_SequenceOfAsciiString", "TColgp_Array1OfPnt", "TColgp_Array2OfPnt", "TColgp_HArray1OfPnt",
           "TDF_LabelSequence", "TopTools_IndexedDataMapOfShapeListOfShape", "TopTools_IndexedMapOfShape",
           "TopTools_ListOfShape"]
