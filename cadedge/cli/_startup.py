"""The console script's start-up: OCP's import without the garbage collector.

Importing OCP creates a few hundred thousand Python objects (its classes, functions, enums and
docstrings), all alive until the process ends. With the collector on, the growing heap is traversed
again and again while they load (about 0.2 s of CPU), and once more by the collection at interpreter
exit (about 0.3 s), for nothing: none of them is ever garbage. In a process the CLI owns
(:func:`own_process`, called by the console script and ``python -m cadedge``), :func:`heavy_imports`
therefore loads them with the collector off and then moves them out of its reach (``gc.freeze``);
objects made afterwards are collected as usual. It also asks OpenBLAS (numpy's BLAS) for one thread
unless ``OPENBLAS_NUM_THREADS`` is set: its worker threads start with numpy and spin while idle (about
0.07 s of CPU on two cores), and the refiner makes no BLAS call large enough to share. Called
in-process (``main(argv)`` from Python) it does nothing: these are the process owner's choices, not a
library's.
"""

from __future__ import annotations

import gc
import os
import sys
from contextlib import contextmanager
from typing import Iterator

_owner = False


def own_process() -> None:
    """Declare the running process the CLI's own (the console script, ``python -m cadedge``)."""
    global _owner
    _owner = True


@contextmanager
def heavy_imports() -> Iterator[None]:
    """Run the block (a subcommand's imports of OCP, numpy) with the collector off, then freeze what
    it made, OpenBLAS on one thread; a no-op unless :func:`own_process` was called and the collector is on."""
    if not (_owner and gc.isenabled()):
        yield
        return
    if "numpy" not in sys.modules:
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    gc.disable()
    try:
        yield
    finally:
        gc.freeze()
        gc.enable()
