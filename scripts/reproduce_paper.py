"""Reproduce McLaurin & Shontz's Tables 1 and 2 and Figures 6-8 with cadedge's paper mode.

    python scripts/reproduce_paper.py [--out docs/figures] [--order breadth|depth] [--search-tol 1e-4]

Prints markdown tables (ours beside the paper's numbers, pass/fail per cell) and writes one PNG per
curve (a row of three panels: 10%, 1%, 0.1% local delta). Exit status 1 if any cell fails.
A cell passes when: segments = printed count - 1 (+-1, the printed count is of vertices), polyline
length within 0.5% of Table 1, evaluations at most a third of Table 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from cadedge import refine_curve  # noqa: E402
from cadedge.yardsticks.analytic import paper_curves  # noqa: E402
from cadedge.yardsticks.reference import reference_length  # noqa: E402

DELTAS = (0.1, 0.01, 0.001)
PAPER_TRUE = {"lissajous": 13.0653, "tricuspid": 16.0, "cochleoid": 2.94}
PAPER_LENGTH = {"lissajous": (12.7123, 12.884, 13.04), "tricuspid": (15.5885, 15.87, 15.99),
                "cochleoid": (2.7916, 2.916, 2.939)}
PAPER_COUNT = {"lissajous": (8, 21, 121), "tricuspid": (4, 7, 25), "cochleoid": (11, 27, 86)}
PAPER_EVALS = {"lissajous": (1599, 4797, 29397), "tricuspid": (615, 1353, 5781),
               "cochleoid": (2337, 6273, 20787)}
TITLES = {"lissajous": "Lissajous (Fig. 6)", "tricuspid": "Tricuspid (Fig. 7)", "cochleoid": "Cochleoid (Fig. 8)"}


def run(order: str, search_tol: float | None) -> tuple[list[dict], dict]:
    """Refine every curve at every delta; one row per cell, plus the grids for the figures."""
    rows, grids = [], {}
    for curve in paper_curves():
        true = reference_length(curve, (0.0, 1.0))
        for k, delta in enumerate(DELTAS):
            g = refine_curve(curve, (0.0, 1.0), local_delta=delta, order=order, search_tol=search_tol)
            grids[curve.name, delta] = g
            count, plen, pev = PAPER_COUNT[curve.name][k], PAPER_LENGTH[curve.name][k], PAPER_EVALS[curve.name][k]
            ok_count = abs(g.segments - (count - 1)) <= 1
            ok_length = abs(g.length / plen - 1.0) <= 0.005
            ok_evals = 3 * g.evaluations <= pev
            rows.append(dict(curve=curve.name, delta=delta, segments=g.segments, vertices=g.segments + 1,
                             paper_count=count, length=g.length, paper_length=plen, true=true,
                             paper_true=PAPER_TRUE[curve.name], ald=1.0 - g.length / true,
                             estimate=g.ald_estimate, evaluations=g.evaluations, paper_evals=pev,
                             ok=ok_count and ok_length and ok_evals))
    return rows, grids


def markdown(rows: list[dict]) -> str:
    """Table 1 (lengths) and Table 2 (counts, evaluations) as markdown, ours beside the paper's."""
    t1 = ["| curve | local delta | our length | paper length | difference | true length (ours / paper) "
          "| achieved ALD | ald_estimate |", "|---|---|---|---|---|---|---|---|"]
    t2 = ["| curve | local delta | our segments | our vertices | paper count | our evaluations "
          "| paper evaluations | ratio | cell |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        d = f"{100 * r['delta']:g}%"
        t1.append(f"| {r['curve']} | {d} | {r['length']:.4f} | {r['paper_length']} "
                  f"| {100 * (r['length'] / r['paper_length'] - 1):+.2f}% | {r['true']:.4f} / {r['paper_true']} "
                  f"| {100 * r['ald']:.3f}% | {100 * r['estimate']:.3f}% |")
        t2.append(f"| {r['curve']} | {d} | {r['segments']} | {r['vertices']} | {r['paper_count']} "
                  f"| {r['evaluations']} | {r['paper_evals']} | {r['evaluations'] / r['paper_evals']:.3f} "
                  f"| {'pass' if r['ok'] else 'FAIL'} |")
    return ("Table 1: polyline length against the paper's\n\n" + "\n".join(t1)
            + "\n\nTable 2: counts and curve evaluations against the paper's\n\n" + "\n".join(t2) + "\n")


def draw(grids: dict, out: Path) -> list[Path]:
    """Figures 6-8: per curve a row of three panels, curve in red, grid in black with circled vertices."""
    out.mkdir(parents=True, exist_ok=True)
    u = np.linspace(0.0, 1.0, 4001)
    paths = []
    for curve in paper_curves():
        dense = curve.evaluate(u)
        fig, axes = plt.subplots(1, 3, figsize=(12, 4))
        for ax, delta in zip(axes, DELTAS):
            g = grids[curve.name, delta]
            ax.plot(dense[:, 0], dense[:, 1], color="red", lw=1.0)
            ax.plot(g.points[:, 0], g.points[:, 1], color="black", lw=0.8, marker="o", ms=4, mfc="none")
            ax.set_title(f"{100 * delta:g}% local delta: {g.segments} segments", fontsize=10)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
        fig.suptitle(TITLES[curve.name])
        fig.tight_layout()
        path = out / f"paper_{curve.name}.png"
        fig.savefig(path, dpi=80, bbox_inches="tight")
        plt.close(fig)
        paths.append(path)
    return paths


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "docs" / "figures",
                    help="folder for the figure PNGs (default: docs/figures)")
    ap.add_argument("--order", choices=("breadth", "depth"), default="breadth")
    ap.add_argument("--search-tol", type=float, default=None, help="golden-section tolerance (default: cadedge's)")
    args = ap.parse_args(argv)
    rows, grids = run(args.order, args.search_tol)
    print(markdown(rows))
    for path in draw(grids, args.out):
        print(f"wrote {path}")
    failed = [f"{r['curve']} {r['delta']}" for r in rows if not r["ok"]]
    print(f"{9 - len(failed)}/9 cells pass" + (f"; failed: {', '.join(failed)}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
