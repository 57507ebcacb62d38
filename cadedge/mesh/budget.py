"""How many triangles one face may take, and the size that fills a face with that many.

Sizes that follow a face's curvature, or the spacing of a sharp ridge along its boundary, can ask for more
triangles than gmsh makes within the time of one attempt (a blade with a 0.007 mm trailing edge: 0.006 mm
sizes over 390 mm2). Wherever a size is set from curvature, it stops at :func:`filling_size`: the one-size
strategy, the ``.geo`` export's per-face sizes, the interior floor of faces with sharp ridges, and the
boundary splits of the surface target (:func:`cadedge.mesh.boundary_fit.fit_boundaries`).
"""

from __future__ import annotations

import numpy as np

#: A face gets at most about this many triangles from sizes set by curvature.
MAX_FACE_TRIANGLES = 400_000


def filling_size(area):
    """The size whose triangles fill a face of ``area`` (a number or an array) about
    :data:`MAX_FACE_TRIANGLES` times: an equilateral triangle of side ``h`` covers ``h**2 / 2.3``."""
    return np.sqrt(2.3 * np.abs(area) / MAX_FACE_TRIANGLES)
