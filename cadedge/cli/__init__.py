"""The ``cadedge`` command line: a thin shell over the API.

``main(argv)`` is testable in-process. Each subcommand lives in its own module with
``register(subparsers)``, which adds its parser and sets ``func(args) -> int``. Library errors become
one line on stderr naming the file and the reason, with exit code 2 (bad input or usage); ``--debug``
shows the traceback instead. Ctrl-C ends with one "interrupted" line (exit 130), also when native code
turned it into another error; SIGTERM (``kill``, ``timeout``, a job scheduler) while a command runs is
handled the same way, with a "terminated" line and exit 143 (:class:`Terminated`); a closed stdout pipe
(``cadedge info x | head``) ends quietly with exit 141, as a process killed by SIGPIPE.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from typing import Iterator, Sequence

from ..errors import CadedgeError

SUBCOMMANDS = ("refine", "info", "mesh", "batch")


class Terminated(KeyboardInterrupt):
    """SIGTERM received while a command ran. A KeyboardInterrupt, so it takes Ctrl-C's way out: gmsh and
    OCCT children are killed, no output is half-written, batch closes its cluster."""


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The parser; given ``argv`` that names a subcommand, only that subcommand's module is imported
    (each imports what it needs, so ``cadedge info`` never loads numpy, gmsh or dask)."""
    import importlib

    parser = argparse.ArgumentParser(prog="cadedge", description="Edge grids for CAD models by arc-length deficit.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    parser.add_argument("--version", action="version", version=f"cadedge {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    words = [a for a in (argv or ()) if not a.startswith("-")]
    names = words[:1] if words and words[0] in SUBCOMMANDS else SUBCOMMANDS
    for name in names:
        importlib.import_module(f"{__name__}.{name}").register(sub)
    return parser


def _version() -> str:
    from .. import __version__
    return __version__


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code (0 ok, 1 some inputs failed, 2 bad input or usage)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(argv)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse exits 2 on usage errors, 0 on --help
        return int(exc.code or 0)
    try:
        with _sigterm_as_interrupt():
            code = int(args.func(args))
        sys.stdout.flush()
        return code
    except BrokenPipeError:  # stdout's reader went away (``cadedge info x | head``): stop quietly, as on SIGPIPE
        _stdout_to_devnull()
        return 141
    except CadedgeError as exc:
        debug_traceback(args)
        message, given = str(exc), getattr(args, "input", None)
        if isinstance(given, str) and without_name(given, message) != message:  # named: as the user typed it
            message = f"{given}: {without_name(given, message)}"
        print(f"cadedge {args.command}: error: {message}", file=sys.stderr)
        return 2
    except (KeyboardInterrupt, Exception) as exc:  # Ctrl-C, SIGTERM (native code may turn them into another error)
        if isinstance(exc, Exception) and (args.debug or not _interrupted(exc)):
            raise
        word, code = stopped(exc)
        print(f"cadedge {args.command}: {word}", file=sys.stderr)
        return code


@contextlib.contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """While a command runs, SIGTERM raises :class:`Terminated` instead of ending the process on the spot
    (which left no line, and a gmsh child to die by its parent-death signal). Only in the main thread and
    where SIGTERM has its default action: a program calling ``main`` that handles SIGTERM keeps its handler."""
    import signal

    def stop(signum: int, frame: object) -> None:
        raise Terminated

    try:
        if signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
            yield
            return
        previous = signal.signal(signal.SIGTERM, stop)
    except ValueError:  # not the main thread: no handlers to set
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def stopped(exc: BaseException) -> tuple[str, int]:
    """The word and exit code for a run ended by Ctrl-C (``interrupted``, 130) or SIGTERM (``terminated``,
    143), given the KeyboardInterrupt or the error native code turned it into."""
    return ("terminated", 143) if _interrupted(exc, Terminated) else ("interrupted", 130)


def without_name(given: str, message: str) -> str:
    """``message`` without its leading ``FILE: `` where FILE is the input as typed or its base name (the
    library names a file by its base name, the ``source`` of its results, once it is read)."""
    import os

    for prefix in (f"{given}: ", f"{os.path.basename(given)}: "):
        if message.startswith(prefix):
            return message[len(prefix):]
    return message


def debug_traceback(args: argparse.Namespace) -> None:
    """With ``--debug``, the traceback of the error being handled."""
    if getattr(args, "debug", False):
        import traceback  # only here: every command's start-up would pay for it

        traceback.print_exc()


def _interrupted(exc: BaseException, kind: type[BaseException] = KeyboardInterrupt) -> bool:
    """Whether a ``kind`` (Ctrl-C's KeyboardInterrupt by default) caused ``exc``: native code turns a
    KeyboardInterrupt raised inside it into another error (an extension module interrupted while loading:
    "ImportError: initialization failed")."""
    seen: set[int] = set()
    cause: BaseException | None = exc
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, kind):
            return True
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    return False


def _stdout_to_devnull() -> None:
    """Point the process's stdout at /dev/null, so the interpreter's last flush does not fail again."""
    import os

    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # not a real file (in-process tests): nothing to flush
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def entry() -> None:  # pragma: no cover - console-script shim
    from ._startup import own_process

    own_process()
    sys.exit(main())
