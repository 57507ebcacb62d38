"""OCCT's STEP and IGES transfers run outside the caller, so that an OCCT crash cannot take it down.

OCCT's transfer crashes (segmentation fault) on some malformed files: files with unresolved references
(a file cut short with a trailer appended), but also files its load check passes, such as a ``LINE``
whose vector attribute names a ``DIRECTION`` (a writer's slip; the transfer dereferences the missing
vector). Every transfer therefore runs in another process, which hands the shape back as an OCCT BREP
file with the completeness, units and warnings as JSON; a crash, a hang past ``TIMEOUT`` or any other
death of that process becomes one :class:`~cadedge.errors.InputError` naming the file.

- A file whose load check shows damage (:func:`cadedge.occt.loading.damaged`) is read and transferred
  again in a new child (``python -m cadedge.occt.isolate``, :func:`isolated`).
- Any other file is parsed here and transferred in a fork of this process (:func:`in_fork`): the
  parsed model is already there, so it costs the fork and the BREP round trip (0.02-0.1 s), not a new
  interpreter (about 1 s a file). The fork runs only OCCT's transfer, the BREP writer and a JSON dump,
  so the locks other threads may hold at the fork (a batch worker's event loop, a notebook's kernel)
  are not ones it takes. Off Linux the new child is used.

The child ends with its caller (:mod:`cadedge.childproc`).
"""

from __future__ import annotations

import faulthandler
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from dataclasses import asdict
from pathlib import Path
from typing import Callable

from OCP.BRep import BRep_Builder
from OCP.BRepTools import BRepTools
from OCP.TopoDS import TopoDS_Shape

from ..childproc import PARENT_ENV, child_env, die_with_parent
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


def isolated(kind: str, path: Path, given: str, *, cut: bool = False, damaged: bool = True) -> Transferred:
    """``transfer_step``/``transfer_iges`` of ``path`` run in a new child process; InputError if it dies
    (saying why the file is suspect: ``cut`` short, ``damaged`` by the load check's account, or neither)."""
    with tempfile.TemporaryDirectory(prefix="cadedge-") as tmp:
        cmd = [sys.executable, "-m", "cadedge.occt.isolate", kind, os.fspath(path), given, tmp]
        env = child_env()
        try:
            proc = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL, timeout=TIMEOUT, env=env)
        except subprocess.TimeoutExpired:
            raise InputError(f"{given}: damaged {kind} file: OCCT did not finish transferring it within "
                             f"{TIMEOUT:g} s") from None
        if proc.returncode != 0 or not (Path(tmp) / "result.json").is_file():
            if not damaged:
                raise _crashed(kind, given, proc.returncode)
            why = "it is cut short (its last entity is incomplete)" if cut else \
                "it refers to entities it does not define, or holds unreadable ones"
            raise InputError(f"{given}: damaged {kind} file: OCCT crashed transferring it "
                             f"({_how(proc.returncode)}); {why}")
        return _result(Path(tmp), given)


def _crashed(kind: str, given: str, code: int) -> InputError:
    return InputError(f"{given}: malformed {kind} file: OCCT crashed transferring it ({_how(code)}), though "
                      "its load check found nothing wrong")


def can_fork() -> bool:
    """Whether :func:`in_fork` may fork here: on Linux (macOS's system libraries are not safe to use in
    a fork that does not exec; Windows cannot fork)."""
    return sys.platform.startswith("linux") and hasattr(os, "fork")


def in_fork(transfer: Callable[[], Transferred], kind: str, given: str) -> Transferred:
    """``transfer()`` (the rest of a transfer whose file this process has parsed) run in a fork of this
    process (see the module doc; the caller checks :func:`can_fork`); InputError if the fork dies."""
    with tempfile.TemporaryDirectory(prefix="cadedge-") as tmp:
        parent = os.getpid()
        sys.stdout.flush()
        sys.stderr.flush()
        with warnings.catch_warnings():  # Python 3.12+ warns of forking beside other threads (see below)
            warnings.simplefilter("ignore", DeprecationWarning)
            pid = os.fork()
        if pid == 0:  # the child: never returns, never runs the caller's exit handlers
            code = 1
            try:
                os.environ[PARENT_ENV] = str(parent)
                die_with_parent()
                _silence()
                _write(transfer, Path(tmp), given)
                code = 0
            finally:
                os._exit(code)
        status = _wait(pid)
        if status is None:
            raise InputError(f"{given}: OCCT did not finish transferring the {kind} file within {TIMEOUT:g} s")
        if status != 0 or not (Path(tmp) / "result.json").is_file():
            raise _crashed(kind, given, status)
        return _result(Path(tmp), given)


def _silence() -> None:
    """Send the fork's console output nowhere, as the new child's is: OCCT's complaints, and a crash
    report of Python's ``faulthandler`` where the caller enabled it."""
    faulthandler.disable()
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)


def _wait(pid: int) -> int | None:
    """The exit status of child ``pid`` (negative: the signal that ended it); None, the child killed,
    after :data:`TIMEOUT` seconds. Polled, first every millisecond: most transfers take a few."""
    deadline, pause = time.monotonic() + TIMEOUT, 0.001
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            return os.waitstatus_to_exitcode(status)
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            return None
        time.sleep(pause)
        pause = min(2 * pause, 0.05)


def _how(code: int) -> str:
    return f"signal {signal.Signals(-code).name}" if code < 0 else f"exit code {code}"


def _write(transfer: Callable[[], Transferred], out: Path, given: str) -> None:
    """Run ``transfer`` and leave its result in folder ``out``: ``shape.brep`` and ``result.json`` (a
    CadedgeError as its type and message; any other exception as an OCCT failure)."""
    try:
        t = transfer()
    except CadedgeError as exc:
        doc = {"error": {"type": type(exc).__name__, "message": str(exc)}}
    except Exception as exc:  # an OCCT exception OCP did not turn into Standard_Failure, a bug of ours
        doc = {"error": {"type": "GeometryError", "message": f"{given}: OCCT failed to transfer the file: "
                                                            f"{type(exc).__name__}: {exc}"}}
    else:
        if not t.shape.IsNull():
            with quiet_occt():
                BRepTools.Write_s(t.shape, str(out / "shape.brep"))
        doc = {"null": t.shape.IsNull(), "done": asdict(t.done), "units": t.units, "warnings": t.warnings,
               "declared": t.declared}
    (out / "result.json").write_text(json.dumps(doc))


def _result(folder: Path, given: str) -> Transferred:
    """The transfer a child left in ``folder`` (see :func:`_write`); its error raised here."""
    doc = json.loads((folder / "result.json").read_text())
    if "error" in doc:
        raise _ERRORS.get(doc["error"]["type"], InputError)(doc["error"]["message"])
    shape = TopoDS_Shape()
    with quiet_occt():
        if not doc["null"] and not BRepTools.Read_s(shape, str(folder / "shape.brep"), BRep_Builder()):
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
    _write(lambda: _transfer(kind, Path(path), given), Path(folder), given)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
