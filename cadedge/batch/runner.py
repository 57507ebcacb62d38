"""Running batch tasks on dask.distributed: cluster or client set-up, submission, timeouts, crashes.

Tasks are submitted no faster than the cluster has threads, so a submitted task starts at once (one
waiting on a worker behind another would share its fate if that worker died, and its clock would run)
and the scheduler never holds thousands of keys. A task's clock starts when the scheduler first
reports it processing on a worker; the scheduler is asked only about tasks not ended within
:data:`POLL_SECONDS` of their submission (the clock only matters to time a task out). Failures are
isolated per input:

- the task raises: failed with the exception's type and message;
- the worker process dies (OCCT crash, kill, out of memory): dask's ``KilledWorker``; our own
  LocalCluster allows no retries (``allowed-failures`` 0), so a crashing file costs one worker restart;
- the task outlives ``timeout``: a hung OCCT call cannot be interrupted in its thread, so the worker
  running it is restarted through its nanny and the input is failed as timed out.

A task's summary reaches the client with its end: the worker logs it as a dask event on a topic
this client subscribes to, sent on the same stream and before the message that the task finished,
so the summary is in hand when its future is done and no round trip fetches it. That round trip was
about 3 ms a file, and one ``processing`` query per task as much again: on a local cluster the cost
per file beyond the task's own clock fell from about 17 ms to 10, the rest being dask's own dispatch
and report. A summary that cannot travel as an event (a custom task's, not msgpack-serialisable)
stays on its worker until fetched, and a worker stuck in C code holding the GIL answers nothing, not
even for a summary it already holds. So summaries are in hand before the freed threads get new jobs
(a next job hanging on the same worker would otherwise block the fetch, and with it the loop that
times the hang out), and each fetch is bounded: a summary that
cannot be fetched in time is tried again on later rounds, and if its worker is restarted the
scheduler computes it again.
"""

from __future__ import annotations

import contextlib
import logging
import math
import multiprocessing
import os
import signal
import uuid
from collections import deque
from dataclasses import dataclass
from time import monotonic
from typing import Any, Callable, Iterator

from ..errors import InputError

POLL_SECONDS = 0.2
#: How long a finished task's summary is waited for on the round it ends, and on later rounds.
FETCH_SECONDS, REFETCH_SECONDS = 2.0, 0.05
#: How long the cluster's thread count is trusted before asking the scheduler again (it is asked at
#: once after a failure, which may mean a worker left).
THREADS_SECONDS = 2.0
RESTART_SECONDS = 30.0
WORKER_DIED = "worker process died (killed or crashed)"
#: LocalCluster options for no dashboard. The scheduler always serves HTTP (health, metrics); with
#: ``dashboard_address=None`` it takes port 8787 and warns when another cluster holds it, so it gets
#: a free port instead.
NO_DASHBOARD = {"dashboard_address": ":0", "scheduler_kwargs": {"dashboard": False}}

#: What a worker needs before its first file (dask, OCCT, the task), imported by :mod:`.preload`.
WORKER_PRELOAD = ["cadedge.batch.preload"]

Task = Callable[[str, str, dict], dict]


@dataclass(frozen=True)
class Job:
    """One input to process: its resolved path and the full path of its output file."""

    input: str
    output: str


@dataclass(frozen=True)
class Outcome:
    """What became of a job: ``status`` "ok" with the task's summary, or "failed" with a reason."""

    job: Job
    status: str
    summary: dict[str, Any] | None
    error: str | None
    seconds: float


