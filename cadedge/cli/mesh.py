"""``cadedge mesh INPUT --ald EPS -o OUT``: surface mesh by gmsh on the edge grids, then the check.

OUT's suffix picks the format: ``.msh``, ``.stl``, ``.vtk`` (the mesh) or ``.geo`` (spacing export plus a
``.brep`` beside it, not meshed). On a terminal, a status line on stderr says what it is doing while it
works (seconds so far, the step, faces meshed) and is cleared before anything is printed. Prints the
watertight/conforming check; exit 0 when every face meshed and the check passed, 1 otherwise (failed
faces, a gmsh crash or timeout: a short summary on stderr, every line naming INPUT as typed;
``--verbose`` for every attempt), 2 on bad input.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import threading
import time
import warnings
from pathlib import Path
from typing import IO, Any

from ..errors import CadedgeError, CadedgeWarning, InputError
from . import _interrupted, debug_traceback, stopped, without_name
from .refine import add_refine_options, check_writable, parse_number, refine_options


def register(subparsers: Any) -> None:
    from ..mesh import DEFAULT_GROWTH, MESH_MAX_GROWTH, MODES
    from ..mesh.isolate import DEFAULT_TIMEOUT

    p = subparsers.add_parser(
        "mesh", help="surface mesh (gmsh) on the edge grids, with a watertight check",
        description="Refine every edge of INPUT, impose the edge grids on gmsh's curves and mesh every face "
                    "(faces sharing an edge share its nodes); print the watertight/conforming check. "
                    "OUT: .msh .stl .vtk, or .geo for the spacing export (with a .brep beside it).",
        epilog=f"For meshing, --max-growth defaults to {MESH_MAX_GROWTH} (graded edge grids avoid slivers "
               "next to finely split edges). gmsh runs in a separate process: a crash or hang costs that face "
               "or that run, never more. Exit 0 ok, 1 some face failed, gmsh crashed or timed out, or the "
               "check failed, 2 bad input.")
    p.add_argument("input", metavar="INPUT", help="STEP (.step/.stp), IGES (.igs/.iges) or OCCT BREP (.brep) file")
    add_refine_options(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="output mesh (.msh .stl .vtk) or .geo")
    p.add_argument("--mode", choices=MODES, default="nodes",
                   help="nodes: impose the grid nodes on every curve (default); sizes: give gmsh only sizes")
    p.add_argument("--growth", metavar="G", default=str(DEFAULT_GROWTH),
                   help=f"interior size growth per unit distance from the edges (default {DEFAULT_GROWTH})")
    p.add_argument("--max-size", metavar="H", help="largest triangle size (default: --max-length, else the "
                                                   "largest edge spacing)")
    p.add_argument("--timeout", metavar="SECONDS", default=str(DEFAULT_TIMEOUT),
                   help=f"bound on the whole job, from reading INPUT on (default {DEFAULT_TIMEOUT:g}); one face "
                        "attempt gets a fifth of it, "
                        "and a face's triangle budget grows with it above the default")
    p.add_argument("--workers", metavar="N", help="gmsh processes meshing a large model's faces at once (default: "
                                                  "one per core; 1: all faces in one process)")
    p.add_argument("--surface-ald", metavar="S", help="every face's |area deficit| (1 - mesh area / B-rep area) "
                                                      "at most S (default: --ald)")
    p.add_argument("--report", metavar="JSON", help="write the per-face mesh report (surface type, triangles, "
                                                    "area deficit, min angle) as JSON")
    p.add_argument("--plot", metavar="FILE", help="also draw the mesh and the edge grids: .png (static) or .html "
                                                  "(interactive 3-D page, works offline)")
    p.add_argument("--quiet", action="store_true", help="print only problems (no status line)")
    p.add_argument("--verbose", action="store_true", help="every failed attempt of every face, every note and "
                   "every warning")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Mesh INPUT; every error or problem is one stderr line naming INPUT as the user typed it."""
    try:
        return _run(args)
    except InputError as exc:
        debug_traceback(args)
        _err(args.input, exc)
        return 2
    except CadedgeError as exc:  # a valid file our pipeline could not finish: not bad input
        debug_traceback(args)
        _err(args.input, exc)
        return 1
    except (KeyboardInterrupt, Exception) as exc:  # Ctrl-C or SIGTERM (native code may turn them into another
        if _interrupted(exc):                       # error), or a fault of ours on a valid file: one line, exit 1
            word, code = stopped(exc)               # (--debug: raise)
            print(f"cadedge mesh: {args.input}: {word}", file=sys.stderr)
            return code
        if getattr(args, "debug", False):
            raise
        _err(args.input, f"internal error: {type(exc).__name__}: {exc}")
        return 1


def _err(source: str, message: object) -> None:
    print(f"cadedge mesh: {source}: {without_name(source, str(message))}", file=sys.stderr)


