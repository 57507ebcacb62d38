"""The sampled DP optimum of a named analytic curve at a given arc-length deficit.

    python scripts/optimum.py CURVE --ald EPS [--n SAMPLES]

CURVE is one of ``cadedge.yardsticks.analytic`` (lissajous, tricuspid, cochleoid, circle, oscillatory, astroid,
helix, uneven, narrow_bump, spiral). Prints the fewest segments whose best polyline through dense
samples reaches ``(1 - EPS) * L_ref`` (``L_ref`` the known length or
``cadedge.yardsticks.reference.reference_length``), with the seconds taken. Exit status 2 on a bad argument.
"""

from __future__ import annotations

import argparse
import sys
import time

from cadedge.yardsticks import analytic
from cadedge.errors import CadedgeError
from cadedge.yardsticks.optimum import sampled_optimum
from cadedge.yardsticks.reference import reference_length

CURVES = {c.name.rstrip("0123456789"): c for c in analytic.paper_curves() + analytic.family()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("curve", choices=sorted(CURVES))
    parser.add_argument("--ald", type=float, required=True, help="arc-length deficit, e.g. 1e-3")
    parser.add_argument("--n", type=int, default=None, help="samples (default: adaptive)")
    args = parser.parse_args(argv)
    if not 0.0 < args.ald < 1.0:
        parser.error(f"--ald must be in (0, 1), got {args.ald}")
    curve = CURVES[args.curve]
    true = curve.length if curve.length is not None else reference_length(curve, curve.domain)
    start = time.perf_counter()
    try:
        count = sampled_optimum(curve, curve.domain, (1.0 - args.ald) * true, n=args.n)
    except CadedgeError as exc:
        print(f"optimum.py: error: {exc}", file=sys.stderr)
        return 2
    print(f"{curve.name}: ald {args.ald:g}, reference length {true:.10g}, sampled optimum {count} segments "
          f"({time.perf_counter() - start:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
