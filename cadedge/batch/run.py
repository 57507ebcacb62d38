"""``run_batch``: plan which inputs are due, run them on dask, record each outcome in the index."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Any, Callable, Iterable

from ..errors import InputError
from ..options import positive, refine_options
from .index import INDEX_NAME, BatchIndex, IndexRow, options_key
from .inputs import expand_inputs, output_names
from .report import BatchProgress, BatchReport, FileResult
from .runner import Job, Outcome, Task, connect, run_jobs
from .task import refine_task

DEFAULT_TIMEOUT = 600.0


def _check_options(ald: float, min_length: float | None, max_length: float | None,
                   max_growth: float | None, workers: int | None, scheduler: str | None,
                   timeout: float) -> dict[str, float | None]:
    """The refinement options as checked floats; bad batch options raise InputError."""
    options = refine_options(ald, min_length, max_length, max_growth)
    positive("timeout", timeout)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise InputError(f"workers must be a whole number of at least 1, got {workers!r}")
    if workers is not None and scheduler is not None:
        raise InputError("give workers (a local cluster) or scheduler (an existing one), not both")
    return options


def _result(row: IndexRow) -> FileResult:
    return FileResult(row.input, row.output, row.status, row.edges, row.segments, row.worst_ald,
                      row.seconds, row.error, tuple(json.loads(row.warnings)))


def run_batch(inputs: Iterable[str | os.PathLike], outdir: str | os.PathLike, *, ald: float = 1e-3,
              min_length: float | None = None, max_length: float | None = None,
              max_growth: float | None = None, workers: int | None = None, scheduler: str | None = None,
              timeout: float = DEFAULT_TIMEOUT, retry_failed: bool = False, allow_partial: bool = False,
              progress: Callable[[BatchProgress], None] | None = None,
              task: Task | None = None) -> BatchReport:
    """Refine many STEP, IGES or BREP files on dask.distributed into ``outdir/<name>.json``, resumably.

    ``inputs``: files, folders (searched recursively for .step/.stp/.igs/.iges/.brep) or globs. A file
    that OCCT transfers only in part is recorded failed unless ``allow_partial`` (then it is refined
    with a warning saying what was lost). Without ``scheduler``
    a LocalCluster of ``workers`` processes (default: one per core) is started and closed; with it,
    the scheduler at that address is used (its workers must import cadedge and see ``outdir``).
    Each outcome is recorded in ``outdir/index.sqlite`` as it arrives. An input already ok there
    (same size, mtime and options, output present) is skipped; one that failed is skipped unless
    ``retry_failed``. A task that raises, kills its worker or runs over ``timeout`` seconds fails
    alone, and its earlier output, if any, is removed: an output file exists only for inputs ok in
    the index. Largest inputs go first. ``task(input, output, options) -> summary`` replaces the
    per-file work (default: refine and write JSON). ``progress`` receives a :class:`BatchProgress`
    before the first task and after each. Raises :class:`InputError` for bad options, missing
    inputs or no inputs.
    """
    options: dict[str, Any] = _check_options(ald, min_length, max_length, max_growth, workers, scheduler,
                                             timeout)
    if allow_partial:  # only when given, so the options recorded by earlier runs stay the same
        options["allow_partial"] = True
    t0 = time.perf_counter()
    paths = expand_inputs(inputs)
    out = Path(outdir)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: output exists and is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    opts = options_key(options)
    report = BatchReport(outdir=out, index=out / INDEX_NAME)
    with BatchIndex(report.index) as index:
        names = output_names(paths, index.names())
        todo: list[Job] = []
        stats = {}
        for path in paths:
            try:
                st = path.stat()
            except OSError as exc:
                raise InputError(f"{path}: cannot read: {exc.strerror}") from None
            stats[str(path)] = st
            row = index.get(str(path))
            same = row is not None and (row.size, row.mtime_ns, row.options) == (st.st_size, st.st_mtime_ns,
                                                                                  opts)
            if same and row.status == "ok" and (out / row.output).is_file():
                report.skipped.append(row.input)
            elif same and row.status == "failed" and not retry_failed:
                report.skipped_failed.append(_result(row))
            else:
                todo.append(Job(str(path), str(out / names[path])))
        # largest files first: the long tasks start early, so workers finish together
        todo.sort(key=lambda job: -stats[job.input].st_size)

        counts = {"ok": 0, "failed": 0}

        def snapshot(last: FileResult | None) -> BatchProgress:
            return BatchProgress(len(todo), len(report.results), counts["ok"], counts["failed"],
                                 len(report.skipped), len(report.skipped_failed), last)

        def record(outcome: Outcome) -> None:
            st = stats[outcome.job.input]
            s = outcome.summary or {}
            res = FileResult(outcome.job.input, Path(outcome.job.output).name, outcome.status,
                             s.get("edges"), s.get("segments"), s.get("worst_ald"), outcome.seconds,
                             outcome.error, tuple(s.get("warnings", ())))
            index.record(input=res.input, output=res.output, status=res.status, size=st.st_size,
                         mtime_ns=st.st_mtime_ns, options=opts, edges=res.edges, segments=res.segments,
                         worst_ald=res.worst_ald, seconds=res.seconds, error=res.error,
                         warnings=res.warnings)
            if res.status == "failed":  # an output from an earlier version of this input is stale now
                Path(outcome.job.output).unlink(missing_ok=True)
            report.results.append(res)
            counts[res.status] += 1
            if progress is not None:
                progress(snapshot(res))

        if progress is not None:
            progress(snapshot(None))
        clock = time.perf_counter()
        report.phases["plan"] = clock - t0
        if todo:
            with connect(workers=workers, scheduler=scheduler) as client:
                report.phases["start"] = time.perf_counter() - clock
                clock = time.perf_counter()
                run_jobs(client, todo, task or refine_task, options, timeout=timeout, on_outcome=record)
                report.phases["run"] = time.perf_counter() - clock
                clock = time.perf_counter()
            report.phases["close"] = time.perf_counter() - clock
    report.seconds = time.perf_counter() - t0
    return report
