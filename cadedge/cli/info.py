"""``cadedge info INPUT``: what is in a STEP, IGES or BREP file, edge by edge, before refining it.

Counts (solids, shells, faces, edges, vertices), curve types, the worst edge tolerance, units and total edge
length, then one row per edge: id, curve type, degenerate/closed/seam flags, vertex and face ids,
tolerance and OCCT's length. Ids are those of ``cadedge refine``'s output.
"""

from __future__ import annotations

import argparse
from typing import Any

from ._table import format_table


def _flag(value: bool) -> str:
    return "yes" if value else "-"


def _ids(ids: Any) -> str:
    return ",".join(map(str, ids)) or "-"


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("info", help="list the edges of a STEP, IGES or BREP file",
                              description="List the edges of INPUT (ids as in cadedge refine's output) "
                                          "with their curve type, flags, faces, tolerance and length.")
    p.add_argument("input", metavar="INPUT", help="STEP (.step/.stp), IGES (.igs/.iges) or OCCT BREP (.brep) file")
    p.add_argument("--allow-partial", action="store_true",
                   help="list what a partial transfer did load (with a warning saying what was lost) instead "
                        "of refusing the file")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ._startup import heavy_imports
    from .refine import print_warnings

    with heavy_imports():
        from ..occt.describe import describe_shape

    d = describe_shape(args.input, allow_partial=args.allow_partial)
    print_warnings("info", args.input, d.warnings)
    types = ", ".join(f"{name} {n}" for name, n in sorted(d.curve_types.items(), key=lambda kv: (-kv[1], kv[0])))
    print(f"source: {d.source}")
    print(f"units: {d.units}")
    print(f"solids {d.solids}, shells {d.shells}, faces {d.faces}, edges {len(d.edges)}, vertices {d.vertices}")
    print(f"curve types: {types}")
    print(f"max edge tolerance: {d.max_tolerance:.3g} {d.units}")
    print(f"total edge length: {sum(e.length for e in d.edges):.6g} {d.units}")
    print()
    rows = [[e.id, e.curve, _flag(e.degenerate), _flag(e.closed), _flag(e.seam), _ids(e.vertices), _ids(e.faces),
             f"{e.tolerance:.3g}", f"{e.length:.6g}"] for e in d.edges]
    print(format_table(["id", "curve", "degenerate", "closed", "seam", "vertices", "faces", "tolerance", "length"],
                       rows, right=[True, False, False, False, False, False, False, True, True]))
    return 0
