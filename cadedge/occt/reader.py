"""Load a B-rep shape from a STEP file or an in-memory cadquery / build123d / OCP shape.

:func:`load_shape` returns a :class:`LoadedShape`: the ``TopoDS_Shape``, a name for it, its length
unit and the warnings worth passing on (the STEP reader's check messages and suspiciously loose
tolerances). Bad input raises :class:`~cadedge.errors.InputError` with one line naming the file and
the reason. The STEP file is checked in Python before OCCT sees it, because OCCT's parser may crash
the process on some garbage and prints its own complaints to stdout (silenced here).
"""

from __future__ import annotations

import os
import threading
from collections import Counter
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

from OCP.Bnd import Bnd_Box
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepBndLib import BRepBndLib
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_CheckIterator
from OCP.Message import Message
from OCP.StepBasic import StepBasic_UncertaintyMeasureWithUnit
from OCP.Standard import Standard_Failure
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_EDGE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS_Compound, TopoDS_Shape

from ..errors import GeometryError, InputError
from .compat import TColStd_SequenceOfAsciiString, TopoDS, TopTools_IndexedMapOfShape

STEP_SUFFIXES = (".step", ".stp")
#: Millimetres per unit for the length unit names STEP files declare (lower-cased).
MM_PER_UNIT = {"millimetre": 1.0, "millimeter": 1.0, "mm": 1.0, "centimetre": 10.0, "centimeter": 10.0,
               "cm": 10.0, "metre": 1000.0, "meter": 1000.0, "m": 1000.0, "inch": 25.4, "in": 25.4,
               "foot": 304.8, "ft": 304.8, "micrometre": 1e-3, "micron": 1e-3, "kilometre": 1e6}
UNIT_NAMES = {1.0: "mm", 10.0: "cm", 1000.0: "m", 25.4: "inch", 304.8: "ft", 1e-3: "um"}
#: Warn when the worst edge tolerance exceeds this fraction of the model's bounding-box diagonal ...
TOL_REL_MODEL = 5e-4
#: ... or exceeds this many times the uncertainty the STEP file declares.
TOL_REL_DECLARED = 10.0
_READ_STATUS = {"RetVoid": "nothing to read", "RetError": "cannot open or unknown format",
                "RetFail": "syntax error", "RetStop": "reading stopped"}
_HEAD_BYTES = 4096
_TAIL_BYTES = 4096
_occt_output = threading.Lock()
_quiet_depth = 0
_saved_printers: list[Any] = []


@dataclass
class LoadedShape:
    """A shape ready for refinement: ``units`` is its length unit, ``warnings`` one line each."""

    shape: TopoDS_Shape
    source: str
    units: str = "mm"
    warnings: list[str] = field(default_factory=list)


@contextmanager
def quiet_occt() -> Iterator[None]:
    """Detach OCCT's default message printers (its console output) for the duration of the block.

    Reference-counted, so concurrent readers in threads do not serialise or restore too early.
    """
    global _quiet_depth, _saved_printers
    with _occt_output:
        if _quiet_depth == 0:
            messenger = Message.DefaultMessenger_s()
            printers = messenger.Printers()
            _saved_printers = [printers.Value(i) for i in range(1, printers.Size() + 1)]
            for p in _saved_printers:
                messenger.RemovePrinter(p)
        _quiet_depth += 1
    try:
        yield
    finally:
        with _occt_output:
            _quiet_depth -= 1
            if _quiet_depth == 0:
                messenger = Message.DefaultMessenger_s()
                for p in _saved_printers:
                    messenger.AddPrinter(p)
                _saved_printers = []


def _check_messages(checks: Interface_CheckIterator, stage: str) -> list[str]:
    """Fail and warning messages of an OCCT check list, counted and one line each."""
    counts: Counter[str] = Counter()
    checks.Start()
    while checks.More():
        ch = checks.Value()
        for i in range(1, ch.NbFails() + 1):
            counts[f"fail: {ch.CFail(i)}"] += 1
        for i in range(1, ch.NbWarnings() + 1):
            counts[f"warning: {ch.CWarning(i)}"] += 1
        checks.Next()
    return [f"STEP {stage} {msg}" + (f" (x{n})" if n > 1 else "") for msg, n in counts.items()]


def _sniff_step(path: Path) -> None:
    """Raise InputError unless ``path`` looks like a complete ISO 10303-21 file."""
    name = path.name
    if not path.exists():
        raise InputError(f"{name}: no such file")
    if not path.is_file():
        raise InputError(f"{name}: not a file")
    if path.suffix.lower() not in STEP_SUFFIXES:
        raise InputError(f"{name}: unsupported file type {path.suffix or '(none)'!r}; expected .step or .stp")
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            head = fh.read(_HEAD_BYTES)
            fh.seek(max(0, size - _TAIL_BYTES))
            tail = fh.read()
    except OSError as exc:
        raise InputError(f"{name}: cannot read: {exc.strerror or exc}") from None
    if size == 0:
        raise InputError(f"{name}: empty file")
    if not head.lstrip(b"\xef\xbb\xbf \t\r\n").upper().startswith(b"ISO-10303-21"):
        raise InputError(f"{name}: not a STEP file (no ISO-10303-21 header)")
    if b"END-ISO-10303-21" not in tail.upper():
        raise InputError(f"{name}: truncated or corrupt STEP file (no END-ISO-10303-21 trailer)")


