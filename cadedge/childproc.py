"""Child processes that end with their caller: the environment a parent gives them, the guard they run.

cadedge runs native code that can crash or hang (gmsh in :mod:`cadedge.mesh.isolate`, OCCT on a damaged
file in :mod:`cadedge.occt.isolate`) in a ``python -m`` child. Whatever ends the caller (SIGKILL, a
SIGTERM Python does not handle, a crash, a batch worker restarted), the child must not go on as an
orphan, meshing or hanging with nobody to time it or read its result: :func:`die_with_parent`, called
first thing in the child, arms Linux's parent-death signal (``PR_SET_PDEATHSIG``, SIGKILL from the
kernel, which works even while native code holds the interpreter) or, where that is missing, starts a
thread that watches the parent's id.
"""

from __future__ import annotations

import os
import sys

#: Environment variable naming the process that started the child.
PARENT_ENV = "CADEDGE_PARENT_PID"
#: Linux's prctl option for a signal on the parent's death.
PR_SET_PDEATHSIG = 1
#: Seconds between checks of the parent's id where prctl is missing.
PARENT_POLL = 1.0


def child_env() -> dict[str, str]:
    """The environment for a ``python -m cadedge...`` child: this one, the caller's import path (so the
    child imports the same cadedge) and the caller's pid for :func:`die_with_parent`."""
    return dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p), **{PARENT_ENV: str(os.getpid())})


def die_with_parent() -> None:
    """End this process when the one named by :data:`PARENT_ENV` ends (a no-op without it)."""
    import ctypes
    import signal

    parent = int(os.environ.get(PARENT_ENV) or 0)
    if not parent:
        return
    try:
        armed = ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL) == 0
    except (OSError, AttributeError):  # no prctl on this platform
        armed = False
    if os.getppid() != parent:  # the parent ended before the signal was armed
        os._exit(1)
    if not armed:
        import threading
        import time

        def watch() -> None:
            while os.getppid() == parent:
                time.sleep(PARENT_POLL)
            os._exit(1)

        threading.Thread(target=watch, name="cadedge-parent-watch", daemon=True).start()
