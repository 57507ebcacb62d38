"""OCCT's own ASCII BREP files (``BRepTools::Write``) through ``BRepTools::Read``, checked first in Python.

OCCT's BREP reader reports a damaged file only on standard output and hands back what it could, so
the file is checked before it is read: the "CASCADE Topology" header, the ``TShapes N`` table with N
shape records, and the root reference after them (in files saved by OCCT's Draw, followed by its "0"
line; text after it, which OCCT's reader ignores, is named in a warning). After the read, the distinct
faces and solids of the shape are counted against the file's face (``Fa``) and solid (``So``) records.
BREP files carry no length unit; their lengths are taken as millimetres, like in-memory shapes.
"""

from __future__ import annotations

import re
from pathlib import Path

from OCP.BRep import BRep_Builder
from OCP.BRepTools import BRepTools
from OCP.Standard import Standard_Failure
from OCP.TopoDS import TopoDS_Shape

from ..errors import GeometryError, InputError
from .loading import Completeness, LoadedShape, accept, sniff_path, transferred

_HEADER = re.compile(rb"^\s*(DBRep_DrawableShape\s+)?CASCADE Topology V\d")
_TSHAPES = re.compile(rb"^TShapes (\d+)\s*$", re.MULTILINE)
_RECORD = re.compile(rb"^(Ve|Ed|Wi|Fa|Sh|So|CS|Co)\s*$", re.MULTILINE)
# The root reference follows the last shape record: an orientation (``+`` forward, ``-`` reversed, ``i``
# internal, ``e`` external: gmsh's SlenderSurface.brep has an internal root), the shape's index and its
# location's. It is the end of the shape; OCCT's reader reads nothing after it. A shape saved by OCCT's
# Draw (``save``, the DBRep_DrawableShape header) has one more line, "0"; text appended after it (gmsh's
# unable_to_recover_edge_2d-2.brep carries 44 lines of a .geo script, from "+1 1 //+" on) is ignored.
_ROOT = re.compile(rb"^[+\-ie]\d+ \d+(?![ \t]*[+\-ie]?\d)(?![ \t]*\*)[^\n]*$", re.MULTILINE)


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


def read_brep(path: Path, given: str, *, allow_partial: bool = False) -> LoadedShape:
    """Read an ASCII BREP file; InputError for bad, empty or (unless allowed) partial files."""
    from .reader import quiet_occt

    faces, solids, warning = sniff(path, given)
    shape = TopoDS_Shape()
    with quiet_occt():
        try:
            ok = BRepTools.Read_s(shape, str(path), BRep_Builder())
        except Standard_Failure as exc:
            raise GeometryError(f"{given}: OCCT failed to read the BREP file: {exc}") from exc
    if not ok:
        raise InputError(f"{given}: corrupt BREP file (OCCT could not read it)")
    got_faces, got_solids = transferred(shape)
    done = Completeness(faces=(got_faces, faces), solids=(got_solids, solids), roots=(int(not shape.IsNull()), 1))
    loaded = LoadedShape(shape=shape, source=path.name, units="mm", warnings=[warning] if warning else [])
    return accept(loaded, done, given, "BREP", allow_partial)
