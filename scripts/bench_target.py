"""Target-mode benchmark: achieved deficit and segment count against the sampled DP optimum.

    python scripts/bench_target.py [--eps 1e-2 1e-3 1e-4] [--curve NAME ...] [--write]

For every curve of ``analytic.paper_curves() + analytic.family()`` (``cadedge.yardsticks``) and every ``eps``:
``cadedge.refine_curve(c, c.domain, ald=eps)``; the achieved ALD ``1 - length / L_ref`` (``L_ref`` the
known length, else ``cadedge.yardsticks.reference.reference_length``); the sampled DP optimum at the achieved length
(``cadedge.yardsticks.optimum.sampled_optimum``: fewest segments through dense samples, the grid's own vertices
included, reaching the grid's own length, so the optimum is never worse than the grid) and at
``(1 - eps) L_ref``; the ratio segments / optimum at the achieved length; evaluations; seconds of
refinement. A row passes when ALD <= eps and the ratio <= 1.15.
Prints a markdown table; ``--write`` also puts it into docs/target.md. Exit status 1 if any row fails.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

from cadedge import refine_curve
from cadedge.atomic import atomic_write_bytes
from cadedge.yardsticks import analytic
from cadedge.yardsticks.optimum import sampled_optimum
from cadedge.yardsticks.reference import reference_length

RATIO_LIMIT = 1.15
DOC = Path(__file__).resolve().parents[1] / "docs" / "target.md"
BEGIN, END = "<!-- bench_target:begin -->", "<!-- bench_target:end -->"


def run(eps_list: list[float], names: list[str] | None) -> list[dict]:
    """One row per (eps, curve)."""
    curves = [c for c in analytic.paper_curves() + analytic.family() if not names or c.name in names]
    truth = {c.name: c.length if c.length is not None else reference_length(c, c.domain) for c in curves}
    rows = []
    for eps in eps_list:
        for c in curves:
            start = time.perf_counter()
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                g = refine_curve(c, c.domain, ald=eps)
            seconds = time.perf_counter() - start
            true = truth[c.name]
            ald = 1.0 - g.length / true
            opt = sampled_optimum(c, c.domain, g.length, include=g.params)
            opt_eps = sampled_optimum(c, c.domain, (1.0 - eps) * true)
            ratio = g.segments / opt
            rows.append(dict(curve=c.name, eps=eps, segments=g.segments, ald=ald, estimate=g.ald_estimate,
                             opt=opt, opt_eps=opt_eps, ratio=ratio, evaluations=g.evaluations,
                             seconds=seconds, ald_ok=ald <= eps, ratio_ok=ratio <= RATIO_LIMIT,
                             warnings=len(caught)))
            print(f"  {c.name} eps={eps:g}: {g.segments} segments, ald {ald:.3e}, optimum {opt}, "
                  f"ratio {ratio:.3f}", file=sys.stderr, flush=True)
    return rows


def markdown(rows: list[dict]) -> str:
    lines = ["| eps | curve | segments | achieved ALD | ald_estimate | DP optimum at achieved length "
             "| ratio | DP optimum at eps | evaluations | seconds | ALD <= eps | ratio <= 1.15 |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['eps']:g} | {r['curve']} | {r['segments']} | {r['ald']:.3e} "
                     f"| {r['estimate']:.3e} | {r['opt']} | {r['ratio']:.3f} | {r['opt_eps']} "
                     f"| {r['evaluations']} | {r['seconds']:.3f} | {'PASS' if r['ald_ok'] else 'FAIL'} "
                     f"| {'PASS' if r['ratio_ok'] else 'FAIL'} |")
    failed = sum(not (r["ald_ok"] and r["ratio_ok"]) for r in rows)
    worst = max(rows, key=lambda r: r["ratio"])
    lines.append("")
    lines.append(f"{len(rows) - failed} of {len(rows)} rows pass; worst ratio {worst['ratio']:.3f} "
                 f"({worst['curve']}, eps {worst['eps']:g}); worst ALD / eps "
                 f"{max(r['ald'] / r['eps'] for r in rows):.3f}.")
    return "\n".join(lines) + "\n"


def write_doc(table: str, command: str) -> None:
    """Replace the generated block of docs/target.md (between the markers) with the new table."""
    block = f"{BEGIN}\n\nCommand: `{command}`\n\n{table}\n{END}"
    text = DOC.read_text() if DOC.exists() else f"# Target mode\n\n{BEGIN}\n{END}\n"
    if BEGIN not in text or END not in text:
        text = text.rstrip("\n") + f"\n\n{BEGIN}\n{END}\n"
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    atomic_write_bytes(DOC, (head + block + tail).encode())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--eps", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    parser.add_argument("--curve", nargs="+", default=None, help="curve names (default: all)")
    parser.add_argument("--write", action="store_true", help="update docs/target.md")
    args = parser.parse_args(argv)
    known = {c.name for c in analytic.paper_curves() + analytic.family()}
    unknown = sorted(set(args.curve or ()) - known)
    if unknown:
        parser.error(f"unknown curve(s) {unknown}; choose from {sorted(known)}")
    rows = run(args.eps, args.curve)
    table = markdown(rows)
    print(table)
    if args.write:
        command = "python scripts/bench_target.py"
        if argv or sys.argv[1:]:
            command += " " + " ".join(a for a in (argv if argv is not None else sys.argv[1:]))
        write_doc(table, command)
    return 0 if all(r["ald_ok"] and r["ratio_ok"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
