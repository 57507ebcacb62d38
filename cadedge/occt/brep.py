"""OCCT's own ASCII BREP files (``BRepTools::Write``) through ``BRepTools::Read``, checked first in Python.

OCCT's BREP reader reports a damaged file only on standard output and hands back what it could, so
the file is checked before it is read: the "CASCADE Topology" header, the ``TShapes N`` table with N
shape records, and the root reference after them (in files saved by OCCT's Draw, followed by its "0"
line; text after it, which OCCT's reader ignores, is named in a warning). The geometry tables' counts
(``Curves N`` and the like) must be no more than the file's lines: OCCT's reader takes them at their word,
and a count of a billion kept it reading for minutes. After the read, the distinct faces and solids of the
shape are counted against the file's face (``Fa``) and solid (``So``) records. BREP files carry no length
unit; their lengths are taken as millimetres, like in-memory shapes.

The read itself runs in another process, as STEP and IGES transfers do (:mod:`cadedge.occt.isolate`):
OCCT's BREP reader crashes on some damaged files the check passes (a curve record of a type it does not
know: a segmentation fault), and that must cost one error line, not the caller.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

from OCP.BRep import BRep_Builder
from OCP.BRepTools import BRepTools
from OCP.TopoDS import TopoDS_Shape

from ..errors import InputError
from .loading import Completeness, LoadedShape, Transferred, accept, quiet_occt, sniff_path, transferred

_HEADER = re.compile(rb"^\s*(DBRep_DrawableShape\s+)?CASCADE Topology V\d")
_TSHAPES = re.compile(rb"^TShapes (\d+)\s*$", re.MULTILINE)
_RECORD = re.compile(rb"^(Ve|Ed|Wi|Fa|Sh|So|CS|Co)\s*$", re.MULTILINE)
# The root reference follows the last shape record: an orientation (``+`` forward, ``-`` reversed, ``i``
# internal, ``e`` external: gmsh's SlenderSurface.brep has an internal root), the shape's index and its
# location's. It is the end of the shape; OCCT's reader reads nothing after it. A shape saved by OCCT's
# Draw (``save``, the DBRep_DrawableShape header) has one more line, "0"; text appended after it (gmsh's
# unable_to_recover_edge_2d-2.brep carries 44 lines of a .geo script, from "+1 1 //+" on) is ignored.
_ROOT = re.compile(rb"^[+\-ie]\d+ \d+(?![ \t]*[+\-ie]?\d)(?![ \t]*\*)[^\n]*$", re.MULTILINE)
#: The geometry tables before the shapes, each headed by its name and how many records it holds.
_TABLE = re.compile(rb"^(Locations|Curve2ds|Curves|Polygon3D|PolygonOnTriangulations|Surfaces|Triangulations)"
                    rb"[ \t]+(-?\d+)\s*$", re.MULTILINE)


def sniff(path: Path, given: str) -> tuple[int, int, str | None]:
    """(face records, solid records, a warning or None) of a complete ASCII BREP file; InputError
    otherwise. The warning names text after the root reference, which OCCT's reader ignores."""
    head, _, _ = sniff_path(path, given)
    if not _HEADER.match(head):
        if b"Open CASCADE Topology" in head[:64]:
            raise InputError(f"{given}: binary BREP files are not supported; write ASCII BREP (BRepTools::Write)")
        raise InputError(f"{given}: not an OCCT BREP file (no 'CASCADE Topology' header)")
    data = path.read_bytes()
    table = _TSHAPES.search(data)
    if table is None:
        raise InputError(f"{given}: truncated or corrupt BREP file (no TShapes table)")
    lines = data.count(b"\n") + 1
    for name, count in _TABLE.findall(data, 0, table.start()):
        if not 0 <= int(count) <= lines:
            raise InputError(f"{given}: corrupt BREP file (its {name.decode()} table declares {int(count)} "
                             f"records, in a file of {lines} lines)")
    found = list(_RECORD.finditer(data, table.end()))
    records = [m.group(1) for m in found]
    declared = int(table.group(1))
    if len(records) != declared:
        raise InputError(f"{given}: truncated BREP file (its TShapes table declares {declared} shapes, the file "
                         f"holds {len(records)})")
    root = _ROOT.search(data, found[-1].end() if found else table.end())
    if root is None:
        raise InputError(f"{given}: truncated BREP file (it ends without the root shape reference)")
    after = [line.strip() for line in data[root.end():].splitlines() if line.strip()]
    if after[:1] == [b"0"]:
        after = after[1:]  # Draw's closing line
    junk = len(after) + bool(root.group().split()[2:])
    warning = (f"BREP file: {junk} line{'s' * (junk > 1)} of text after the root shape reference ignored "
               "(OCCT's reader reads none of it)") if junk else None
    return records.count(b"Fa"), records.count(b"So"), warning


def transfer_brep(path: Path, given: str, *, isolate: bool = True,
                  note: Callable[[str], None] | None = None) -> Transferred:
    """Check and read an ASCII BREP file, without judging completeness; InputError for bad files. With
    ``isolate`` the read runs in another process (see the module doc); ``note`` is unused (a BREP read
    has no stages to tell)."""
    faces, solids, warning = sniff(path, given)
    if isolate:
        from .isolate import run_isolated
        return run_isolated("BREP", path, given, lambda at: _read(path, given, faces, solids, warning))
    return _read(path, given, faces, solids, warning)


def _read(path: Path, given: str, faces: int, solids: int, warning: str | None) -> Transferred:
    """:func:`transfer_brep` past the check (the file's ``faces`` and ``solids`` records), here."""
    shape = TopoDS_Shape()
    with quiet_occt():
        try:
            ok = BRepTools.Read_s(shape, str(path), BRep_Builder())
        except Exception as exc:  # OCCT's exceptions (compat.OCCT_ERRORS) and the binding's own: an index
            # out of its table, a shape referring to itself
            raise InputError(f"{given}: corrupt BREP file (OCCT could not read it: {type(exc).__name__}: "
                             f"{exc})") from exc
    if not ok:
        raise InputError(f"{given}: corrupt BREP file (OCCT could not read it)")
    got_faces, got_solids = transferred(shape)
    done = Completeness(faces=(got_faces, faces), solids=(got_solids, solids), roots=(int(not shape.IsNull()), 1))
    return Transferred(shape=shape, done=done, units="mm", warnings=[warning] if warning else [])


def read_brep(path: Path, given: str, *, allow_partial: bool = False) -> LoadedShape:
    """Read an ASCII BREP file; InputError for bad, empty or (unless allowed) partial files."""
    t = transfer_brep(path, given)
    loaded = LoadedShape(shape=t.shape, source=path.name, units=t.units, warnings=t.warnings)
    return accept(loaded, t.done, given, "BREP", allow_partial)
