"""What the file readers (STEP, IGES, BREP) share: the loaded shape, OCCT's silenced console, check
messages, the first sniff of a path, and the completeness of a transfer.

A transfer is *partial* when the shape OCCT hands back holds fewer faces or solids than the file
defines, or when some of the file's roots did not transfer. :class:`Completeness` measures that from
what OCCT reports (its model's entities, the references it could not resolve, the roots it
transferred) against the distinct faces and solids of the result; :func:`accept` refuses a partial
transfer unless the caller allows it, and then says what was lost in a warning.
"""

from __future__ import annotations

import re
import threading
from collections import Counter
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

from OCP.Interface import Interface_CheckIterator
from OCP.Message import Message
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_SOLID
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS_Shape

from ..errors import GeometryError, InputError
from .compat import OCCT_ERRORS, TopTools_IndexedMapOfShape

#: Millimetres per unit for the length unit names files declare (lower-cased).
MM_PER_UNIT = {"millimetre": 1.0, "millimeter": 1.0, "mm": 1.0, "centimetre": 10.0, "centimeter": 10.0,
               "cm": 10.0, "metre": 1000.0, "meter": 1000.0, "m": 1000.0, "inch": 25.4, "in": 25.4,
               "foot": 304.8, "ft": 304.8, "micrometre": 1e-3, "micron": 1e-3, "kilometre": 1e6}
UNIT_NAMES = {1.0: "mm", 10.0: "cm", 1000.0: "m", 25.4: "inch", 304.8: "ft", 1e-3: "um"}
HEAD_BYTES = 4096
TAIL_BYTES = 4096
_occt_output = threading.Lock()
_quiet_depth = 0
_saved_printers: list[Any] = []


@dataclass
class LoadedShape:
    """A shape ready for refinement: ``units`` is its length unit, ``warnings`` one line each, ``declared``
    the uncertainty the file declares (in the shape's coordinates; None if it declares none), for the tolerance
    scan (:func:`cadedge.occt.reader.tolerance_warnings`)."""

    shape: TopoDS_Shape
    source: str
    units: str = "mm"
    warnings: list[str] = field(default_factory=list)
    declared: float | None = None


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


#: OCCT's check message for an entity its parser could not build.
_NO_DATA = "DATA NOT AVAILABLE FOR CHECK"


def check_counts(checks: Interface_CheckIterator) -> Counter[str]:
    """Fail and warning messages of an OCCT check list, counted ("fail: ..." / "warning: ...")."""
    counts: Counter[str] = Counter()
    checks.Start()
    while checks.More():
        ch = checks.Value()
        for i in range(1, ch.NbFails() + 1):
            counts[f"fail: {ch.CFail(i)}"] += 1
        for i in range(1, ch.NbWarnings() + 1):
            counts[f"warning: {ch.CWarning(i)}"] += 1
        checks.Next()
    return counts


def first_failure(checks: Interface_CheckIterator) -> str:
    """"; first error: ..." with OCCT's first informative fail message of a parse, or "" if it has none
    (OCCT's placeholder for an entity it could not parse, "DATA NOT AVAILABLE FOR CHECK", says nothing)."""
    fails = [m[6:] for m in check_counts(checks) if m.startswith("fail: ") and _NO_DATA not in m]
    return f"; first error: {fails[0]}" if fails else ""


def check_messages(counts: Counter[str], prefix: str) -> list[str]:
    """One line per distinct check message, with its count."""
    return [f"{prefix} {msg}" + (f" (x{n})" if n > 1 else "") for msg, n in counts.items()]


def transfer_roots(reader: Any, given: str, kind: str, load: Counter[str]) -> tuple[int, TopoDS_Shape, list[str],
                                                                                   Counter[str]]:
    """Transfer every root of a loaded STEP or IGES ``reader``: (roots transferred, the shape, the load and
    transfer messages, the transfer check counts). An OCCT exception is a GeometryError naming ``given``."""
    try:
        done_roots = reader.TransferRoots()
        shape = reader.OneShape()
    except OCCT_ERRORS as exc:
        raise GeometryError(f"{given}: OCCT failed to transfer the {kind} file: {exc}") from exc
    transfer = check_counts(reader.WS().TransferReader().LastCheckList())
    return done_roots, shape, check_messages(load, f"{kind} load") + check_messages(transfer, f"{kind} transfer"), \
        transfer


