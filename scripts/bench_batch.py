"""Batch throughput: files per minute of ``run_batch`` on the STEP corpus with 1 and 2 workers.

Each run starts its own LocalCluster (start-up included in the wall time) and writes into a fresh
temporary folder, so nothing is skipped. Prints a Markdown table (paste into docs/batch.md).

    python scripts/bench_batch.py [--corpus FOLDER] [--ald 1e-3] [--workers 1 2] [--repeat 1]

``--corpus`` defaults to the third-party corpus found as ``scripts/corpus_path.py`` says.
"""

from __future__ import annotations

import argparse
import platform
import tempfile
import time
from pathlib import Path

from corpus_path import require_corpus

from cadedge.batch import expand_inputs, run_batch


def bench(corpus: Path, ald: float, workers: int) -> dict:
    with tempfile.TemporaryDirectory(prefix="cadedge-bench-") as tmp:
        t0 = time.perf_counter()
        report = run_batch([corpus], Path(tmp) / "out", ald=ald, workers=workers)
        wall = time.perf_counter() - t0
    task_seconds = sum(r.seconds or 0.0 for r in report.results)
    return {"workers": workers, "files": len(report.results), "ok": len(report.ok), "failed": len(report.failed),
            "wall": wall, "per_min": 60.0 * len(report.results) / wall, "task_seconds": task_seconds}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=None, help="a folder of STEP files (default: the corpus)")
    parser.add_argument("--ald", type=float, default=1e-3)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--repeat", type=int, default=1, help="runs per worker count; the best is kept")
    args = parser.parse_args()
    args.corpus = args.corpus or require_corpus()
    n = len(expand_inputs([args.corpus]))
    print(f"corpus {args.corpus} ({n} files), ald {args.ald:g}, {platform.processor() or platform.machine()}, "
          f"python {platform.python_version()}")
    print("\n| workers | files | ok | failed | wall s (incl. cluster start) | files/min | sum of task s |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for w in args.workers:
        best = min((bench(args.corpus, args.ald, w) for _ in range(args.repeat)), key=lambda r: r["wall"])
        print(f"| {w} | {best['files']} | {best['ok']} | {best['failed']} | {best['wall']:.1f} | "
              f"{best['per_min']:.1f} | {best['task_seconds']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
