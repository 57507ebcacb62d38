"""Many models at once: ``run_batch`` refines STEP, IGES and BREP files on dask.distributed, resumably.

Modules: :mod:`.inputs` (expand and name inputs), :mod:`.index` (the SQLite index), :mod:`.runner`
(dask cluster, submission, timeouts, crashes), :mod:`.task` (the per-file work), :mod:`.run`
(``run_batch``), :mod:`.report` (results). See docs/batch.md.
"""

from __future__ import annotations

from .index import INDEX_NAME, BatchIndex
from .inputs import expand_inputs, output_names
from .report import BatchProgress, BatchReport, FileResult
from .run import DEFAULT_TIMEOUT, run_batch
from .runner import WORKER_DIED
from .task import refine_task

__all__ = ["run_batch", "BatchReport", "BatchProgress", "FileResult", "BatchIndex", "INDEX_NAME",
           "expand_inputs", "output_names", "refine_task", "DEFAULT_TIMEOUT", "WORKER_DIED"]
