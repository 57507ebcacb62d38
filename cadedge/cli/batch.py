"""``cadedge batch INPUT... -o OUTDIR``: refine many STEP, IGES or BREP files on dask.distributed, resumably.

A thin shell over :func:`cadedge.batch.run_batch`: a tqdm bar on stderr (when it is a terminal) with
done/failed counts, each failure as one line on stderr as it happens, a summary on stdout. Exit code
0 when every input is ok, 1 when any is failed (now or in an earlier run, not retried), 2 for bad
usage or no inputs found.
"""

from __future__ import annotations

import argparse
import logging
import sys
from typing import IO, Any

from ..batch.run import DEFAULT_TIMEOUT

from .refine import add_refine_options, refine_options


class BatchBar:
    """The ``progress`` callback of ``run_batch``: skip notice on stdout, tqdm bar and failures on stderr."""

    def __init__(self, *, out: IO[str], err: IO[str], enabled: bool | None = None):
        self.out, self.err = out, err
        self.enabled = err.isatty() if enabled is None else enabled
        self.bar: Any = None

    def __call__(self, p: Any) -> None:
        if p.last is None:
            if p.skipped:
                print(f"skipped {p.skipped} finished inputs", file=self.out, flush=True)
            if p.skipped_failed:
                print(f"skipped {p.skipped_failed} inputs that failed before (retry them with --retry-failed)",
                      file=self.out, flush=True)
            if self.enabled and p.total:
                from tqdm import tqdm
                self.bar = tqdm(total=p.total, desc="batch", unit="file", file=self.err, dynamic_ncols=True)
            return
        if p.last.status == "failed":
            line = f"failed: {p.last.input}: {p.last.error}"
            if self.bar is not None:
                self.bar.write(line, file=self.err)
            else:
                print(line, file=self.err, flush=True)
        if self.bar is not None:
            self.bar.set_postfix(done=p.ok, failed=p.failed, refresh=False)
            self.bar.update(p.done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("batch", help="edge grids of many STEP, IGES or BREP files on dask",
                              description="Refine every model file named (files, folders searched recursively "
                                          "for .step/.stp/.igs/.iges/.brep, globs) into OUTDIR/<name>.json, recording each "
                                          "outcome in OUTDIR/index.sqlite; a rerun skips finished inputs.")
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="STEP, IGES or BREP file, folder or glob")
    p.add_argument("-o", "--output", required=True, metavar="OUTDIR", help="output folder (created if missing)")
    add_refine_options(p)
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N", help="worker processes of the local cluster "
                                                                "(default: one per core)")
    where.add_argument("--scheduler", metavar="ADDRESS", help="use the dask scheduler at ADDRESS "
                                                              "(e.g. tcp://host:8786) instead of a local cluster")
    p.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"per-file time limit (default {DEFAULT_TIMEOUT:g})")
    p.add_argument("--retry-failed", action="store_true", help="run again the inputs that failed before")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..batch import run_batch

    opts = refine_options(args, "options")
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
    bar = BatchBar(out=sys.stdout, err=sys.stderr)
    try:
        report = run_batch(args.inputs, args.output, **opts, workers=args.workers, scheduler=args.scheduler,
                           timeout=args.timeout, retry_failed=args.retry_failed, allow_partial=args.allow_partial,
                           progress=bar)
    finally:
        bar.close()
    total = len(report.results) + len(report.skipped) + len(report.skipped_failed)
    failed = report.failed + report.skipped_failed
    print(f"{total} inputs: {len(report.ok)} ok, {len(report.failed)} failed, {len(report.skipped)} skipped "
          f"(finished before), {len(report.skipped_failed)} failed before; {report.seconds:.1f} s")
    for r in failed:
        print(f"failed: {r.input}: {r.error}")
    warned = sum(bool(r.warnings) for r in report.ok)
    if warned:
        print(f"{warned} inputs refined with warnings (column 'warnings' of the index)")
    print(f"results in {report.outdir}, index {report.index}")
    return 0 if report.all_ok else 1
