"""``cadedge mesh INPUT --ald EPS -o OUT``: surface mesh by gmsh on the edge grids, then the check.

OUT's suffix picks the format: ``.msh``, ``.stl``, ``.vtk`` (the mesh) or ``.geo`` (spacing export plus a
``.brep`` beside it, not meshed). Prints the watertight/conforming check; exit 0 when every face meshed
and the check passed, 1 otherwise (one line on stderr per problem), 2 on bad input.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

from ..errors import CadedgeWarning, InputError
from .refine import add_refine_options, check_writable, parse_number, print_warnings, refine_options


def register(subparsers: Any) -> None:
    from ..mesh import DEFAULT_GROWTH, MESH_MAX_GROWTH, MODES

    p = subparsers.add_parser(
        "mesh", help="surface mesh (gmsh) on the edge grids, with a watertight check",
        description="Refine every edge of INPUT, impose the edge grids on gmsh's curves and mesh every face "
                    "(faces sharing an edge share its nodes); print the watertight/conforming check. "
                    "OUT: .msh .stl .vtk, or .geo for the spacing export (with a .brep beside it).",
        epilog=f"For meshing, --max-growth defaults to {MESH_MAX_GROWTH} (graded edge grids avoid slivers "
               "next to finely split edges). Exit 0 ok, 1 some face failed or the check failed, 2 bad input.")
    p.add_argument("input", metavar="INPUT", help="STEP (.step/.stp), IGES (.igs/.iges) or OCCT BREP (.brep) file")
    add_refine_options(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="output mesh (.msh .stl .vtk) or .geo")
    p.add_argument("--mode", choices=MODES, default="nodes",
                   help="nodes: impose the grid nodes on every curve (default); sizes: give gmsh only sizes")
    p.add_argument("--growth", metavar="G", default=str(DEFAULT_GROWTH),
                   help=f"interior size growth per unit distance from the edges (default {DEFAULT_GROWTH})")
    p.add_argument("--max-size", metavar="H", help="largest triangle size (default: --max-length, else the "
                                                   "largest edge spacing)")
    p.add_argument("--plot", metavar="FILE", help="also draw the mesh and the edge grids: .png (static) or .html "
                                                  "(interactive 3-D page, works offline)")
    p.add_argument("--quiet", action="store_true", help="print only problems")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import cadedge
    from ..mesh import MESH_MAX_GROWTH, MESH_SUFFIXES, mesh_shape

    source = args.input
    opts = refine_options(args, source)
    if opts["max_growth"] is None:
        opts["max_growth"] = MESH_MAX_GROWTH
    growth = parse_number("--growth", args.growth, source, low=0.0)
    max_size = parse_number("--max-size", args.max_size, source, low=0.0)
    out = Path(args.output)  # checked before any work: the grids are made here, outside mesh_shape
    if out.suffix.lower() not in MESH_SUFFIXES + (".geo",):
        raise InputError(f"{out}: unsupported mesh output suffix {out.suffix!r} (use {', '.join(MESH_SUFFIXES)} "
                         "or .geo)")
    check_writable(args.output)
    if args.plot:
        from ..plot import check_plot_path
        check_plot_path(args.plot)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", CadedgeWarning)
        grid = cadedge.refine_shape(args.input, **opts, allow_partial=args.allow_partial)
    print_warnings("mesh", [*grid.warnings, *(str(w.message) for w in caught
                                              if issubclass(w.category, CadedgeWarning))])
    result = mesh_shape(grid, output=out, mode=args.mode, growth=growth, max_size=max_size, **opts)
    if args.plot:
        from ..plot import plot_mesh
        plot_mesh(result, args.plot)
    if not args.quiet:
        for line in result.lines()[: len(result.lines()) - len(result.problems())]:
            print(line)
        for note in result.notes:
            print(f"note: {note}")
        if out.suffix.lower() != ".geo":  # the .geo note already says what was written
            print(f"wrote {out}")
        if args.plot:
            print(f"wrote {args.plot}")
    for problem in result.problems():
        print(f"cadedge mesh: {source}: {problem}", file=sys.stderr)
    return 0 if result.ok else 1
