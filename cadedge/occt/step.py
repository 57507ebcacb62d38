"""STEP files (ISO 10303-21) through OCCT's ``STEPControl_Reader``, checked at every stage.

The file is sniffed in Python before OCCT sees it (header, trailer), because OCCT's parser may
crash on some garbage and prints its own complaints to stdout (silenced here). A file OCCT cannot
parse, one whose DATA section holds nothing readable, and one that holds no shape get distinct
messages; so does a file cut short. After the transfer, the faces and solids of the result are
counted against the file's ``FACE_SURFACE``/``ADVANCED_FACE`` and ``MANIFOLD_SOLID_BREP`` entities
and the face references the file could not resolve, and the roots transferred against the roots
present (see :class:`~cadedge.occt.loading.Completeness`).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Callable

from OCP.IFSelect import IFSelect_RetDone
from OCP.StepBasic import StepBasic_UncertaintyMeasureWithUnit
from OCP.StepShape import (StepShape_ConnectedFaceSet, StepShape_FaceSurface, StepShape_ManifoldSolidBrep,
                           StepShape_OrientedClosedShell, StepShape_OrientedOpenShell)
from OCP.STEPControl import STEPControl_Reader

from ..errors import InputError
from .compat import TColStd_SequenceOfAsciiString
from .loading import (MM_PER_UNIT, UNIT_NAMES, Completeness, LoadedShape, Transferred, accept, check_counts,
                      cut_short, damaged, first_failure, opens_as_step, skipped_entities, sniff_path,
                      transfer_roots, transferred, unresolved_references)

_ORIENTED = (StepShape_OrientedClosedShell, StepShape_OrientedOpenShell)
_READ_STATUS = {"RetVoid": "nothing to read", "RetError": "cannot open or unknown format",
                "RetFail": "syntax error", "RetStop": "reading stopped"}
#: Files up to this size are read whole to tell an empty DATA section from an unreadable one.
_SCAN_BYTES = 1 << 20
_TRAILER = re.compile(rb"ENDSEC\s*;\s*END-ISO-10303-21\s*;\s*$", re.IGNORECASE)


def sniff(path: Path, given: str) -> bytes:
    """The file's tail; InputError unless ``path`` looks like a complete ISO 10303-21 file."""
    head, tail, _ = sniff_path(path, given)
    if not opens_as_step(head):
        raise InputError(f"{given}: not a STEP file (no ISO-10303-21 header)")
    if b"END-ISO-10303-21" not in tail.upper():
        raise InputError(f"{given}: truncated STEP file (it ends without the END-ISO-10303-21 trailer)")
    return tail


def _parse_failure(given: str, tail: bytes, reader: STEPControl_Reader, status: str) -> InputError:
    """Why OCCT could not parse the file: cut off inside an entity, or corrupt (with OCCT's first fail)."""
    body = _TRAILER.sub(b"", tail.rstrip())
    if body and not body.rstrip().endswith(b";"):
        return InputError(f"{given}: truncated STEP file (its last entity is cut off before the trailer)")
    first = first_failure(reader.WS().ModelCheckList())
    return InputError(f"{given}: corrupt STEP file (OCCT: {_READ_STATUS.get(status, status)}{first})")


def _no_roots(given: str, path: Path, entities: int, faces: int) -> InputError:
    """Empty DATA section, unreadable DATA section, or entities of which none is a shape."""
    if faces:
        return InputError(f"{given}: corrupt STEP file: nothing transferred; it defines {faces} faces but no "
                          "shape representation holding them (cut short or damaged)")
    if entities:
        return InputError(f"{given}: no shape in the STEP file ({entities} entities, none of them a shape "
                          "representation to transfer)")
    size = path.stat().st_size
    text = path.read_bytes() if size <= _SCAN_BYTES else b"x" * size
    start = text.upper().find(b"DATA;")
    body = text[start + 5:] if start >= 0 else b""
    body = _TRAILER.sub(b"", body.rstrip())
    if size <= _SCAN_BYTES and not body.strip():
        return InputError(f"{given}: empty STEP file (its DATA section holds no entities)")
    return InputError(f"{given}: corrupt STEP file (nothing in its DATA section could be read as an entity)")


def _survey(reader: STEPControl_Reader) -> tuple[int, int, int, float | None]:
    """(faces, solids, unresolved face references, smallest declared uncertainty) of the file's model."""
    model = reader.StepModel()
    faces = solids = unresolved = 0
    uncertainties = []
    for i in range(1, model.NbEntities() + 1):
        ent = model.Value(i)
        if isinstance(ent, StepShape_FaceSurface):
            faces += 1
        elif isinstance(ent, StepShape_ManifoldSolidBrep):
            solids += 1
        elif isinstance(ent, StepShape_ConnectedFaceSet) and not isinstance(ent, _ORIENTED):
            refs = ent.CfsFaces()  # (an oriented shell's are its shell's, which OCCT fetches without a check)
            if refs is None:
                continue
            unresolved += sum(refs.Value(k) is None for k in range(refs.Lower(), refs.Upper() + 1))
        elif isinstance(ent, StepBasic_UncertaintyMeasureWithUnit) and ent.ValueComponent() > 0:
            uncertainties.append(ent.ValueComponent())
    return faces, solids, unresolved, min(uncertainties) if uncertainties else None


