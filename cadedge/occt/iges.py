"""IGES files (fixed 80-column ASCII form) through OCCT's ``IGESControl_Reader``, with the STEP checks.

Sniffed first: the start or global section letter in column 73 of the first line, and a terminate
line (``T`` in column 73) whose section line counts must add up to the file's lines, so a cut or
padded file is caught before OCCT parses it. After the transfer, the distinct faces and solids of
the result are counted against the file's face entities (types 510 face, 144 trimmed surface, 143
bounded surface) and manifold solids (186), and the roots transferred against the roots present.
Lengths are converted from the file's unit (global section) to OCCT's session unit, millimetres by
default.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Callable

from OCP.IFSelect import IFSelect_RetDone
from OCP.IGESControl import IGESControl_Reader
from OCP.Interface import Interface_Static

from ..errors import InputError
from .loading import (Completeness, LoadedShape, Transferred, accept, check_counts, damaged, first_failure,
                      opens_as_step, skipped_entities, sniff_path, transfer_roots, transferred,
                      unresolved_references)

FACE_TYPES = (510, 144, 143)
SOLID_TYPES = (186,)
#: OCCT's session length unit (``xstep.cascade.unit``) as cadedge names units.
_CASCADE_UNITS = {"MM": "mm", "CM": "cm", "M": "m", "IN": "inch", "INCH": "inch", "FT": "ft", "UM": "um",
                  "KM": "km", "MIL": "mil"}
_TERMINATE = re.compile(rb"S\s*(\d+)G\s*(\d+)D\s*(\d+)P\s*(\d+)")
_READ_STATUS = {"RetVoid": "nothing to read", "RetError": "cannot open or unknown format",
                "RetFail": "syntax error", "RetStop": "reading stopped"}


def _lines(data: bytes) -> list[bytes]:
    return [line for line in data.splitlines() if line.strip()]


def sniff(path: Path, given: str) -> None:
    """InputError unless ``path`` looks like a complete IGES file (header letter, terminate line, line count)."""
    head, tail, _ = sniff_path(path, given)
    first = (_lines(head) or [b""])[0]
    if opens_as_step(head):
        raise InputError(f"{given}: not an IGES file (it holds STEP text; name it .step or .stp)")
    if len(first) < 73 or first[72:73] not in (b"S", b"G"):
        raise InputError(f"{given}: not an IGES file (no start section: 'S' in column 73 of the first line)")
    last = (_lines(tail) or [b""])[-1]
    counts = _TERMINATE.match(last[:72]) if len(last) >= 73 and last[72:73] == b"T" else None
    if counts is None:
        raise InputError(f"{given}: truncated IGES file (it ends without a terminate line, 'T' in column 73)")
    declared = sum(int(n) for n in counts.groups()) + 1
    actual = len(_lines(path.read_bytes()))
    if actual != declared:
        raise InputError(f"{given}: truncated or corrupt IGES file (its terminate line counts {declared} lines, "
                         f"the file has {actual})")


def _survey(reader: IGESControl_Reader) -> tuple[int, int, int]:
    """(face entities, solid entities, all entities) of the loaded IGES model."""
    model = reader.IGESModel()
    faces = solids = 0
    for i in range(1, model.NbEntities() + 1):
        kind = model.Entity(i).TypeNumber()
        faces += kind in FACE_TYPES
        solids += kind in SOLID_TYPES
    return faces, solids, model.NbEntities()


def transfer_iges(path: Path, given: str, *, isolate: bool = True,
                  note: Callable[[str], None] | None = None) -> Transferred:
    """Read and transfer an IGES file, without judging completeness; InputError for bad or empty files.
    With ``isolate`` everything after the sniff runs in another process, as for STEP (see
    :mod:`cadedge.occt.isolate`); ``note`` is told how far the reading got there."""
    sniff(path, given)
    if isolate:
        from .isolate import run_isolated
        return run_isolated("IGES", path, given, lambda at: _read(path, given, at))
    return _read(path, given, note or (lambda stage: None))


def _read(path: Path, given: str, note: Callable[[str], None]) -> Transferred:
    """:func:`transfer_iges` past the sniff, here."""
    from .reader import quiet_occt

    reader = IGESControl_Reader()
    with quiet_occt():
        status = reader.ReadFile(str(path))
        if status != IFSelect_RetDone:
            first = first_failure(reader.WS().ModelCheckList())
            reason = _READ_STATUS.get(str(status).split("_")[-1], str(status))
            raise InputError(f"{given}: corrupt IGES file (OCCT: {reason}{first})")
        load = check_counts(reader.WS().ModelCheckList())
        note("damaged" if damaged(load) else "parsed")
        faces, solids, entities = _survey(reader)
        roots = reader.NbRootsForTransfer()
        if roots == 0:
            what = f"{entities} entities, none of them a shape" if entities else "it holds no entities"
            raise InputError(f"{given}: no shape in the IGES file ({what})")
        done_roots, shape, warnings, transfer = transfer_roots(reader, given, "IGES", load)
    got_faces, got_solids = transferred(shape)
    done = Completeness(faces=(got_faces, faces), solids=(got_solids, solids), roots=(done_roots, roots),
                        unresolved=unresolved_references(load), skipped=skipped_entities(transfer))
    cascade = Interface_Static.CVal_s("xstep.cascade.unit").strip().upper()
    return Transferred(shape=shape, done=done, units=_CASCADE_UNITS.get(cascade, cascade.lower() or "mm"),
                       warnings=warnings)


def read_iges(path: Path, given: str, *, allow_partial: bool = False) -> LoadedShape:
    """Read and transfer an IGES file; InputError for bad, empty or (unless allowed) partial files."""
    t = transfer_iges(path, given)
    return accept(LoadedShape(shape=t.shape, source=path.name, units=t.units, warnings=t.warnings), t.done,
                  given, "IGES", allow_partial)
