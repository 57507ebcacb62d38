"""Batch throughput: files per minute of ``run_batch`` on the STEP corpus with 1 and 2 workers.

Each run starts its own LocalCluster (start-up included in the wall time) and writes into a fresh
temporary folder, so nothing is skipped. Prints a Markdown table (paste into docs/batch.md).

    python scripts/bench_batch.py [--corpus FOLDER] [--ald 1e-3] [--workers 1 2] [--repeat 1] [--copies 1]

``--corpus`` defaults to the third-party corpus found as ``scripts/corpus_path.py`` says. ``--copies N``
runs N copies of it in one batch (copied into a temporary folder), which measures the steady-state
throughput: on one pass of the 11-file corpus the fixed cost of starting and closing the cluster and
the longest file bound what a second worker can gain.
"""

from __future__ import annotations

import argparse
import json
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from corpus_path import require_corpus

from cadedge.batch import expand_inputs, run_batch


def bench(corpus: Path, ald: float, workers: int) -> dict:
    """One batch in a fresh Python process, as a user's ``cadedge batch`` runs (fork server included)."""
    code = ("import json, sys; from pathlib import Path; sys.path.insert(0, sys.argv[1]); import bench_batch as b; "
            "print(json.dumps(b.bench_here(Path(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]))))")
    out = subprocess.run([sys.executable, "-c", code, str(Path(__file__).parent), str(corpus), repr(ald),
                          str(workers)], check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def bench_here(corpus: Path, ald: float, workers: int) -> dict:
    with tempfile.TemporaryDirectory(prefix="cadedge-bench-") as tmp:
        t0 = time.perf_counter()
        report = run_batch([corpus], Path(tmp) / "out", ald=ald, workers=workers)
        wall = time.perf_counter() - t0
    task_seconds = sum(r.seconds or 0.0 for r in report.results)
    return {"workers": workers, "files": len(report.results), "ok": len(report.ok), "failed": len(report.failed),
            "wall": wall, "per_min": 60.0 * len(report.results) / wall, "task_seconds": task_seconds}


def cluster_seconds(workers: int) -> float:
    """Wall time, in a fresh Python process, to start a LocalCluster as ``run_batch`` does, reach
    every worker, and close it."""
    code = ("import sys, time; t0 = time.perf_counter(); from cadedge.batch.runner import connect\n"
            "if __name__ == '__main__':\n"
            "    with connect(workers=int(sys.argv[1])) as client: client.run(int)\n"
            "    print(time.perf_counter() - t0)")
    with tempfile.TemporaryDirectory(prefix="cadedge-bench-") as tmp:
        script = Path(tmp) / "cluster.py"
        script.write_text(code)
        out = subprocess.run([sys.executable, str(script), str(workers)], check=True, capture_output=True,
                             text=True).stdout
    return float(out.strip().splitlines()[-1])


def replicate(corpus: Path, copies: int, dest: Path) -> Path:
    """``dest`` holding ``copies`` copies of every model of ``corpus``, one folder per copy."""
    for k in range(copies):
        for path in expand_inputs([corpus]):
            target = dest / f"copy{k}" / path.relative_to(corpus)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(path, target)
    return dest


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=None, help="a folder of STEP files (default: the corpus)")
    parser.add_argument("--ald", type=float, default=1e-3)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--repeat", type=int, default=1, help="runs per worker count; the best is kept")
    parser.add_argument("--copies", type=int, default=1, help="copies of the corpus in one batch")
    args = parser.parse_args()
    args.corpus = args.corpus or require_corpus()
    with tempfile.TemporaryDirectory(prefix="cadedge-corpus-") as tmp:
        source = args.corpus if args.copies == 1 else replicate(args.corpus, args.copies, Path(tmp))
        run(source, args)


def run(source: Path, args: argparse.Namespace) -> None:
    n = len(expand_inputs([source]))
    print(f"corpus {args.corpus} x {args.copies} ({n} files), ald {args.ald:g}, "
          f"{platform.processor() or platform.machine()}, python {platform.python_version()}")
    print("\n| workers | files | ok | failed | wall s (incl. cluster) | files/min | vs 1 worker | sum of task s "
          "| cluster start+close s | beyond tasks |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    base = None
    for w in args.workers:
        best = min((bench(source, args.ald, w) for _ in range(args.repeat)), key=lambda r: r["wall"])
        fixed = min(cluster_seconds(w) for _ in range(args.repeat))
        base = base or best["per_min"]
        # worker-seconds not spent in a task (read + refine + write), cluster start and close left out
        beyond = (w * (best["wall"] - fixed) - best["task_seconds"]) / best["task_seconds"]
        print(f"| {w} | {best['files']} | {best['ok']} | {best['failed']} | {best['wall']:.1f} | "
              f"{best['per_min']:.1f} | {best['per_min'] / base:.2f}x | {best['task_seconds']:.1f} | {fixed:.1f} | "
              f"{100 * beyond:.0f}% |", flush=True)

if __name__ == "__main__":
    main()
