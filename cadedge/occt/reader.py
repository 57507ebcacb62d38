"""Load a B-rep shape from a STEP, IGES or OCCT BREP file or an in-memory cadquery / build123d / OCP shape.

:func:`load_shape` returns a :class:`LoadedShape`: the ``TopoDS_Shape``, a name for it, its length
unit and the warnings worth passing on (the reader's check messages and suspiciously loose
tolerances). Bad input raises :class:`~cadedge.errors.InputError` with one line naming the file (the
path as given) and the reason; so does a file that OCCT transfers only in part, unless
``allow_partial`` is true (see :mod:`cadedge.occt.loading`). The formats' own readers are
:mod:`cadedge.occt.step`, :mod:`cadedge.occt.iges` and :mod:`cadedge.occt.brep`.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from OCP.Bnd import Bnd_Box
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepBndLib import BRepBndLib
from OCP.TopAbs import TopAbs_EDGE, TopAbs_VERTEX
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS_Compound, TopoDS_Shape

from ..errors import InputError
from ..formats import INPUT_FORMATS
from .compat import TopoDS, TopTools_IndexedMapOfShape
from .loading import LoadedShape, quiet_occt

if TYPE_CHECKING:  # (shapedump needs numpy, which ``cadedge info`` does not import)
    from .shapedump import ShapeDump

__all__ = ["LoadedShape", "load_shape", "quiet_occt", "tolerance_warnings", "SUFFIXES"]

#: File suffixes (lower case) and the format they are read as (:data:`cadedge.formats.INPUT_FORMATS`).
SUFFIXES = INPUT_FORMATS
#: Warn when the worst edge tolerance exceeds this fraction of the model's bounding-box diagonal ...
TOL_REL_MODEL = 5e-4
#: ... or exceeds this many times the uncertainty the STEP file declares (and this fraction of the diagonal).
TOL_REL_DECLARED, TOL_REL_DECLARED_MODEL = 10.0, 1e-5


def tolerance_warnings(shape: TopoDS_Shape, units: str, declared: float | None = None,
                       dump: ShapeDump | None = None) -> list[str]:
    """One warning if the worst edge tolerance is large for the model's size or its declared precision.

    A large edge tolerance means vertices and pcurves may lie far off the 3-D curves (healed or
    badly exported models): the grids are still made, but downstream meshes may not close up.
    ``dump``, the shape read in one call (:mod:`cadedge.occt.shapedump`), gives the tolerances and vertex
    points without an OCP call each.
    """
    if dump is not None and len(dump.edge_tolerance):
        worst = float(dump.edge_tolerance.max())  # BRep_Tool::MaxTolerance: the same numbers, the same max
        lower = _diagonal_from_dump(dump, worst)
    else:
        worst = BRep_Tool.MaxTolerance_s(shape, TopAbs_EDGE)
        lower = _diagonal_at_least(shape, worst)
    file_test = declared is not None and worst > TOL_REL_DECLARED * declared
    if worst <= (TOL_REL_DECLARED_MODEL if file_test else TOL_REL_MODEL) * lower:
        return []  # neither test below can fire: skip the bounding box (OCCT boxes every face's surface)
    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box, False)
    if box.IsVoid():
        return []
    diag = box.SquareExtent() ** 0.5  # not box.Get(): OCP 8.0 cannot return its Limits struct
    too_big_for_model = diag > 0 and worst > TOL_REL_MODEL * diag
    too_big_for_file = file_test and worst > TOL_REL_DECLARED_MODEL * diag
    if not (too_big_for_model or too_big_for_file):
        return []
    if dump is not None and len(dump.edge_tolerance):
        worst_id = int(dump.edge_tolerance.argmax()) + 1  # the first of MapShapes order, as below
    else:
        edges = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(shape, TopAbs_EDGE, edges)
        worst_id = next(i for i in range(1, edges.Extent() + 1)
                        if BRep_Tool.Tolerance_s(TopoDS.Edge_s(edges.FindKey(i))) == worst)
    decl = f", declared uncertainty {declared:.3g} {units}" if declared is not None else ""
    return [f"loose tolerance: edge {worst_id} has tolerance {worst:.3g} {units}, {worst / diag:.2g} of the "
            f"model size {diag:.4g} {units}{decl}; vertices may lie off their curves"]


def _diagonal_at_least(shape: TopoDS_Shape, worst: float, samples: int = 32) -> float:
    """A lower bound on the diagonal of ``BRepBndLib``'s box of ``shape``, from ``samples`` of its vertices.

    A vertex lies within its tolerance of its edges' ends, which lie within the edge tolerance (at most
    ``worst``) of the faces' surfaces that the box contains: so the vertices' own box, shrunk by those
    tolerances, lies inside it.
    """
    vertices = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_VERTEX, vertices)
    n = vertices.Extent()
    if n == 0:
        return 0.0
    lo, hi, slack = [math.inf] * 3, [-math.inf] * 3, 0.0
    for i in sorted({1 + (k * (n - 1)) // max(samples - 1, 1) for k in range(min(samples, n))}):
        v = TopoDS.Vertex_s(vertices.FindKey(i))
        p = BRep_Tool.Pnt_s(v).Coord()
        lo = [min(a, b) for a, b in zip(lo, p)]
        hi = [max(a, b) for a, b in zip(hi, p)]
        slack = max(slack, BRep_Tool.Tolerance_s(v))
    diag = math.dist(lo, hi)
    return max(diag - 2 * math.sqrt(3) * (slack + worst), 0.0)


def _diagonal_from_dump(dump: ShapeDump, worst: float) -> float:
    """:func:`_diagonal_at_least` from every vertex of the dump (a tighter bound, and no OCP call)."""
    points = dump.vertex_points
    if not len(points):
        return 0.0
    diag = math.dist(points.min(axis=0).tolist(), points.max(axis=0).tolist())
    return max(diag - 2 * math.sqrt(3) * (float(dump.vertex_tolerance.max()) + worst), 0.0)


def _compound(shapes: list[TopoDS_Shape]) -> TopoDS_Shape:
    if len(shapes) == 1:
        return shapes[0]
    comp = TopoDS_Compound()
    builder = BRep_Builder()
    builder.MakeCompound(comp)
    for s in shapes:
        builder.Add(comp, s)
    return comp


def _from_object(source: Any) -> LoadedShape:
    """A cadquery Workplane/Shape, a build123d shape or a raw TopoDS_Shape."""
    kind = type(source).__name__
    if isinstance(source, TopoDS_Shape):
        shape, desc = source, "<TopoDS_Shape>"
    elif hasattr(source, "vals") and callable(source.vals):  # cadquery Workplane
        shapes = [v.wrapped for v in source.vals() if isinstance(getattr(v, "wrapped", None), TopoDS_Shape)]
        if not shapes:
            raise InputError("<cadquery Workplane>: empty shape (the Workplane holds no shapes)")
        shape, desc = _compound(shapes), "<cadquery Workplane>"
    elif type(source).__module__.split(".")[0] == "build123d" and hasattr(source, "_wrapped"):
        # an empty build123d Compound()/Part() wraps None, and its ``wrapped`` property asserts on that
        shape, desc = source._wrapped, f"<build123d {kind}>"
        if not isinstance(shape, TopoDS_Shape):
            raise InputError(f"{desc}: empty shape (it holds no OCCT shape)")
    elif isinstance(getattr(source, "wrapped", None), TopoDS_Shape):
        shape, desc = source.wrapped, f"<{type(source).__module__.split('.')[0]} {kind}>"
    else:
        raise InputError(f"cannot refine a {kind}: expected a STEP, IGES or BREP file path, a cadquery "
                         "Workplane/Shape, a build123d shape or a TopoDS_Shape")
    if shape.IsNull() or not TopExp_Explorer(shape, TopAbs_EDGE).More():  # (no map of every edge)
        raise InputError(f"{desc}: empty shape (no edges)")
    return LoadedShape(shape=shape, source=desc, units="mm")


def load_shape(source: Any, *, allow_partial: bool = False, tolerance_scan: bool = True) -> LoadedShape:
    """Load ``source``: a STEP (.step/.stp), IGES (.igs/.iges) or OCCT BREP (.brep) path (str or
    PathLike, suffix in any case), or an in-memory shape.

    Files are transferred with OCCT's defaults, which convert lengths to millimetres (``units``
    reports the unit after transfer); BREP files and in-memory shapes carry no unit and are taken as
    millimetres. A file that OCCT transfers only in part raises :class:`InputError` unless
    ``allow_partial``, which keeps what did transfer and says what was lost in ``warnings``. With
    ``tolerance_scan`` the warnings end with :func:`tolerance_warnings`' (a caller that reads the shape in one
    call anyway, as ``refine_shape`` does, scans it from that read instead).
    """
    loaded = _load(source, allow_partial)
    if tolerance_scan:
        loaded.warnings += tolerance_warnings(loaded.shape, loaded.units, loaded.declared)
    return loaded


def _load(source: Any, allow_partial: bool) -> LoadedShape:
    if not isinstance(source, (str, os.PathLike)):
        return _from_object(source)
    given = os.fspath(source)
    if isinstance(given, bytes):
        given = os.fsdecode(given)
    path = Path(given)
    kind = SUFFIXES.get(path.suffix.lower())
    if kind is None:
        if not path.exists():
            raise InputError(f"{given}: no such file")
        if not path.is_file():
            raise InputError(f"{given}: not a file")
        *others, last = SUFFIXES
        raise InputError(f"{given}: unsupported file type {path.suffix or '(none)'!r}; expected "
                         f"{', '.join(others)} or {last}")
    if kind == "STEP":
        from .step import read_step
        return read_step(path, given, allow_partial=allow_partial)
    if kind == "IGES":
        from .iges import read_iges
        return read_iges(path, given, allow_partial=allow_partial)
    from .brep import read_brep
    return read_brep(path, given, allow_partial=allow_partial)