def _run(args: argparse.Namespace) -> int:
    from ..mesh import MESH_MAX_GROWTH, mesh_shape

    source = args.input
    opts = refine_options(args, source)
    if opts["max_growth"] is None:
        opts["max_growth"] = MESH_MAX_GROWTH
    growth = parse_number("--growth", args.growth, source, low=0.0)
    max_size = parse_number("--max-size", args.max_size, source, low=0.0)
    timeout = parse_number("--timeout", args.timeout, source, low=0.0)
    surface_ald = parse_number("--surface-ald", args.surface_ald, source, low=0.0)
    workers = args.workers
    if workers is not None and not (workers.strip().isdigit() and int(workers) >= 1):
        raise InputError(f"{source}: --workers must be a whole number, 1 or more, got {workers!r}")
    out = Path(args.output)  # mesh_shape checks its suffix and folder before any work; these, too:
    for path in (args.output, args.report):
        if path:
            check_writable(path)
    if args.plot:
        from ..plot import check_plot_path
        check_plot_path(args.plot)
    status = StatusLine(stream=sys.stderr, enabled=False if args.quiet else None)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", CadedgeWarning)  # others keep their filters
            result = mesh_shape(args.input, output=out, mode=args.mode, growth=growth, max_size=max_size,
                                timeout=timeout, surface_ald=surface_ald,
                                workers=None if workers is None else int(workers),
                                allow_partial=args.allow_partial, progress=status, **opts)
    finally:
        status.close()
    if not args.quiet:
        for line in _summary(result, verbose=args.verbose):
            print(line)
    found = [str(w.message) if issubclass(w.category, CadedgeWarning) else f"{w.category.__name__}: {w.message}"
             for w in caught]
    found = list(dict.fromkeys([*result.grid.warnings, *found]))
    shown = found if args.verbose else found[:MAX_WARNING_LINES]
    for message in shown:
        _err(source, f"warning: {message}")
    if len(found) > len(shown):
        _err(source, f"warning: ... and {len(found) - len(shown)} more warnings (--verbose lists them)")
    if args.report and result.report is not None:
        result.report.write(args.report)
        if not args.quiet:
            print(f"wrote {args.report}")
    if args.plot and len(result.triangles):
        from ..plot import plot_mesh
        plot_mesh(result, args.plot)
        if not args.quiet:
            print(f"wrote {args.plot}")
    for problem in result.problems(verbose=args.verbose):
        _err(source, problem)
    return 0 if result.ok else 1


class StatusLine:
    """A ``progress(text)`` callback keeping one line on ``stream`` (``enabled=None``: only a terminal) with the
    seconds so far and what the job is doing, redrawn every :data:`REDRAW` seconds from a thread (a face may
    take a minute between two steps); :meth:`close` stops the thread and clears the line."""

    def __init__(self, *, stream: IO[str], enabled: bool | None = None):
        self.stream = stream
        self.enabled = stream.isatty() if enabled is None else enabled
        self.text, self.t0 = "", time.monotonic()
        self.stop = threading.Event()
        self.lock = threading.Lock()
        self.thread: threading.Thread | None = None

    def __call__(self, text: str) -> None:
        if not self.enabled:
            return
        with self.lock:
            self.text = text
        if self.thread is None:
            self.thread = threading.Thread(target=self._run, name="cadedge-status", daemon=True)
            self.thread.start()

    def _run(self) -> None:
        while True:
            self._draw()
            if self.stop.wait(REDRAW):
                return

    def _draw(self) -> None:
        width = max(shutil.get_terminal_size().columns - 1, 20)
        with self.lock:
            line = f"cadedge mesh: {time.monotonic() - self.t0:.0f} s: {self.text}"
            self.stream.write("\r\x1b[K" + line[:width])
            self.stream.flush()

    def close(self) -> None:
        if self.thread is not None:
            self.stop.set()
            self.thread.join()
            self.thread = None
            self.stream.write("\r\x1b[K")
            self.stream.flush()


#: Seconds between redraws of the status line.
REDRAW = 0.25


#: Warnings (from reading and refining) shown without ``--verbose``; the rest is counted.
MAX_WARNING_LINES = 3


#: Shells listed one by one up to this many (an assembly may have hundreds).
MAX_SHELL_LINES = 8


def _summary(result: Any, *, verbose: bool) -> list[str]:
    """The printed report: head, check (shells capped unless verbose), faces meshed, notes, what was written."""
    lines = result.lines()[: len(result.lines()) - len(result.problems())]
    shells = [ln for ln in lines if ln.startswith("  shell ")]
    if len(shells) > MAX_SHELL_LINES and not verbose:
        first = lines.index(shells[0])
        lines = lines[:first + MAX_SHELL_LINES] + [f"  ... {len(shells) - MAX_SHELL_LINES} more shells"] + \
            lines[first + len(shells):]
    if result.faces:
        ok = [o for o in result.faces if o.ok]
        fallback = [o for o in ok if o.attempts]
        lines.append(f"faces meshed: {len(ok)}/{len(result.faces)}"
                     + (f" ({len(fallback)} by a fallback strategy)" if fallback else ""))
    lines += [f"note: {n}" for n in result.notes + (result.details if verbose else [])]
    if result.output is not None:
        lines.append(f"wrote {result.output}" if result.check is not None else "")
    elif result.check is None or len(result.triangles) == 0:
        lines.append("nothing meshed: no output written")
    return [ln for ln in lines if ln]
