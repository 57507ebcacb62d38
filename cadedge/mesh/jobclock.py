"""One time budget for a whole mesh job: ``timeout`` counts from the start of ``mesh_shape``, the caller's
steps before gmsh included.

Reading the shape and refining its edges must run, however long they take. The optional stages after them,
which fit the edge grids to the faces (the boundary fit for the area target, splits near small features
and across thin faces, the gradings), start only while the job has used under :data:`PREP_SHARE` of the
timeout; those left out are named in a note, and gmsh gets what is left: its watchdog's marks
(:mod:`cadedge.mesh.isolate`) count from the same start. cadquery-contrib's tetrakaidecahedron lattice
(10 182 faces, 25 300 edges) at 1e-2 spent over 6 minutes in those stages under ``--timeout 300``
before gmsh started, and gmsh then had its 300 s on top.
"""

from __future__ import annotations

import time

#: The grid-fitting stages start only while the job has used under this share of its timeout.
PREP_SHARE = 0.25


class JobClock:
    """The job's start (``time.monotonic()``) and timeout, and the fitting stages left out for want of time."""

    def __init__(self, timeout: float):
        self.started = time.monotonic()
        self.timeout = timeout
        self.skipped: list[str] = []
        self.skipped_at = 0.0  # seconds spent when the first stage was left out

    def spent(self) -> float:
        """Seconds since the job started."""
        return time.monotonic() - self.started

    def allows(self, name: str) -> bool:
        """Whether the fitting stage ``name`` may start: the job has used under :data:`PREP_SHARE` of its
        timeout. If not, ``name`` is noted as left out."""
        if self.spent() <= PREP_SHARE * self.timeout:
            return True
        self.skipped_at = self.skipped_at or self.spent()
        self.skipped.append(name)
        return False

    def note(self) -> str | None:
        """What the job left out for want of time, as a note; None if nothing."""
        if not self.skipped:
            return None
        return (f"the edge grids were meshed without {', '.join(self.skipped)}: the job had used "
                f"{self.skipped_at:.0f} s, over {PREP_SHARE:.0%} of --timeout ({self.timeout:g} s); a longer "
                "--timeout gives them")
