"""Test-only batch tasks and cluster set-up, importable by dask workers (tests/ is on their sys.path).

The tasks run the real refine task except for one input chosen by name, which kills its worker
process (as an OCCT crash would) or blocks in C code holding the GIL (as a stuck OCCT call would).
"""

from __future__ import annotations

import contextlib
import ctypes
import gc
import json
import logging
import os
import signal
import sys
from pathlib import Path
from typing import Any, Iterator

from cadedge.batch import refine_task
from cadedge.batch.runner import NO_DASHBOARD

CRASH_STEM = "crash_me"
HANG_STEM = "hang_me"


def crash_or_refine(input: str, output: str, options: dict[str, Any]) -> dict[str, Any]:
    """SIGKILL this worker process for the input named ``crash_me*``; refine any other."""
    if Path(input).stem.startswith(CRASH_STEM):
        os.kill(os.getpid(), signal.SIGKILL)
    return refine_task(input, output, options)


def probe_and_refine(input: str, output: str, options: dict[str, Any]) -> dict[str, Any]:
    """Record what the worker held before its first file (next to ``output``, as ``*.probe``), then refine."""
    probe = {"frozen": gc.get_freeze_count(), "ocp": "OCP.BRepAdaptor" in sys.modules,
             "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS")}
    Path(output).with_suffix(".probe").write_text(json.dumps(probe))
    return refine_task(input, output, options)


def hang_or_refine(input: str, output: str, options: dict[str, Any]) -> dict[str, Any]:
    """Sleep an hour inside libc with the GIL held for ``hang_me*`` (a PyDLL call never releases it)."""
    if Path(input).stem.startswith(HANG_STEM):
        ctypes.PyDLL(None).sleep(3600)
    return refine_task(input, output, options)


def unpublishable_refine(input: str, output: str, options: dict[str, Any]) -> dict[str, Any]:
    """Refine, with a summary that msgpack cannot carry (a ``Path`` in it): it cannot travel as an event."""
    return {**refine_task(input, output, options), "written": Path(output)}


def wait_for_workers(address: str, n: int) -> None:
    """Wait until the scheduler at ``address`` has ``n`` workers: the nannies restart killed workers in
    their own time (a fresh interpreter importing distributed: tens of seconds on a loaded machine, longer
    than the 30 s a batch waits for its first worker)."""
    from distributed import Client

    with Client(address) as client:
        client.wait_for_workers(n, timeout=300)


@contextlib.contextmanager
def local_cluster(n_workers: int = 2) -> Iterator[Any]:
    """A LocalCluster configured like the embedded one (no task retries after a worker death)."""
    import dask
    from distributed import LocalCluster

    with dask.config.set({"distributed.scheduler.allowed-failures": 0,
                          "distributed.scheduler.worker-saturation": 1.0}):
        cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                               silence_logs=logging.CRITICAL, **NO_DASHBOARD)
    with cluster:
        yield cluster
