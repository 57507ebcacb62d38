"""Inside the gmsh job: faces held at a size floor meshed by both of gmsh's Delaunay algorithms.

A face whose curvature has a ridge much sharper than its size floor (see
:func:`cadedge.mesh.interior.size_floors`) is meshed by Frontal-Delaunay like any other, and when it is
over its area target, again by Delaunay at the same sizes; the mesh nearer its B-rep area is kept
(:func:`try_delaunay`, called by :func:`cadedge.mesh.fidelity.after_generate` on every pass).
"""

from __future__ import annotations

from typing import Callable

#: The strategy name a face kept as gmsh's Delaunay meshed it is recorded with (``FaceOutcome.strategy``).
DELAUNAY = "Delaunay"


def try_delaunay(s: int, per_circle: float, measured: float, outcomes: dict,
                 deficit: Callable[[float], float]) -> float:
    """Mesh gmsh surface ``s`` (a face held at a size floor, over its target at ``measured``) again by
    gmsh's Delaunay at ``per_circle`` (the sizes it was meshed with); keep whichever mesh has the smaller
    area deficit (``deficit(mesh area)``) and return it (``outcomes[s]`` names the strategy kept:
    :func:`cadedge.mesh.remesh.keep_closer`).

    Across a ridge much sharper than the floor, Frontal-Delaunay left triangles that join the two sides of
    the propeller's blades (``scripts/hard_models.py``) straight through the solid, edges of 0.3-0.8 mm
    across a 0.02 mm leading edge: a blade face 1.9e-2 short at ``--ald 1e-2`` and a single such blade
    2.4e-2, finer or not; Delaunay follows the ridge there (8.6e-3 to 1e-2). Neither is better everywhere,
    so both are measured: at ``--ald 1e-3`` Frontal-Delaunay's first mesh of a blade face was 1.05e-2
    short and Delaunay's 4.1e-3, and meshed finer 2.2e-3 against 1.2e-3."""
    from .remesh import keep_closer

    return keep_closer(s, DELAUNAY, per_circle, measured, outcomes, deficit)
