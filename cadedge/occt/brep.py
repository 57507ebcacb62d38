"""OCCT's own ASCII BREP files (``BRepTools::Write``) through ``BRepTools::Read``, checked first in Python.

OCCT's BREP reader reports a damaged file only on standard output and hands back what it could, so
the file is checked before it is read: the "CASCADE Topology" header, the ``TShapes N`` table with N
shape records, and the closing root reference (in files saved by OCCT's Draw, followed by its "0"
line). After the read, the distinct faces and solids of the shape are counted against the file's face
(``Fa``) and solid (``So``) records. BREP files carry no length unit; their lengths are taken as
millimetres, like in-memory shapes.
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
# The root reference ends the file; a shape saved by OCCT's Draw (``save``, the DBRep_DrawableShape
# header) is followed by one more line, "0", that the reader does not need.
_ROOT = re.compile(rb"[+\-]\d+ \d+\s*(?:\n0\s*)?$")


def sniff(path: Path, given: str) -> tuple[int, int]:
    """(face records, solid records) of a complete ASCII BREP file; InputError otherwise."""
    head, _, _ = sniff_path(path, given)
    if not _HEADER.match(head):
        if b"Open CASCADE Topology" in head[:64]:
            raise InputError(f"{given}: binary BREP files are not supported; write ASCII BREP (BRepTools::Write)")
        raise InputError(f"{given}: not an OCCT BREP file (no 'CASCADE Topology' header)")
    data = path.read_bytes()
    table = _TSHAPES.search(data)
    if table is None:
        raise InputError(f"{given}: truncated or corrupt BREP file (no TShapes table)")
    records = _RECORD.findall(data, table.end())
    declared = int(table.group(1))
    if len(records) != declared:
        raise InputError(f"{given}: truncated BREP file (its TShapes table declares {declared} shapes, the file "
                         f"holds {len(records)})")
    if not _ROOT.search(data[-64:]):
        raise InputError(f"{given}: truncated BREP file (it ends without the root shape reference)")
    return records.count(b"Fa"), records.count(b"So")


def read_brep(path: Path, given: str, *, allow_partial: bool = False) -> LoadedShape:
    """Read an ASCII BREP file; InputError for bad, empty or (unless allowed) partial files."""
    from .reader import quiet_occt

    faces, solids = sniff(path, given)
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
    return accept(LoadedShape(shape=shape, source=path.name, units="mm"), done, given, "BREP", allow_partial)
