"""``cadedge refine INPUT --ald EPS -o OUT``: refine every edge of a STEP file and write the grids.

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
from ._table import format_table

if TYPE_CHECKING:
    from ..shapegrid import ShapeGrid

PROGRESS_MIN_EDGES = 50
MAX_WARNINGS = 20


def add_refine_options(parser: argparse.ArgumentParser) -> None:
    """The refinement options shared by the subcommands that refine (values checked by :func:`refine_options`)."""
    parser.add_argument("--ald", default="1e-3", metavar="EPS",
                        help="target arc-length deficit per edge, 0 < EPS < 1 (default 1e-3)")
    parser.add_argument("--min-length", metavar="L", help="shortest segment allowed (model units)")
    parser.add_argument("--max-length", metavar="L", help="longest segment allowed (model units)")
    parser.add_argument("--max-growth", metavar="G", help="largest ratio of adjacent segment lengths, > 1")


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
    if opts["min_length"] is not None and opts["max_length"] is not None and opts["min_length"] > opts["max_length"]:
        raise InputError(f"{source}: --min-length {args.min_length} exceeds --max-length {args.max_length}")
    return opts


def check_output(path: str) -> str:
    """The exporter suffix of ``path``; InputError if unsupported or its folder is missing."""
    from ..exporters import suffix_of

    suffix = suffix_of(path)
    folder = Path(path).parent
    if str(folder) and not folder.is_dir():
        raise InputError(f"{path}: folder {os.fspath(folder)!r} does not exist")
    return suffix


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
    p = subparsers.add_parser("refine", help="edge grids of a STEP file",
                              description="Refine every edge of INPUT to the arc-length deficit EPS and write "
                                          "the grids; the format comes from OUT's suffix "
                                          "(.json .csv .vtp .msh .geo .obj .ply).")
    p.add_argument("input", metavar="INPUT", help="STEP file (.step/.stp)")
    add_refine_options(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="output file")
    p.add_argument("--plot", metavar="PNG", help="also draw the grids to this PNG")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import cadedge
    from ..exporters import write

    source = os.path.basename(args.input) or args.input
    opts = refine_options(args, source)
    check_output(args.output)
    if args.plot:
        from ..plot import check_plot_path
        check_plot_path(args.plot)
    progress = Progress(stream=sys.stderr, enabled=False if args.quiet else None)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", CadedgeWarning)  # others keep their filters
            grid = cadedge.refine_shape(args.input, **opts, progress=progress)
    finally:
        progress.close()
    for w in caught:  # pass on what is not ours (library deprecations etc.) untouched
        if not issubclass(w.category, CadedgeWarning):
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    ours = [str(w.message) for w in caught if issubclass(w.category, CadedgeWarning)]
    messages = list(dict.fromkeys([*grid.warnings, *ours]))
    for message in messages[:MAX_WARNINGS]:
        print(f"cadedge refine: warning: {message}", file=sys.stderr)
    if len(messages) > MAX_WARNINGS:
        print(f"cadedge refine: warning: ... and {len(messages) - MAX_WARNINGS} more warnings (all in the "
              "ShapeGrid.warnings of the Python API)", file=sys.stderr)
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
