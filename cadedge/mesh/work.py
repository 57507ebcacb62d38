"""Budgets counted in work done, not in time taken, so that a model meshes the same way on every run.

The optional stages after gmsh's meshing (the face optimiser, MeshAdapt's retries) used to stop at a
share of the CPU time the job had taken: under load, or merely from one run to the next, they got to a
different point, and the same model gave different meshes (the Onshape gear at 1e-2: 167 462 to 167 902
triangles over four runs). With no bound at all its meshes were byte for byte the same, but took 72 s
instead of 40. A :class:`Meter` counts what a stage has done in units that do not depend on the machine
(triangles visited, triangles handed to gmsh again), and its limit is set from the job's own size. The
clock still bounds everything through ``--timeout`` (the soft deadline and ``finish_by`` of
:mod:`cadedge.mesh.isolate`): a job held by its timeout can still differ from run to run.
"""

from __future__ import annotations

import time


class Meter:
    """Work done against a limit (a count), and an optional ``deadline`` on ``time.time()``."""

    def __init__(self, limit: float = float("inf"), deadline: float | None = None):
        self.limit = limit
        self.deadline = deadline
        self.spent = 0.0

    def charge(self, units: float) -> None:
        """Count ``units`` of work done."""
        self.spent += units

    def left(self) -> float:
        """The work left before the limit (never negative)."""
        return max(0.0, self.limit - self.spent)

    def late(self) -> bool:
        """Whether the work has reached its limit or the clock passed the deadline: nothing more should
        start."""
        return self.spent >= self.limit or (self.deadline is not None and time.time() > self.deadline)

    def part(self, share: float) -> Meter:
        """A meter for one piece of the work: ``share`` of what is left, the same deadline. What it counts
        is added here with :meth:`settle`."""
        return Meter(share * self.left(), self.deadline)

    def settle(self, part: Meter) -> None:
        """Add what ``part`` (from :meth:`part`) counted."""
        self.spent += part.spent
