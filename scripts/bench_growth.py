"""max_growth benchmark: segments, CPU time and the limits met, with and without grading.

For every corpus file and fixture, ``refine_shape`` at one ALD without ``max_growth`` and at each growth
given: the segment count, the CPU time of the call, the worst ratio of adjacent segments within an edge and
of end segments meeting at a vertex, the pairs over the limit, the worst edge's ALD estimate and the
``max_growth`` notes. Below the golden ratio edges are re-placed along graded size fields, at and above it
split (see ``cadedge/occt/vertexgrowth.py``).

    python scripts/bench_growth.py                        # ALD 1e-3, growth 2.0 1.5 1.2, markdown table
    python scripts/bench_growth.py --growth 1.5 --json rows.json --file fixtures/bracket.step
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
from corpus_path import find_corpus, step_files  # noqa: E402

SLACK = 1e-6


def measure(path: Path, ald: float, growth: float | None) -> dict:
    """One refine_shape call: counts, CPU time, worst ratios (within edges, at vertices) and notes."""
    from cadedge import refine_shape

    t = time.process_time()
    grid = refine_shape(path, ald=ald, max_growth=growth)
    cpu = time.process_time() - t
    live = [e for e in grid.edges if not e.degenerate and e.segments]
    ratios = []
    ends: dict[int, list[float]] = {}
    for e in live:
        s = e.segment_lengths
        if len(s) > 1:
            ratios.append(np.maximum(s[1:], s[:-1]) / np.minimum(s[1:], s[:-1]))
        ends.setdefault(e.vertices[0], []).append(s[0])
        ends.setdefault(e.vertices[1], []).append(s[-1])
    within = np.concatenate(ratios) if ratios else np.ones(1)
    at = np.array([max(v) / min(v) for v in ends.values() if len(v) > 1] or [1.0])
    limit = np.inf if growth is None else growth * (1 + SLACK)
    return {"model": path.name, "ald": ald, "growth": growth, "segments": grid.segments, "cpu": cpu,
            "worst_within": float(within.max()), "over_within": int((within > limit).sum()),
            "worst_at_vertex": float(at.max()), "over_at_vertex": int((at > limit).sum()),
            "worst_ald": max((e.ald_estimate for e in live), default=0.0),
            "notes": sum("max_growth" in w for w in grid.warnings)}


def table(rows: list[dict]) -> list[str]:
    """Markdown: one row per model and growth, the segments also as a multiple of the ungraded count."""
    plain = {r["model"]: r["segments"] for r in rows if r["growth"] is None}
    out = ["| model | max_growth | segments | x ungraded | CPU s | worst within / over | worst at vertex / over "
           "| worst ALD | notes |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        g = "-" if r["growth"] is None else f"{r['growth']:g}"
        ratio = r["segments"] / plain[r["model"]] if plain.get(r["model"]) else float("nan")
        out.append(f"| {r['model']} | {g} | {r['segments']} | {ratio:.2f} | {r['cpu']:.2f} | "
                   f"{r['worst_within']:.3f} / {r['over_within']} | {r['worst_at_vertex']:.3f} / {r['over_at_vertex']} "
                   f"| {r['worst_ald']:.2e} | {r['notes']} |")
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ald", type=float, default=1e-3)
    ap.add_argument("--growth", type=float, nargs="+", default=[2.0, 1.5, 1.2])
    ap.add_argument("--file", type=Path, nargs="+", help="these files instead of the corpus and the fixtures")
    ap.add_argument("--json", type=Path, help="also write the rows as JSON")
    args = ap.parse_args()
    files = args.file or (step_files(find_corpus()) + sorted((ROOT / "fixtures").glob("*.step")))
    rows = []
    for path in files:
        for growth in [None, *args.growth]:
            rows.append(measure(path, args.ald, growth))
            print(f"{path.name} {growth}: {rows[-1]['segments']} segments, {rows[-1]['cpu']:.2f} s", file=sys.stderr)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    print("\n".join(table(rows)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
