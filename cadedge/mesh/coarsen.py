"""Inside the gmsh job: curved faces far under the model's worst face are meshed again, coarser.

A model's fidelity is its worst face. Sizes chosen per surface type before meshing leave many curved
faces well under it (a fillet at 3e-3 beside a planar face at 5.6e-3), and their extra triangles buy
nothing. The level they may coarsen to is the worst face, or a share of the target where the worst face
is far under it (``COARSEN_FLOOR`` in :mod:`cadedge.mesh.fidelity`). Each such face is meshed again with ``Mesh.MeshSizeFromCurvature`` lowered by the measured
margin (deficit ~ N**-2; faces of like counts together, see :mod:`cadedge.mesh.remesh`) and kept only
when it has fewer triangles and stays within the level; otherwise its mesh as it was is put back (meshed
again instead, a face whose kept mesh was Delaunay's, see :func:`cadedge.mesh.floored.try_delaunay`,
came back as Frontal-Delaunay's: sharp_blade's face 3 at 2.6e-2 where it had been at 4.4e-3). Only the
face's interior changes: its boundary nodes stay, so neighbours stay conforming.
"""

from __future__ import annotations

import time

import numpy as np

#: A curved face whose |deficit| is under this share of the level is meshed again coarser.
BELOW = 0.75
#: The coarser mesh aims at this share of the level.
AIM = 0.9
#: Bounds of the per-circle factor of one coarsening (at most halved, at least 10% fewer).
FACTOR = (0.5, 0.9)


def coarsen(ctx, *, level: float, deficit, per_circle: dict[int, float],
            measured: dict[int, float]) -> dict[int, float]:
    """Mesh the gmsh surfaces of ``measured`` (surface -> its deficit as meshed now) again coarser where
    their |deficit| is under ``BELOW * level`` (``deficit(s, mesh_area)`` measures a new mesh;
    ``per_circle[s]`` the count they were meshed with). Returns the per-circle count of each face that
    kept a coarser mesh."""
    import gmsh

    from .facemesh import read_face, write_interior
    from .fidelity import gmsh_surface_areas
    from .remesh import job_groups, remesh_group

    face_of = ctx.emap.face_of_surface
    say = ctx.progress or (lambda line: None)
    kept: dict[int, float] = {}
    coarser = {s: per_circle[s] * float(np.clip(np.sqrt(max(abs(d), 1e-12) / (AIM * level)), *FACTOR))
               for s, d in measured.items() if abs(d) < BELOW * level and np.isfinite(d)}
    for n, group in job_groups(coarser):  # faces of like counts in one gmsh call (see remesh.py)
        if ctx.job.deadline is not None and time.time() > ctx.job.deadline:
            break
        faces = " ".join(str(face_of.get(s, s)) for s in group)
        before = {s: read_face(s) for s in group}
        say(f"refine {faces}")  # same watchdog line as a refinement: a hang here keeps them as first meshed
        redo = remesh_group(group, n, face_of)
        areas = gmsh_surface_areas([s for s in group if redo[s].ok])
        for s in group:
            old = before[s]
            if redo[s].ok and (old is None or len(gmsh.model.mesh.getElementsByType(2, s)[0]) < len(old.tri)) \
                    and abs(deficit(s, areas[s])) <= level:
                kept[face_of.get(s, s)] = n
                ctx.outcomes[s] = redo[s]
            elif old is not None:  # its mesh as it was, put back
                write_interior(s, old, old.x, old.tri, old.movable, old.uv)
        say(f"refined {faces}")
    return kept