def count(shape: TopoDS_Shape, kind: Any) -> int:
    """Sub-shapes of ``kind`` in ``TopExp::MapShapes`` order (distinct by shape and location)."""
    m = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, kind, m)
    return m.Extent()


def distinct(shape: TopoDS_Shape, kind: Any) -> int:
    """Sub-shapes of ``kind`` that are distinct geometry: instances of one part count once."""
    m = TopTools_IndexedMapOfShape()
    ex = TopExp_Explorer(shape, kind)
    here = TopLoc_Location()
    while ex.More():
        m.Add(ex.Current().Located(here))
        ex.Next()
    return m.Extent()


#: What may come before the ISO-10303-21 token: a byte-order mark, white space and ``/* */`` comments
#: (OCCT reads files that open with a comment).
_LEADING = re.compile(rb"(?:\xef\xbb\xbf)?(?:\s+|/\*.*?\*/)*", re.DOTALL)


def opens_as_step(head: bytes) -> bool:
    r"""Whether the first bytes of a file are those of an ISO 10303-21 file.

    >>> opens_as_step(b"/* made by hand */\nISO-10303-21;\nHEADER;"), opens_as_step(b"solid x")
    (True, False)
    """
    return head[_LEADING.match(head).end():].upper().startswith(b"ISO-10303-21")


def sniff_path(path: Path, given: str) -> tuple[bytes, bytes, int]:
    """(head, tail, size) of a readable, non-empty file; InputError naming ``given`` otherwise."""
    if not path.exists():
        raise InputError(f"{given}: no such file")
    if not path.is_file():
        raise InputError(f"{given}: not a file")
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            head = fh.read(HEAD_BYTES)
            fh.seek(max(0, size - TAIL_BYTES))
            tail = fh.read()
    except OSError as exc:
        raise InputError(f"{given}: cannot read: {exc.strerror or exc}") from None
    if size == 0:
        raise InputError(f"{given}: empty file (0 bytes)")
    return head, tail, size


def _of(what: str, got: int, expected: int) -> str:
    return f"{expected - got} of {expected} {what}"


@dataclass(frozen=True)
class Completeness:
    """What a file defines against what OCCT transferred from it.

    ``faces``/``solids``: (transferred, defined) where the file's entities say how many there are
    (``None`` when the format does not tell); ``roots``: (transferred, present); ``unresolved``:
    references to entities the file does not hold (a cut or corrupted file); ``skipped``: entities the
    transfer check says failed or were skipped. Any of these makes the transfer partial: an unresolved
    reference may have lost no face yet still the file's length unit, its context or part of a curve,
    and a skipped face may be hidden in the counts by an orphaned surface transferred in its place.
    """

    faces: tuple[int, int] | None
    solids: tuple[int, int] | None
    roots: tuple[int, int]
    unresolved: int = 0
    truncated: bool = False
    skipped: int = 0

    @property
    def partial(self) -> bool:
        """Something the file defines did not reach the shape."""
        pairs = [p for p in (self.faces, self.solids, self.roots) if p is not None]
        return self.unresolved > 0 or self.truncated or self.skipped > 0 or any(
            got < expected for got, expected in pairs)

    def lost(self) -> str:
        """What was lost, e.g. "3 of 82 faces (2 of 12 solids) failed to load". Solids lost while every
        face loaded are said to be so, since allowing the partial transfer then loses no face: a solid
        whose faces share no edge (some ECAD libraries' faceted models: OCCT's shell fix splits it into
        a shell per face), or a body OCCT reads as a shell."""
        faces = self.faces if self.faces is not None and self.faces[0] < self.faces[1] else None
        solids = self.solids if self.solids is not None and self.solids[0] < self.solids[1] else None
        roots = self.roots if self.roots[0] < self.roots[1] else None
        if faces:
            text = _of("faces", *faces) + (f" ({_of('solids', *solids)})" if solids else "")
        elif solids:
            text = _of("solids", *solids)
        elif roots:
            text = _of("shape roots", *roots)
        else:
            text = ""
        if text:
            text += " failed to load"
            if solids and not faces and self.faces is not None and self.faces[1]:
                text += f" (all {self.faces[1]} faces loaded, as shells or faces outside any solid)"
        if (faces or solids) and roots:
            text += f", {_of('shape roots', *roots)} failed to transfer"
        notes = []
        if self.unresolved:
            notes.append(f"{self.unresolved} reference{'s' * (self.unresolved != 1)} to entities missing from "
                         "the file")
        if self.skipped:
            notes.append(f"{self.skipped} entit{'ies' if self.skipped != 1 else 'y'} skipped by the transfer")
        if notes:
            text = f"{text} ({', '.join(notes)})" if text else f"no face or solid measurably lost, but {' and '.join(notes)}"
        if self.truncated:
            text += "; the file is cut short (its last entity is incomplete)"
        return text


