"""``cadedge refine INPUT --ald EPS -o OUT``: refine every edge of a STEP, IGES or BREP file and write the grids.

Arguments are checked (numbers, output suffix, output folder, plot name) before the model is read,
so a typo costs nothing. A progress bar (tqdm, stderr) appears for models with more than
``PROGRESS_MIN_EDGES`` edges when stderr is a terminal; ``--quiet`` silences it and the summary.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import warnings
from collections import defaultdict
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from ..errors import CadedgeWarning, InputError
from ..options import MIN_ALD, MIN_ALD_TEXT
from ._table import format_table

if TYPE_CHECKING:
    from ..shapegrid import ShapeGrid

PROGRESS_MIN_EDGES = 50
MAX_WARNINGS = 20


def add_refine_options(parser: argparse.ArgumentParser) -> None:
    """The refinement options shared by the subcommands that refine (values checked by :func:`refine_options`)."""
    parser.add_argument("--ald", default="1e-3", metavar="EPS",
                        help=f"target arc-length deficit per edge, {MIN_ALD_TEXT} <= EPS < 1 (smaller targets are "
                             "below what double precision resolves; default 1e-3)")
    parser.add_argument("--min-length", metavar="L", help="shortest segment allowed (model units)")
    parser.add_argument("--max-length", metavar="L", help="longest segment allowed (model units)")
    parser.add_argument("--max-growth", metavar="G", help="largest ratio of adjacent segment lengths, > 1")
    parser.add_argument("--allow-partial", action="store_true",
                        help="refine what a partial transfer did load (with a warning saying what was lost) "
                             "instead of refusing the file")


def parse_number(name: str, text: str | None, source: str, *, low: float, high: float = math.inf,
            inclusive_low: bool = False) -> float | None:
    """``text`` as a number above ``low`` (and below ``high``), or None; InputError naming ``source``."""
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{source}: {name} must be a number, got {text!r}") from None
    ok = math.isfinite(value) and (value >= low if inclusive_low else value > low) and value < high
    if not ok:
        bounds = f"greater than {low:g}" + (f" and less than {high:g}" if math.isfinite(high) else "")
        raise InputError(f"{source}: {name} must be {bounds}, got {text!r}")
    return value


def refine_options(args: argparse.Namespace, source: str) -> dict[str, float | None]:
    """The keyword arguments of :func:`cadedge.refine_shape` from parsed options; InputError naming ``source``."""
    opts = {"ald": parse_number("--ald", args.ald, source, low=0.0, high=1.0),
            "min_length": parse_number("--min-length", args.min_length, source, low=0.0),
            "max_length": parse_number("--max-length", args.max_length, source, low=0.0),
            "max_growth": parse_number("--max-growth", args.max_growth, source, low=1.0)}
    if opts["ald"] < MIN_ALD:
        raise InputError(f"{source}: --ald {args.ald} is below {MIN_ALD_TEXT}, the smallest target double "
                         "precision can resolve")
    if opts["min_length"] is not None and opts["max_length"] is not None and opts["min_length"] > opts["max_length"]:
        raise InputError(f"{source}: --min-length {args.min_length} exceeds --max-length {args.max_length}")
    return opts


def local_alds(args: argparse.Namespace, source: str) -> dict[tuple[str, int], float]:
    """``--ald-edge ID=EPS`` and ``--ald-face ID=EPS`` as :func:`cadedge.refine_shape`'s ``ald_for``
    (an id named twice keeps its finest EPS); InputError naming ``source`` for a malformed one. EPS is
    checked by the library's own check of ``ald``, so the bounds are the API's."""
    from ..options import refine_options as check_ald

    out: dict[tuple[str, int], float] = {}
    for kind, flag, items in (("edge", "--ald-edge", args.ald_edge), ("face", "--ald-face", args.ald_face)):
        for text in items:
            ident, sep, eps = text.partition("=")
            ident = ident.strip()
            if not (sep and ident.isascii() and ident.isdigit() and int(ident) >= 1):
                raise InputError(f"{source}: {flag} expects ID=EPS, ID a positive {kind} id (as listed by "
                                 f"cadedge info), got {text!r}")
            try:
                value = check_ald(eps)["ald"]
            except InputError as exc:
                raise InputError(f"{source}: {flag} {ident}: {exc}") from None
            key = (kind, int(ident))
            out[key] = min(out.get(key, value), value)
    return out


def check_output(path: str) -> str:
    """The exporter suffix of ``path``; InputError if unsupported or its folder is missing."""
    from ..exporters import suffix_of

    suffix = suffix_of(path)
    check_writable(path)
    return suffix


def check_writable(path: str) -> None:
    """InputError, before any work, if ``path`` is an existing folder or its folder is missing."""
    if Path(path).is_dir():
        raise InputError(f"{path}: is a folder; give a file name")
    folder = Path(path).parent
    if str(folder) and not folder.is_dir():
        raise InputError(f"{path}: folder {os.fspath(folder)!r} does not exist")


def print_warnings(command: str, source: str, messages: list[str], *, stream: IO[str] | None = None) -> None:
    """Each distinct message as ``cadedge COMMAND: SOURCE: warning: ...`` (``source`` as the user typed it),
    at most ``MAX_WARNINGS``, then a count."""
    stream = sys.stderr if stream is None else stream
    messages = list(dict.fromkeys(messages))
    for message in messages[:MAX_WARNINGS]:
        print(f"cadedge {command}: {source}: warning: {message}", file=stream)
    if len(messages) > MAX_WARNINGS:
        print(f"cadedge {command}: {source}: warning: ... and {len(messages) - MAX_WARNINGS} more warnings (the "
              "Python API returns them all, e.g. ShapeGrid.warnings)", file=stream)


class Progress:
    """A ``progress(done, total)`` callback drawing a tqdm bar once ``total`` exceeds ``min_total``.

    ``enabled=None`` means: only when ``stream`` is a terminal.
    """

    def __init__(self, *, stream: IO[str], enabled: bool | None = None, min_total: int = PROGRESS_MIN_EDGES,
                 desc: str = "edges"):
        self.stream, self.min_total, self.desc = stream, min_total, desc
        self.enabled = stream.isatty() if enabled is None else enabled
        self.bar: Any = None

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled or total <= self.min_total:
            return
        if self.bar is None:
            from tqdm import tqdm
            self.bar = tqdm(total=total, desc=self.desc, unit="edge", file=self.stream, leave=False,
                            dynamic_ncols=True)
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def summary_table(grid: ShapeGrid) -> str:
    """Edges by curve type (count, segments, worst ALD estimate) and the totals."""
    groups: dict[str, list] = defaultdict(list)
    for e in grid.edges:
        groups["(degenerate)" if e.degenerate else e.curve].append(e)
    order = sorted(groups, key=lambda k: (k == "(degenerate)", -len(groups[k]), k))

    def worst(edges: list) -> str:
        vals = [e.ald_estimate for e in edges if not e.degenerate]
        return f"{max(vals):.3g}" if vals else "-"

    rows = [[k, len(groups[k]), sum(e.segments for e in groups[k]), worst(groups[k])] for k in order]
    rows.append(["total", len(grid.edges), grid.segments, worst(grid.edges)])
    return format_table(["curve", "edges", "segments", "worst ALD"], rows, right=[False, True, True, True])


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("refine", help="edge grids of a STEP, IGES or BREP file",
                              description="Refine every edge of INPUT to the arc-length deficit EPS and write "
                                          "the grids; the format comes from OUT's suffix "
                                          "(.json .csv .vtp .vtu .vtk .msh .geo .obj .ply).")
    p.add_argument("input", metavar="INPUT", help="STEP (.step/.stp), IGES (.igs/.iges) or OCCT BREP (.brep) file")
    add_refine_options(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="output file")
    p.add_argument("--ald-edge", action="append", default=[], metavar="ID=EPS",
                   help="own target for edge ID (ids as in cadedge info); repeatable; the finest target wins")
    p.add_argument("--ald-face", action="append", default=[], metavar="ID=EPS",
                   help="own target for every edge of face ID; repeatable; the finest target wins")
    p.add_argument("--plot", metavar="FILE", help="also draw the grids: .png (static) or .html (interactive "
                                                  "3-D page, works offline)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import cadedge
    from ..exporters import write

    source = args.input
    opts = refine_options(args, source)
    local = local_alds(args, source)
    check_output(args.output)
    if args.plot:
        from ..plot import check_plot_path
        check_plot_path(args.plot)
    from ._startup import heavy_imports
    with heavy_imports():
        from ..occt import shape  # noqa: F401 - OCP and numpy, which cadedge.refine_shape imports on first use
    progress = Progress(stream=sys.stderr, enabled=False if args.quiet else None)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", CadedgeWarning)  # others keep their filters
            grid = cadedge.refine_shape(args.input, **opts, ald_for=local or None, progress=progress,
                                        allow_partial=args.allow_partial)
    finally:
        progress.close()
    for w in caught:  # pass on what is not ours (library deprecations etc.) untouched
        if not issubclass(w.category, CadedgeWarning):
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    ours = [str(w.message) for w in caught if issubclass(w.category, CadedgeWarning)]
    print_warnings("refine", source, [*grid.warnings, *ours])
    write(grid, args.output)
    if args.plot:
        from ..plot import plot_grid
        plot_grid(grid, args.plot)
    if not args.quiet:
        print(summary_table(grid))
        wrote = args.output + (f" and {args.plot}" if args.plot else "")
        print(f"{grid.source}: {len(grid.edges)} edges, {grid.segments} segments, "
              f"{grid.seconds:.2f} s; wrote {wrote}")
    return 0
