"""Transfer a damaged file in a child process, so that an OCCT crash cannot take down the caller.

OCCT's STEP and IGES transfers have been seen to crash (segmentation fault) on files with unresolved
references, such as a file cut short with a trailer appended. The readers send only such files here
(see :func:`cadedge.occt.loading.damaged`): the child (``python -m cadedge.occt.isolate``) reads and
transfers the file and hands the shape back as an OCCT BREP file, with the completeness, units and
warnings as JSON. A crash, a hang past ``TIMEOUT`` or any other death of the child becomes one
:class:`~cadedge.errors.InputError` naming the file; the child ends with its caller (:mod:`cadedge.childproc`).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
from dataclasses import asdict
from pathlib import Path

from OCP.BRep import BRep_Builder
from OCP.BRepTools import BRepTools
from OCP.TopoDS import TopoDS_Shape

from ..childproc import child_env, die_with_parent
from ..errors import CadedgeError, GeometryError, InputError
from .loading import Completeness, Transferred, quiet_occt

#: Seconds the child may take to read and transfer one file.
TIMEOUT = 600.0
_ERRORS = {"InputError": InputError, "GeometryError": GeometryError}


def _transfer(kind: str, path: Path, given: str) -> Transferred:
    if kind == "STEP":
        from .step import transfer_step
        return transfer_step(path, given, isolate=False)
    from .iges import transfer_iges
    return transfer_iges(path, given, isolate=False)


def isolated(kind: str, path: Path, given: str, *, cut: bool = False) -> Transferred:
    """``transfer_step``/``transfer_iges`` of ``path`` run in a child process; InputError if it dies."""
    with tempfile.TemporaryDirectory(prefix="cadedge-") as tmp:
        cmd = [sys.executable, "-m", "cadedge.occt.isolate", kind, os.fspath(path), given, tmp]
        env = child_env()
        try:
            proc = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL, timeout=TIMEOUT, env=env)
        except subprocess.TimeoutExpired:
            raise InputError(f"{given}: damaged {kind} file: OCCT did not finish transferring it within "
                             f"{TIMEOUT:g} s") from None
        result = Path(tmp) / "result.json"
        if proc.returncode != 0 or not result.is_file():
            code = proc.returncode
            how = f"signal {signal.Signals(-code).name}" if code < 0 else f"exit code {code}"
            why = "it is cut short (its last entity is incomplete)" if cut else \
                "it refers to entities it does not define, or holds unreadable ones"
            raise InputError(f"{given}: damaged {kind} file: OCCT crashed transferring it ({how}); {why}")
        doc = json.loads(result.read_text())
        if "error" in doc:
            raise _ERRORS.get(doc["error"]["type"], InputError)(doc["error"]["message"])
        shape = TopoDS_Shape()
        with quiet_occt():
            if not doc["null"] and not BRepTools.Read_s(shape, str(Path(tmp) / "shape.brep"), BRep_Builder()):
                raise GeometryError(f"{given}: the shape transferred in a child process could not be read back")
        done = doc["done"]
        completeness = Completeness(faces=_pair(done["faces"]), solids=_pair(done["solids"]),
                                    roots=_pair(done["roots"]), unresolved=done["unresolved"],
                                    truncated=done["truncated"], skipped=done["skipped"])
        return Transferred(shape=shape, done=completeness, units=doc["units"], warnings=doc["warnings"],
                           declared=doc["declared"])


def _pair(value: list[int] | None) -> tuple[int, int] | None:
    return None if value is None else (int(value[0]), int(value[1]))


def main(argv: list[str]) -> int:
    """The child: transfer ``argv = [kind, path, given, folder]``, write ``shape.brep`` and ``result.json``."""
    die_with_parent()
    kind, path, given, folder = argv
    out = Path(folder)
    try:
        t = _transfer(kind, Path(path), given)
    except CadedgeError as exc:
        doc = {"error": {"type": type(exc).__name__, "message": str(exc)}}
    else:
        if not t.shape.IsNull():
            with quiet_occt():
                BRepTools.Write_s(t.shape, str(out / "shape.brep"))
        doc = {"null": t.shape.IsNull(), "done": asdict(t.done), "units": t.units, "warnings": t.warnings, "declared": t.declared}
    (out / "result.json").write_text(json.dumps(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
