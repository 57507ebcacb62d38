"""OCCT's STEP, IGES and BREP reads run outside the caller, so that an OCCT crash cannot take it down.

OCCT crashes (segmentation fault) on some malformed files: in the transfer of files with unresolved
references (a file cut short with a trailer appended), but also of files its load check passes, such
as a ``LINE`` whose vector attribute names a ``DIRECTION`` (a writer's slip), and in its entities'
own accessors (an ``ORIENTED_CLOSED_SHELL`` whose shell did not resolve), and in its BREP reader (a curve
record of a type it does not know). So a STEP, IGES or BREP file is
read, checked and transferred in another process (:func:`run_isolated`), which hands the shape back as
an OCCT BREP file with the completeness, units and warnings as JSON. It notes how far it got (parsed;
parsed, but damaged or cut short by the load check's account), so that a crash, a hang past
``TIMEOUT`` or any other death of it becomes one :class:`~cadedge.errors.InputError` naming the file
and saying what OCCT was doing.

On Linux the process is a fork of this one (0.01-0.1 s a file: the fork and the BREP round trip);
elsewhere a new child, ``python -m cadedge.occt.isolate`` (about 1 s: a new interpreter). The fork runs
only OCCT's reader, the BREP writer and a JSON dump, so the locks other threads may hold when it is
made (a batch worker's event loop, a notebook's kernel) are not ones it takes.

The child ends with its caller (:mod:`cadedge.childproc`).
"""

from __future__ import annotations

import faulthandler
import json
import os
import select
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
#: A transfer run isolated: called with a function that records how far it got (see :data:`_CRASHES`).
Transfer = Callable[[Callable[[str], None]], Transferred]
#: How a crash is put, by the last stage the child noted (``{kind}`` STEP, IGES or BREP, ``{how}`` the
#: signal).
_CRASHES = {
    "": "corrupt {kind} file: OCCT crashed reading it ({how})",
    "parsed": "malformed {kind} file: OCCT crashed transferring it ({how}), though its load check found "
              "nothing wrong",
    "damaged": "damaged {kind} file: OCCT crashed transferring it ({how}); it refers to entities it does not "
               "define, or holds unreadable ones",
    "cut": "damaged {kind} file: OCCT crashed transferring it ({how}); it is cut short (its last entity is "
           "incomplete)",
}


def can_fork() -> bool:
    """Whether :func:`run_isolated` forks: on Linux (macOS's system libraries are not safe to use in a
    fork that does not exec; Windows cannot fork)."""
    return sys.platform.startswith("linux") and hasattr(os, "fork")


def run_isolated(kind: str, path: Path, given: str, transfer: Transfer) -> Transferred:
    """``transfer(note)``, the reading of ``path`` as ``kind`` (STEP, IGES or BREP), run in a fork of this
    process or a new child (see the module doc); InputError naming ``given`` if that process dies."""
    with tempfile.TemporaryDirectory(prefix="cadedge-") as tmp:
        folder = Path(tmp)
        status = _in_fork(transfer, folder, given) if can_fork() else _in_child(kind, path, given, folder)
        stage = (folder / "stage").read_text() if (folder / "stage").is_file() else ""
        if status is None:
            raise InputError(f"{given}: OCCT did not finish reading the {kind} file within {TIMEOUT:g} s")
        if status != 0 or not (folder / "result.json").is_file():
            raise InputError(f"{given}: " + _CRASHES[stage].format(kind=kind, how=_how(status)))
        return _result(folder, given)


def _in_fork(transfer: Transfer, folder: Path, given: str) -> int | None:
    """Run ``transfer`` in a fork of this process, its result left in ``folder``: its exit status (see
    :func:`_wait`)."""
    parent = os.getpid()
    sys.stdout.flush()
    sys.stderr.flush()
    with warnings.catch_warnings():  # Python 3.12+ warns of forking beside other threads (see the module doc)
        warnings.simplefilter("ignore", DeprecationWarning)
        pid = os.fork()
    if pid == 0:  # the child: never returns, never runs the caller's exit handlers
        code = 1
        try:
            os.environ[PARENT_ENV] = str(parent)
            die_with_parent()
            _silence()
            _write(transfer, folder, given)
            code = 0
        finally:
            os._exit(code)
    return _wait(pid)


def _in_child(kind: str, path: Path, given: str, folder: Path) -> int | None:
    """Run :func:`main` in a new child process, its result left in ``folder``: its exit status, None if
    it was killed at :data:`TIMEOUT`."""
    cmd = [sys.executable, "-m", "cadedge.occt.isolate", kind, os.fspath(path), given, os.fspath(folder)]
    try:
        return subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              timeout=TIMEOUT, env=child_env()).returncode
    except subprocess.TimeoutExpired:
        return None


def _silence() -> None:
    """Send the fork's console output nowhere, as the new child's is: OCCT's complaints, and a crash
    report of Python's ``faulthandler`` where the caller enabled it."""
    faulthandler.disable()
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)


def _wait(pid: int) -> int | None:
    """The exit status of child ``pid`` (negative: the signal that ended it); None, the child killed,
    after :data:`TIMEOUT` seconds. The child is killed too if the wait is interrupted (Ctrl-C)."""
    ended = False
    try:
        ended = _exited(pid, TIMEOUT)
    finally:
        if not ended:
            os.kill(pid, signal.SIGKILL)
        status = os.waitpid(pid, 0)[1]
    return os.waitstatus_to_exitcode(status) if ended else None


def _exited(pid: int, timeout: float) -> bool:
    """Whether child ``pid`` ended within ``timeout`` seconds (it is not reaped here): woken by a pidfd
    where the kernel has them (Linux 5.3), else polled, first every millisecond."""
    try:
        fd = os.pidfd_open(pid)
    except (AttributeError, OSError):
        fd = None
    if fd is not None:
        try:
            return bool(select.select([fd], [], [], timeout)[0])
        finally:
            os.close(fd)
    deadline, pause = time.monotonic() + timeout, 0.001
    while os.waitid(os.P_PID, pid, os.WEXITED | os.WNOHANG | os.WNOWAIT) is None:
        if time.monotonic() > deadline:
            return False
        time.sleep(pause)
        pause = min(2 * pause, 0.05)
    return True


def _how(code: int) -> str:
    return f"signal {signal.Signals(-code).name}" if code < 0 else f"exit code {code}"


def _write(transfer: Transfer, out: Path, given: str) -> None:
    """Run ``transfer`` and leave in folder ``out`` how far it got (``stage``) and its result:
    ``shape.brep`` and ``result.json`` (a CadedgeError as its type and message; any other exception as
    an OCCT failure)."""
    def note(stage: str) -> None:
        (out / "stage").write_text(stage)

    try:
        t = transfer(note)
    except CadedgeError as exc:
        doc = {"error": {"type": type(exc).__name__, "message": str(exc)}}
    except Exception as exc:  # an OCCT exception (compat.OCCT_ERRORS), or a bug of ours
        doc = {"error": {"type": "GeometryError", "message": f"{given}: OCCT failed to read the file: "
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
    """The new child: read ``argv = [kind, path, given, folder]``, leaving its result in the folder."""
    die_with_parent()
    kind, path, given, folder = argv
    if kind == "STEP":
        from .step import transfer_step as read
    elif kind == "IGES":
        from .iges import transfer_iges as read
    else:
        from .brep import transfer_brep as read
    _write(lambda note: read(Path(path), given, isolate=False, note=note), Path(folder), given)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
