"""How many triangles one face may take, and the size that fills a face with that many.

Sizes that follow a face's curvature, or the spacing of a sharp ridge along its boundary, can ask for more
triangles than gmsh makes within the time of one attempt (a blade with a 0.007 mm trailing edge: 0.006 mm
sizes over 390 mm2). Wherever a size is set from curvature, it stops at :func:`filling_size`: the one-size
strategy, the ``.geo`` export's per-face sizes, the interior floor of faces with sharp ridges, the
boundary splits of the surface target (:func:`cadedge.mesh.boundary_fit.fit_boundaries`), and gmsh's own
curvature sizes through the count per ``2 pi`` they are given (:func:`budget_per_circle`).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

#: A face gets at most about this many triangles from sizes set by curvature, at the default bound on one
#: face attempt (:data:`BUDGET_BOUND`); a gmsh job bounded longer holds its own (:func:`job_budget`).
MAX_FACE_TRIANGLES = 400_000
#: The bound on one face attempt (CPU seconds: a fifth of the default ``--timeout``) that
#: :data:`MAX_FACE_TRIANGLES` is set for: gmsh's Frontal-Delaunay makes 375 000 triangles on a torus in
#: about 27 s of CPU.
BUDGET_BOUND = 60.0


def job_budget(attempt_bound: float | None) -> int:
    """The per-face triangle budget of a gmsh job whose face attempts are bounded at ``attempt_bound`` CPU
    seconds: :data:`MAX_FACE_TRIANGLES`, raised in proportion to a longer bound (``--timeout 600``:
    800 000), so a longer timeout buys finer faces where the budget holds them."""
    if attempt_bound is None or attempt_bound <= BUDGET_BOUND:
        return MAX_FACE_TRIANGLES
    return int(MAX_FACE_TRIANGLES * attempt_bound / BUDGET_BOUND)


@contextmanager
def held(budget: int) -> Iterator[None]:
    """:data:`MAX_FACE_TRIANGLES` set to ``budget`` for what runs inside (one gmsh job in this process)."""
    global MAX_FACE_TRIANGLES
    before, MAX_FACE_TRIANGLES = MAX_FACE_TRIANGLES, budget
    try:
        yield
    finally:
        MAX_FACE_TRIANGLES = before


def filling_size(area):
    """The size whose triangles fill a face of ``area`` (a number or an array) about
    :data:`MAX_FACE_TRIANGLES` times: an equilateral triangle of side ``h`` covers ``h**2 / 2.3``."""
    return np.sqrt(2.3 * np.abs(area) / MAX_FACE_TRIANGLES)


def curvature_triangles(k: np.ndarray, da: np.ndarray, per_circle: float, lo: float = 0.0,
                        hi: float = np.inf) -> float:
    """About how many triangles curvature sizes ``2 pi / (per_circle k)``, held within ``[lo, hi]``, put on
    a face sampled at curvatures ``k`` standing for areas ``da``."""
    with np.errstate(divide="ignore"):
        h = np.clip(2.0 * np.pi / (per_circle * np.asarray(k, dtype=float)), lo, hi)
    return float(np.sum(2.3 * np.asarray(da, dtype=float) / h ** 2))


#: Bisection steps (on log of the count) of :func:`budget_per_circle`.
STEPS = 60


def budget_per_circle(k: np.ndarray, da: np.ndarray, lo: float = 0.0, hi: float = np.inf) -> float:
    """The largest count per ``2 pi`` (gmsh's ``Mesh.MeshSizeFromCurvature``) whose curvature sizes put at
    most :data:`MAX_FACE_TRIANGLES` on a face sampled at curvatures ``k`` standing for areas ``da``
    (:func:`curvature_triangles`); infinite where no count passes it (sizes held at ``lo``) or the count
    does not matter (sizes held at ``hi`` pass it already). For one curvature and no bounds it is
    ``2 pi / (k * filling_size(area))``."""
    if lo > 0 and 2.3 * float(np.sum(da)) / lo ** 2 <= MAX_FACE_TRIANGLES:
        return np.inf
    if not np.any(np.asarray(k) > 0) or curvature_triangles(k, da, 1e-12, lo, hi) > MAX_FACE_TRIANGLES:
        return np.inf
    a, b = np.log(1e-12), np.log(1e12)
    for _ in range(STEPS):
        mid = 0.5 * (a + b)
        if curvature_triangles(k, da, float(np.exp(mid)), lo, hi) > MAX_FACE_TRIANGLES:
            b = mid
        else:
            a = mid
    return float(np.exp(a))
