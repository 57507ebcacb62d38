"""numba compilation for the refiner's inner loops (exploration, node placement, spline evaluation).

A refine runs these loops a few times per edge on short arrays, where numpy's per-call overhead
dominated; compiled, they cost microseconds. Kernels are cached on disk (``cache=True``): the first
run after installing compiles them (about 5 s), later processes load them in a fraction of a second.
``nogil`` lets threads run them side by side.
"""

from __future__ import annotations

import math

import numba

#: The decorator for every cadedge kernel.
jit = numba.njit(cache=True, nogil=True)


@jit
def distance(p, i, q, j):
    """``|q[j] - p[i]|`` for rows of (n, 3) point arrays."""
    dx = q[j, 0] - p[i, 0]
    dy = q[j, 1] - p[i, 1]
    dz = q[j, 2] - p[i, 2]
    return math.sqrt(dx * dx + dy * dy + dz * dz)
