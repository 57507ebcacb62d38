"""Batch throughput: files per minute of ``run_batch`` on the STEP corpus with 1 and 2 workers.

Each batch runs in a fresh Python process with its own LocalCluster and writes into a fresh temporary
folder, so nothing is skipped. Two throughputs are reported, each against one worker:

- *files/min*: files over the whole command's wall time (interpreter start, imports, cluster start
  and close included), what a user running ``cadedge batch`` once sees;
- *files/min while up*: files over the time from the cluster being up to the last result
  (``BatchReport.phases["run"]``), the steady-state rate of the workers.

*beyond tasks* is the worker time while the cluster is up that the tasks' own clocks (read + refine +
write) do not account for: ``(workers x run - sum of task s) / sum of task s``; with two workers it
includes the end of the run where one worker has finished and the other has not. Prints a Markdown
table (paste into docs/batch.md).

    python scripts/bench_batch.py [--corpus FOLDER] [--ald 1e-3] [--workers 1 2] [--repeat 1] [--copies 1]

``--corpus`` defaults to the third-party corpus found as ``scripts/corpus_path.py`` says. ``--copies N``
runs N copies of it in one batch (copied into a temporary folder). ``--repeat N`` runs N rounds, each
worker count once per round, and keeps for each count the run with the shortest *run s* (the steady
rate is what the workers are judged by; the command figures are that run's).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Iterator

from corpus_path import require_corpus

from cadedge.batch import expand_inputs, run_batch


def bench(corpus: Path, ald: float, workers: int) -> dict:
    """One batch in a fresh Python process, as a user's ``cadedge batch`` runs (fork server included);
    ``command`` is that process's whole wall time, interpreter start and imports included."""
    code = ("import json, sys; from pathlib import Path; sys.path.insert(0, sys.argv[1]); import bench_batch as b\n"
            "if __name__ == '__main__':\n"
            "    print(json.dumps(b.bench_here(Path(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]))))")
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", code, str(Path(__file__).parent), str(corpus), repr(ald),
                          str(workers)], check=True, capture_output=True, text=True).stdout
    row = json.loads(out.strip().splitlines()[-1])
    row["command"] = time.perf_counter() - t0
    return row


def bench_here(corpus: Path, ald: float, workers: int) -> dict:
    """``run_batch`` over ``corpus`` into a temporary folder: counts, phases and the tasks' own seconds."""
    with tempfile.TemporaryDirectory(prefix="cadedge-bench-") as tmp:
        report = run_batch([corpus], Path(tmp) / "out", ald=ald, workers=workers)
    return {"workers": workers, "files": len(report.results), "ok": len(report.ok), "failed": len(report.failed),
            "seconds": report.seconds, **report.phases,
            "task_seconds": sum(r.seconds or 0.0 for r in report.results)}


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
    parser.add_argument("--repeat", type=int, default=1, help="rounds of runs; the run with the shortest run s is kept")
    parser.add_argument("--copies", type=int, default=1, help="copies of the corpus in one batch")
    args = parser.parse_args()
    args.corpus = args.corpus or require_corpus()
    with tempfile.TemporaryDirectory(prefix="cadedge-corpus-") as tmp:
        source = args.corpus if args.copies == 1 else replicate(args.corpus, args.copies, Path(tmp))
        run(source, args)


HEADER = ("| workers | files | ok | failed | command s | files/min | vs 1 worker | cluster start s | run s | close s "
          "| files/min while up | vs 1 worker | sum of task s | beyond tasks |")


def run(source: Path, args: argparse.Namespace) -> None:
    n = len(expand_inputs([source]))
    print(f"corpus {args.corpus} x {args.copies} ({n} files), ald {args.ald:g}, "
          f"{platform.processor() or platform.machine()}, python {platform.python_version()}, "
          f"load average {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    print()
    for line in table(source, args.ald, args.workers, args.repeat):
        print(line, flush=True)


def table(source: Path, ald: float, workers: list[int], rounds: int) -> Iterator[str]:
    """The Markdown table's lines: the header at once, the rows once every round has run (``rounds``
    rounds of one batch per worker count; per count, the run with the shortest *run s*)."""
    yield HEADER
    yield "|" + "---:|" * (HEADER.count("|") - 1)
    # rounds interleave the worker counts, so a slow spell of a shared host falls on all of them alike
    runs: dict[int, list[dict]] = {w: [] for w in workers}
    for _ in range(rounds):
        for w in workers:
            runs[w].append(bench(source, ald, w))
    base = None
    for w in workers:
        best = min(runs[w], key=lambda r: r["run"])
        per_min = 60.0 * best["files"] / best["command"]
        per_min_up = 60.0 * best["files"] / best["run"]
        base = base or (per_min, per_min_up)
        # worker-seconds while the cluster is up that no task (read + refine + write) accounts for
        beyond = (w * best["run"] - best["task_seconds"]) / best["task_seconds"]
        yield (f"| {w} | {best['files']} | {best['ok']} | {best['failed']} | {best['command']:.1f} | {per_min:.1f} "
               f"| {per_min / base[0]:.2f}x | {best['start']:.1f} | {best['run']:.1f} | {best['close']:.1f} "
               f"| {per_min_up:.1f} | {per_min_up / base[1]:.2f}x | {best['task_seconds']:.1f} "
               f"| {100 * beyond:.0f}% |")


if __name__ == "__main__":
    main()