def default_workers() -> int:
    """Worker processes of the embedded LocalCluster: one per usable core."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


@contextlib.contextmanager
def connect(*, workers: int | None = None, scheduler: str | None = None) -> Iterator[Any]:
    """A dask ``Client``: on the scheduler at ``scheduler``, else on a new LocalCluster of processes.

    Connecting, and waiting for a scheduler's first worker, each give up after dask's
    ``distributed.comm.timeouts.connect`` (30 s by default) with an :class:`InputError`.
    The LocalCluster has ``workers`` single-threaded worker processes with nannies (so crashed or
    hung workers are restarted), no dashboard, no task retries after a worker death, and its logs
    silenced: every failure is reported per input instead.
    """
    if scheduler is None:
        _start_fork_server()  # imports OCCT there while this process imports dask and starts the scheduler
    import dask
    from distributed import Client, LocalCluster

    if scheduler is not None:
        wait = dask.config.get("distributed.comm.timeouts.connect")
        try:
            client = Client(scheduler, timeout=wait)
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(f"cannot connect to dask scheduler {scheduler}: {exc}") from None
        with client:
            try:  # tasks on a scheduler without workers would wait for ever
                client.wait_for_workers(1, timeout=dask.utils.parse_timedelta(wait, default="seconds"))
            except TimeoutError:
                raise InputError(f"dask scheduler {scheduler} has no workers (waited {wait})") from None
            yield client
        return
    config = {"distributed.scheduler.allowed-failures": 0,
              "distributed.scheduler.worker-saturation": 1.0}
    if _forkserver():
        config["distributed.worker.multiprocessing-method"] = "forkserver"
    # kept for the cluster's whole life: nannies read the start method again when they restart a worker
    with dask.config.set(config):
        with _ctrl_c_deferred() as interrupted:
            try:
                cluster = LocalCluster(n_workers=workers or default_workers(), threads_per_worker=1,
                                       processes=True, silence_logs=logging.CRITICAL, **NO_DASHBOARD)
            except KeyboardInterrupt:
                _close_half_started_clusters()
                raise
        with cluster, Client(cluster) as client:
            if interrupted:
                raise KeyboardInterrupt
            yield client


@contextlib.contextmanager
def _ctrl_c_deferred() -> Iterator[list[int]]:
    """Hold a first Ctrl-C back while the cluster starts (about a second), so it is closed whole.

    A worker process interrupted half-way through its start finds the semaphores its parent already
    removed and prints a traceback of its own. The caller raises KeyboardInterrupt once the cluster is
    up, if the yielded list is not empty. A second Ctrl-C interrupts at once. Outside the main thread,
    where signal handlers cannot be set, nothing is deferred.
    """
    received: list[int] = []

    def hold(signum: int, frame: Any) -> None:
        if received:
            raise KeyboardInterrupt
        received.append(signum)

    try:
        previous = signal.signal(signal.SIGINT, hold)
    except ValueError:  # not the main thread
        yield received
        return
    try:
        yield received
    finally:
        signal.signal(signal.SIGINT, previous)


def _forkserver() -> bool:
    return "forkserver" in multiprocessing.get_all_start_methods()


def _start_fork_server() -> None:
    """Start multiprocessing's fork server now, importing :data:`WORKER_PRELOAD` there (POSIX only).

    Workers then start as forks of a process that already holds OCCT and the refiner, instead of
    each spawning a fresh interpreter that imports distributed, OCP and cadedge (1-2 s per worker and
    per restart, paid on the cores the tasks need). Started before this process imports dask, the
    server's imports run beside the client's import of distributed and the scheduler's start (on
    two idle cores, up to about 0.7 s less before the first file). dask's own choice of preloaded modules
    comes too late to apply. If the preload fails to import there, multiprocessing skips it and the
    task imports what it needs as usual. Nothing changes if the server is already running (a second batch
    in the same process).

    The server, and so every worker forked from it, ignores SIGINT: a Ctrl-C in the terminal reaches
    the whole process group, and a server or worker interrupted in the middle of its imports or its
    start printed a traceback of its own (or failed the cluster's start). This process handles the
    Ctrl-C alone and closes the cluster, which ends the workers.
    """
    if not _forkserver():
        return
    from multiprocessing import forkserver

    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(WORKER_PRELOAD)
    try:  # started with SIGINT ignored, which a new Python keeps: see above
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread: no handlers to change
        forkserver.ensure_running()
        return
    try:
        forkserver.ensure_running()
    finally:  # a handler installed outside Python reads back as None
        signal.signal(signal.SIGINT, signal.SIG_DFL if previous is None else previous)


def _close_half_started_clusters() -> None:
    """Close the LocalCluster whose start Ctrl-C interrupted, and forget it: left registered, distributed's
    exit hook closes it again and fails an assertion on its never-started workers (a traceback after the
    "interrupted" line)."""
    from distributed.deploy.spec import SpecCluster

    for cluster in list(SpecCluster._instances):
        try:
            cluster.close(timeout=10)
        except (AssertionError, TimeoutError, OSError, RuntimeError):  # the same assertion, or already gone
            pass
        SpecCluster._instances.discard(cluster)


def _failure_reason(future: Any) -> str:
    from distributed import KilledWorker

    if future.status == "cancelled":
        return "cancelled (scheduler lost or shutting down)"
    exc = future.exception()
    if isinstance(exc, KilledWorker):
        return WORKER_DIED
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


def _restart_worker_of(client: Any, key: str) -> str:
    """Restart the worker processing ``key``; returns what happened, for the failure reason."""
    workers = [addr for addr, keys in client.processing().items() if key in keys]
    if not workers:
        return "task no longer on a worker"
    status = client.restart_workers(workers, timeout=RESTART_SECONDS, raise_for_error=False)
    state = status.get(workers[0], "unknown")
    return "worker restarted" if state == "OK" else f"worker restart: {state}"


@dataclass
class _Running:
    job: Job
    submitted: float
    started: float | None = None


def _publishing(task: Task, topic: str, key: str, input: str, output: str,
                options: dict[str, Any]) -> dict[str, Any]:
    """Run ``task`` on a dask worker and log its summary under ``topic`` (see the module's docstring)."""
    from distributed import get_worker

    summary = task(input, output, options)
    try:
        get_worker().log_event(topic, {"key": key, "summary": summary})
    except TypeError:  # not msgpack-serialisable: the client fetches it from the worker instead
        pass
    return summary


def _fetch(future: Any, wait: float) -> tuple[dict[str, Any] | None, str | None] | None:
    """The summary of a finished task, or its failure reason; None if not fetched within ``wait``
    seconds (its worker is not answering, or its lost result is being computed again)."""
    try:
        return future.result(timeout=wait), None
    except TimeoutError:
        return None
    except Exception:  # cancelled, or computed again after its worker left and failed this time
        return None, _failure_reason(future)


def run_jobs(client: Any, jobs: list[Job], task: Task, options: dict[str, Any], *, timeout: float,
             on_outcome: Callable[[Outcome], None]) -> None:
    """Run ``task(job.input, job.output, options)`` for every job; call ``on_outcome`` as each ends.

    ``on_outcome`` runs in this (the client) process, in completion order; it is where the index is
    written, so the index has a single writer. When tasks end, their summaries are in hand, the freed
    worker threads get their next jobs, and the outcomes are recorded while those run.
    """
    from distributed import wait

    todo = deque(jobs)
    running: dict[Any, _Running] = {}
    unfetched: dict[Any, _Running] = {}  # finished, summary not fetched yet
    threads, asked = 0, -math.inf
    topic = f"cadedge-batch-{uuid.uuid4().hex}"
    published: dict[str, dict[str, Any]] = {}  # summaries logged by the tasks, by key

    def receive(event: tuple[float, dict[str, Any]]) -> None:
        published[event[1]["key"]] = event[1]["summary"]

    def top_up(refresh: bool) -> None:
        nonlocal threads, asked
        if not todo:
            return
        if refresh or monotonic() - asked > THREADS_SECONDS:
            threads, asked = max(1, sum(client.nthreads().values())), monotonic()
        while todo and len(running) + len(unfetched) < threads:
            job = todo.popleft()
            key = f"cadedge-batch-{uuid.uuid4().hex}"
            future = client.submit(_publishing, task, topic, key, job.input, job.output, options,
                                   pure=False, key=key)
            running[future] = _Running(job, monotonic())

    def elapsed(run: _Running, now: float) -> float:
        return now - (run.started if run.started is not None else run.submitted)

    client.subscribe_topic(topic, receive)
    try:
        top_up(True)
        while todo or running or unfetched:
            try:
                wait(list(running), timeout=POLL_SECONDS, return_when="FIRST_COMPLETED")
            except TimeoutError:
                pass
            ended = {future: running.pop(future) for future in [f for f in running if f.done()]}
            failed = {future: run for future, run in ended.items() if future.status != "finished"}
            fetched = []
            for future, run in [*unfetched.items(), *((f, r) for f, r in ended.items() if f not in failed)]:
                summary = published.pop(future.key, None)
                got = (summary, None) if summary is not None else _fetch(
                    future, REFETCH_SECONDS if future in unfetched else FETCH_SECONDS)
                if got is None:
                    unfetched[future] = run
                else:
                    unfetched.pop(future, None)
                    fetched.append((future, run, *got))
            # a failure may mean a worker left: ask for the threads again rather than queue on a busy one
            top_up(bool(failed) or any(error is not None for *_, error in fetched))
            now = monotonic()
            for future, run, summary, error in fetched:
                if error is None:
                    on_outcome(Outcome(run.job, "ok", summary, None, float(summary.get("seconds", elapsed(run, now)))))
                else:
                    on_outcome(Outcome(run.job, "failed", None, error, elapsed(run, now)))
            for future, run in failed.items():
                on_outcome(Outcome(run.job, "failed", None, _failure_reason(future), elapsed(run, now)))
            if any(run.started is None and now - run.submitted > POLL_SECONDS for run in running.values()):
                processing = set().union(*client.processing().values())
                for future, run in running.items():
                    if run.started is None and future.key in processing:
                        run.started = now
            timed_out = False
            for future, run in list(running.items()):
                if run.started is not None and now - run.started > timeout and not future.done():
                    del running[future]
                    what = _restart_worker_of(client, future.key)
                    future.cancel()
                    on_outcome(Outcome(run.job, "failed", None, f"timed out after {timeout:g} s ({what})",
                                       monotonic() - run.started))
                    timed_out = True
            if timed_out:
                top_up(True)
    finally:
        client.unsubscribe_topic(topic)
