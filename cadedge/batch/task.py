"""The per-file work of a batch, run inside a dask worker: refine one model file, write its JSON.

A task is any picklable callable ``task(input, output, options) -> dict`` returning the summary the
index records (``edges``, ``segments``, ``worst_ald``, optionally ``seconds`` and ``warnings``, a
list of strings); it raises on failure. Its output is written
atomically by the worker straight into the output folder (a shared file system for remote workers).
"""

from __future__ import annotations

import time
from typing import Any


def refine_task(input: str, output: str, options: dict[str, Any]) -> dict[str, Any]:
    """``cadedge.refine_shape(input, **options)`` then ``grid.write(output)``; returns its summary."""
    from .. import refine_shape

    t0 = time.perf_counter()
    grid = refine_shape(input, **options)
    grid.write(output)
    return {"edges": len(grid.edges), "segments": grid.segments, "worst_ald": grid.max_ald_estimate,
            "seconds": time.perf_counter() - t0, "warnings": [str(w) for w in grid.warnings]}