def _file_unit_mm(reader: STEPControl_Reader) -> float | None:
    """Millimetres per length unit the STEP file declares (None if unknown)."""
    lengths, angles, solids = (TColStd_SequenceOfAsciiString() for _ in range(3))
    reader.FileUnits(lengths, angles, solids)
    if lengths.Length() == 0:
        return None
    return MM_PER_UNIT.get(lengths.Value(1).ToCString().strip().lower())


def _declared_uncertainty(reader: STEPControl_Reader) -> float | None:
    """The smallest length uncertainty the STEP file declares, in the file's unit."""
    model = reader.StepModel()
    vals = []
    for i in range(1, model.NbEntities() + 1):
        ent = model.Value(i)
        if isinstance(ent, StepBasic_UncertaintyMeasureWithUnit):
            vals.append(ent.ValueComponent())
    vals = [v for v in vals if v > 0]
    return min(vals) if vals else None


def _read_step(path: Path) -> LoadedShape:
    _sniff_step(path)
    name = path.name
    reader = STEPControl_Reader()
    with quiet_occt():
        status = reader.ReadFile(str(path))
        if status != IFSelect_RetDone:
            reason = _READ_STATUS.get(str(status).split("_")[-1], str(status))
            raise InputError(f"{name}: truncated or corrupt STEP file (OCCT: {reason})")
        warnings = _check_messages(reader.WS().ModelCheckList(), "load")
        if reader.NbRootsForTransfer() == 0:
            raise InputError(f"{name}: empty STEP file (no shape to transfer)")
        try:
            reader.TransferRoots()
            shape = reader.OneShape()
        except Standard_Failure as exc:
            raise GeometryError(f"{name}: OCCT failed to transfer the STEP file: {exc}") from exc
        warnings += _check_messages(reader.WS().TransferReader().LastCheckList(), "transfer")
    if shape.IsNull() or _count(shape, TopAbs_EDGE) == 0:
        raise InputError(f"{name}: empty shape (the STEP file has no edges)")
    mm_per_unit = _file_unit_mm(reader)
    declared = _declared_uncertainty(reader)
    declared_mm = declared * mm_per_unit if declared is not None and mm_per_unit is not None else None
    units = UNIT_NAMES.get(reader.SystemLengthUnit(), f"{reader.SystemLengthUnit():g} mm")
    warnings += tolerance_warnings(shape, units, declared_mm)
    return LoadedShape(shape=shape, source=name, units=units, warnings=warnings)


def _count(shape: TopoDS_Shape, kind: Any) -> int:
    m = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, kind, m)
    return m.Extent()


def tolerance_warnings(shape: TopoDS_Shape, units: str, declared: float | None = None) -> list[str]:
    """One warning if the worst edge tolerance is large for the model's size or its declared precision.

    A large edge tolerance means vertices and pcurves may lie far off the 3-D curves (healed or
    badly exported models): the grids are still made, but downstream meshes may not close up.
    """
    edges = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_EDGE, edges)
    worst, worst_id = 0.0, 0
    for i in range(1, edges.Extent() + 1):
        tol = BRep_Tool.Tolerance_s(TopoDS.Edge_s(edges.FindKey(i)))
        if tol > worst:
            worst, worst_id = tol, i
    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box, False)
    if box.IsVoid():
        return []
    diag = box.SquareExtent() ** 0.5  # not box.Get(): OCP 8.0 cannot return its Limits struct
    too_big_for_model = diag > 0 and worst > TOL_REL_MODEL * diag
    too_big_for_file = declared is not None and worst > TOL_REL_DECLARED * declared and worst > 1e-5 * diag
    if not (too_big_for_model or too_big_for_file):
        return []
    decl = f", declared uncertainty {declared:.3g} {units}" if declared is not None else ""
    return [f"loose tolerance: edge {worst_id} has tolerance {worst:.3g} {units}, {worst / diag:.2g} of the "
            f"model size {diag:.4g} {units}{decl}; vertices may lie off their curves"]


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
    elif isinstance(getattr(source, "wrapped", None), TopoDS_Shape):  # cq.Shape, build123d shape
        pkg = type(source).__module__.split(".")[0]
        shape, desc = source.wrapped, f"<{pkg} {kind}>"
    else:
        raise InputError(f"cannot refine a {kind}: expected a STEP file path, a cadquery Workplane/Shape, "
                         "a build123d shape or a TopoDS_Shape")
    if shape.IsNull() or _count(shape, TopAbs_EDGE) == 0:
        raise InputError(f"{desc}: empty shape (no edges)")
    return LoadedShape(shape=shape, source=desc, units="mm", warnings=tolerance_warnings(shape, "mm"))


def load_shape(source: Any) -> LoadedShape:
    """Load ``source``: a STEP path (str or PathLike, .step/.stp in any case) or an in-memory shape.

    STEP files are transferred with OCCT's defaults, which convert lengths to millimetres; ``units``
    reports the unit after transfer. In-memory shapes are taken as millimetres.
    """
    if isinstance(source, (str, os.PathLike)):
        return _read_step(Path(source))
    return _from_object(source)
