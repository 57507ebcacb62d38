"""Inside the gmsh job: curved faces far under the model's worst face are meshed again, coarser.

A model's fidelity is its worst face. Sizes chosen per surface type before meshing leave many curved
faces well under it (a fillet at 3e-3 beside a planar face at 5.6e-3), and their extra triangles buy
nothing. The level they may coarsen to is the worst face, or a share of the target where the worst face
is far under it (``COARSEN_FLOOR`` in :mod:`cadedge.mesh.fidelity`). Each such face is meshed again with ``Mesh.MeshSizeFromCurvature`` lowered by the measured
margin (deficit ~ N**-2; faces of like counts together, see :mod:`cadedge.mesh.remesh`; faces of
constant curvature whose triangles the lower count would hardly change are left as they are) and kept only
when it has fewer triangles and stays within the level; otherwise it is meshed again as it was (gmsh is
deterministic). Only the face's interior changes: its boundary
nodes stay, so neighbours stay conforming.
"""

from __future__ import annotations

import time

import numpy as np

from .interior import CONSTANT_CURVATURE

#: A curved face whose |deficit| is under this share of the level is meshed again coarser.
BELOW = 0.75
#: The coarser mesh aims at this share of the level.
AIM = 0.9
#: Bounds of the per-circle factor of one coarsening (at most halved, at least 10% fewer).
FACTOR = (0.5, 0.9)
#: A face of constant curvature (a cylinder, sphere or torus) is not meshed again where the lower count
#: would save less than this share of its triangles
#: (:meth:`~cadedge.mesh.interior.InteriorSizes.curvature_triangles`): its sizes come from its boundary
#: or ``Mesh.MeshSizeMax``. The 2.8 mm wall of an O-ring groove under a 0.2 mm fillet (boundary nodes
#: 0.04 mm apart along 500 mm) came out with the same 115 576 triangles at 23 per 2 pi as at 47, after 42 s
#: of meshing it twice. On other faces the samples can miss what sets the sizes (mesh_T106_V3's blade face
#: 1: 80 triangles predicted at 57 per 2 pi, 3 563 meshed, 1 461 after three passes), so they are tried.
SAVING_SHARE = 0.1
#: The surface types whose samples :data:`SAVING_SHARE` trusts: those of constant curvature, and cones,
#: whose curvature (``cos(half angle) / radius``) changes only along the axis, smoothly, as the samples
#: follow it. A narrow chamfer's cone has its triangles from its circles: the perforated plate's 240 at
#: 1e-3 were each meshed three more times for the same triangles (36 s of 160), and are now left alone.
PREDICTED = CONSTANT_CURVATURE | {"Cone"}
#: Passes: a face kept coarser is tried coarser again while it stays under ``BELOW * level``
#: (mesh_T106_V3's blade face at 1e-3, its deficit set by its loose boundary more than by its triangles:
#: 3.35e-4 at 4 604 triangles after one pass, 3.6e-4 at 2 902 after three; the model 8 961 -> 6 611).
PASSES = 3


def coarsen(ctx, *, level: float, deficit, per_circle: dict[int, float],
            measured: dict[int, float]) -> dict[int, float]:
    """Mesh the gmsh surfaces of ``measured`` (surface -> its deficit as meshed now) again coarser where
    their |deficit| is under ``BELOW * level`` (``deficit(s, mesh_area)`` measures a new mesh;
    ``per_circle[s]`` the count they were meshed with), up to :data:`PASSES` times. Returns the
    per-circle count of each face that kept a coarser mesh."""
    from .areas import unfolded_areas

    face_of = ctx.emap.face_of_surface
    kept: dict[int, float] = {}
    for _ in range(PASSES):
        more = _coarsen_once(ctx, level=level, deficit=deficit, per_circle=per_circle, measured=measured)
        if not more:
            break
        kept.update(more)
        again = [s for s in measured if face_of.get(s, s) in more]
        measured = {s: deficit(s, a) for s, a in unfolded_areas(again).items()}
        per_circle = {s: more[face_of.get(s, s)] for s in again}
    return kept


def _coarsen_once(ctx, *, level: float, deficit, per_circle: dict[int, float],
                  measured: dict[int, float]) -> dict[int, float]:
    """One pass of :func:`coarsen`."""
    import gmsh

    from .areas import unfolded_areas
    from .interior import SIZES, sized_per_circle
    from .remesh import job_groups, remesh_group

    face_of = ctx.emap.face_of_surface
    say = ctx.progress or (lambda line: None)
    kept: dict[int, float] = {}
    kinds = (ctx.job.options.get("fidelity") or {}).get("surface_types") or []

    def saves(s: int, n: float, fewer: float) -> bool:
        """Whether meshing ``s`` at ``fewer`` per 2 pi instead of ``n`` may save triangles (see
        :data:`SAVING_SHARE`)."""
        f = face_of.get(s, s)
        if not (1 <= f <= len(kinds) and kinds[f - 1] in PREDICTED):
            return True
        saving = SIZES.curvature_triangles(s, n) - SIZES.curvature_triangles(s, fewer)
        return saving >= SAVING_SHARE * len(gmsh.model.mesh.getElementsByType(2, s)[0])

    sized = {s: sized_per_circle(s, per_circle[s]) for s in measured}  # the count each was meshed at
    coarser = {s: sized[s] * float(np.clip(np.sqrt(max(abs(d), 1e-12) / (AIM * level)), *FACTOR))
               for s, d in measured.items() if abs(d) < BELOW * level and np.isfinite(d)}
    coarser = {s: n for s, n in coarser.items() if saves(s, sized[s], n)}
    for n, group in job_groups(coarser):  # faces of like counts in one gmsh call (see remesh.py)
        if ctx.job.deadline is not None and time.time() > ctx.job.deadline:
            break
        faces = " ".join(str(face_of.get(s, s)) for s in group)
        before = {s: len(gmsh.model.mesh.getElementsByType(2, s)[0]) for s in group}
        say(f"refine {faces}")  # same watchdog line as a refinement: a hang here keeps them as first meshed
        redo = remesh_group(group, n, face_of)
        areas = unfolded_areas([s for s in group if redo[s].ok])
        back = {}
        for s in group:
            if redo[s].ok and len(gmsh.model.mesh.getElementsByType(2, s)[0]) < before[s] and abs(
                    deficit(s, areas[s])) <= level:
                kept[face_of.get(s, s)] = n
            else:  # mesh it again as it was
                back[s] = sized[s]
        for n_back, again in job_groups(back, share=1.0):
            redo.update(remesh_group(again, n_back, face_of))
        ctx.outcomes.update(redo)
        say(f"refined {faces}")
    return kept
