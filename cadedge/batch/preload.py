"""What the batch fork server imports once for all its workers: dask, OCCT (through cadedge's OCCT layer),
the JSON writer and the task (:data:`cadedge.batch.runner.WORKER_PRELOAD` names this module).

The imports run with the garbage collector off and are then frozen (``gc.freeze``): they are a few
hundred thousand objects that live as long as the process, and with the collector on the growing heap
is traversed again and again while they load (about 0.15 s of the server's 1.3 s of CPU). Frozen, the
workers forked from the server never traverse them either, so their pages stay shared with the server
instead of being touched by each worker's collections. OpenBLAS (numpy's BLAS) gets one thread unless
``OPENBLAS_NUM_THREADS`` is set: each worker is single-threaded and the refiner makes no BLAS call large
enough to share.
"""

from __future__ import annotations

import gc
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
gc.disable()
try:
    import distributed  # noqa: F401

    import cadedge.batch.task  # noqa: F401
    import cadedge.exporters.json  # noqa: F401
    import cadedge.occt.shape  # noqa: F401
    import cadedge.occt.step  # noqa: F401
finally:
    gc.freeze()
    gc.enable()