@dataclass
class Transferred:
    """A file's shape as OCCT transferred it, before :func:`accept` judges it; ``declared`` is the
    smallest length uncertainty the file declares, in ``units`` (None if it declares none)."""

    shape: TopoDS_Shape
    done: Completeness
    units: str
    warnings: list[str]
    declared: float | None = None


#: Load-check messages that mark a damaged file, on which OCCT's transfer has been seen to crash.
DAMAGE_MARKS = ("Unresolved Reference", "Undefined Parsing", "Incorrect syntax")


def cut_short(load: Counter[str]) -> bool:
    """Whether the parser met the end of the DATA section inside an entity (a file cut and re-closed)."""
    return any("unexpected ENDSEC" in msg for msg in load)


def unresolved_references(load: Counter[str]) -> int:
    """How many references the load check found pointing at entities the file does not define."""
    return sum(n for msg, n in load.items() if msg.startswith("fail: Unresolved Reference"))


def skipped_entities(transfer: Counter[str]) -> int:
    """How many transfer-check fails say an entity failed to transfer or was skipped."""
    return sum(n for msg, n in transfer.items()
               if msg.startswith("fail: ") and ("skipped" in msg.lower() or "transfer failed" in msg.lower()))


def damaged(load: Counter[str]) -> bool:
    """Whether the load check of a file shows missing entities or unparsable text."""
    return any(msg.startswith("fail: ") and any(m in msg for m in DAMAGE_MARKS) for msg in load)


def accept(loaded: LoadedShape, done: Completeness, given: str, kind: str, allow_partial: bool) -> LoadedShape:
    """``loaded`` as it is when ``done`` is complete; otherwise InputError, or with ``allow_partial`` a
    warning saying what was lost. A shape with no edges at all is refused either way."""
    if loaded.shape.IsNull() or count(loaded.shape, TopAbs_EDGE) == 0:
        if done.partial:
            raise InputError(f"{given}: corrupt {kind} file: nothing transferred; {done.lost()}")
        raise InputError(f"{given}: empty shape (the {kind} file has no edges)")
    if not done.partial:
        return loaded
    if not allow_partial:
        raise InputError(f"{given}: partial transfer refused: {done.lost()}; allow_partial=True "
                         "(--allow-partial) refines what did load")
    loaded.warnings.insert(0, f"partial transfer: {done.lost()}; refining what did load")
    return loaded


def transferred(shape: TopoDS_Shape) -> tuple[int, int]:
    """(distinct faces, distinct solids) of a transferred shape."""
    if shape.IsNull():
        return 0, 0
    return distinct(shape, TopAbs_FACE), distinct(shape, TopAbs_SOLID)