def _file_unit_mm(reader: STEPControl_Reader) -> float | None:
    """Millimetres per length unit the STEP file declares (None if unknown)."""
    lengths, angles, solids = (TColStd_SequenceOfAsciiString() for _ in range(3))
    reader.FileUnits(lengths, angles, solids)
    if lengths.Length() == 0:
        return None
    return MM_PER_UNIT.get(lengths.Value(1).ToCString().strip().lower())


def transfer_step(path: Path, given: str, *, isolate: bool = True,
                  note: Callable[[str], None] | None = None) -> Transferred:
    """Read and transfer a STEP file, without judging completeness; InputError for bad or empty files.

    With ``isolate`` everything after the sniff runs in another process (OCCT crashes on some malformed
    files; see :mod:`cadedge.occt.isolate`); ``note`` is told how far the reading got there.
    """
    tail = sniff(path, given)
    if isolate:
        from .isolate import run_isolated
        return run_isolated("STEP", path, given, lambda at: _read(path, given, tail, at))
    return _read(path, given, tail, note or (lambda stage: None))


def _read(path: Path, given: str, tail: bytes, note: Callable[[str], None]) -> Transferred:
    """:func:`transfer_step` past the sniff (``tail``, the file's last bytes), here."""
    from .reader import quiet_occt

    reader = STEPControl_Reader()
    with quiet_occt():
        status = reader.ReadFile(str(path))
        if status != IFSelect_RetDone:
            raise _parse_failure(given, tail, reader, str(status).split("_")[-1])
        load = check_counts(reader.WS().ModelCheckList())
        note("cut" if cut_short(load) else "damaged" if damaged(load) else "parsed")
        roots = reader.NbRootsForTransfer()
        faces, solids, unresolved, declared = _survey(reader)
        if roots == 0:
            raise _no_roots(given, path, reader.StepModel().NbEntities(), faces)
        done_roots, shape, warnings, transfer = transfer_roots(reader, given, "STEP", load)
    got_faces, got_solids = transferred(shape)
    done = Completeness(faces=(got_faces, faces + unresolved), solids=(got_solids, solids),
                        roots=(done_roots, roots), unresolved=max(unresolved, unresolved_references(load)),
                        truncated=cut_short(load), skipped=skipped_entities(transfer))
    if (split := _split_by_healing(done.faces, done.solids)) is not None:
        warnings.insert(0, split)
    units = UNIT_NAMES.get(reader.SystemLengthUnit(), f"{reader.SystemLengthUnit():g} mm")
    mm_per_unit = _file_unit_mm(reader)
    declared_mm = declared * mm_per_unit if declared is not None and mm_per_unit is not None else None
    return Transferred(shape=shape, done=done, units=units, warnings=warnings, declared=declared_mm)


def _split_by_healing(faces: tuple[int, int], solids: tuple[int, int]) -> str | None:
    """A warning when the shape holds more faces than the file defines, else None (``faces``, ``solids``:
    (transferred, defined), as :class:`~cadedge.occt.loading.Completeness` counts them).

    The STEP reader's only process is OCCT's shape healing (``FixShape``), so more faces mean it split
    faces the file holds whole. Seen where that loses a face: a sphere with 40 dimples, written and read
    back by OCCT, reads as 79 faces and 39 solids, its sphere face's holes taken for faces of their own
    and the rest of it dropped (89% of the area lost), and OCCT says only "Improperly connected shell
    split into parts".

    >>> _split_by_healing((79, 41), (39, 1))[:73]
    "OCCT's shape healing read the file's 41 faces as 79 and its 1 solid as 39"
    >>> _split_by_healing((6, 6), (1, 1)) is None
    True
    """
    (got_faces, defined), (got_solids, solids) = faces, solids
    if not defined or got_faces <= defined:
        return None
    solid = f" and its {solids} solid{'s' * (solids != 1)} as {got_solids}" if got_solids > solids else ""
    return (f"OCCT's shape healing read the file's {defined} faces as {got_faces}{solid}: it split faces the file "
            "holds whole, which can lose a face's area (its holes taken for faces of their own); check the shape "
            "read")


def read_step(path: Path, given: str, *, allow_partial: bool = False) -> LoadedShape:
    """Read and transfer a STEP file; InputError for bad, empty or (unless allowed) partial files."""
    t = transfer_step(path, given)
    return accept(LoadedShape(shape=t.shape, source=path.name, units=t.units, warnings=t.warnings,
                              declared=t.declared), t.done, given, "STEP", allow_partial)
