"""Inside the gmsh job: faces Frontal-Delaunay left with poor triangles, meshed again by MeshAdapt.

gmsh's Frontal-Delaunay places its nodes in the face's parameter plane, sized by the surface's metric
there. Where that metric degenerates inside a face, it crowds nodes: surf114.igs (a pythonocc-demos
model) has two lens-shaped B-spline faces whose ``u`` iso-lines shrink to a point at two places inside
them, where the face's long sides cross at about 50 degrees. Frontal-Delaunay put nodes 0.0002 mm
apart there and left 14-23% of those faces' triangles under 20 degrees, down to 0.3 degrees, which the
face optimiser could not lift. gmsh's MeshAdapt refines by splitting, collapsing and swapping edges
measured in 3-D, and meshed the same faces at the same sizes with 1-3% under 20 degrees and none under
7 degrees.

So after the surface target's passes (:mod:`cadedge.mesh.fidelity`) and before the face optimiser
(:mod:`cadedge.mesh.optimize`), every face Frontal-Delaunay meshed with more than :data:`POOR_SHARE` of
its triangles under :data:`~cadedge.mesh.quality.GOOD_DEG` degrees is meshed again by MeshAdapt at the
sizes it had. A face with only a few small angles is left to the optimiser: the M6 screw's thread flank
at 1e-3 (28 454 triangles, none under 20 degrees but one corner of 2.2) took MeshAdapt 33 s for the
same smallest angle. The new mesh is kept when it is no worse in both figures, clearly better in one
(:func:`better`), and its area deficit stays within the target (or no larger than before); otherwise the
face gets its first mesh back (:func:`cadedge.mesh.remesh.mesh_again`).

A planar face Frontal-Delaunay left with a triangle under :data:`FAN_ANGLE` is first meshed again by
gmsh's Delaunay, kept if its smallest angle is larger, however many more triangles it has: bounded by
a circle cut far finer than the face (7 682 segments of 0.029 mm round a 70 mm disk, for the grid of
its 0.2 mm edge fillet: :mod:`cadedge.mesh.gridded`), Frontal-Delaunay can join the boundary to a few
nodes 0.5 mm inside, a fan of 10 762 triangles at 1.7 degrees that MeshAdapt's grading (50 000, 15 s)
would exceed the triangle bound with; Delaunay grades it inwards in under a second (49 838, 34.7
degrees once optimised). A face held at a size floor
(:mod:`cadedge.mesh.floored`, as surf114's are) is meshed with gmsh's switch to other algorithms on
failure off, as it was first meshed: gmsh's whole fallback chain never finished on such faces. Only a
face's interior changes: its boundary curves keep their nodes, so neighbours stay conforming.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

#: A face with a larger share of its triangles under ``GOOD_DEG`` is meshed again by MeshAdapt. Faces at
#: 1-2% are left to the optimiser: the propeller's and sharp_blade's blade faces at 1e-3 (1.6-1.7%, 7 000
#: to 23 000 triangles each) took MeshAdapt 25-30 s a face, for a smallest angle of 0 degrees or four
#: times the triangles.
POOR_SHARE = 0.05
#: MeshAdapt's mesh must improve the share under ``GOOD_DEG`` by this fraction of it, or the smallest angle
#: by :data:`GAIN_DEG` degrees (razor_wing's 0.12 mm thin wing at 1e-3: 44.2% -> 44.1%, which no one needs).
GAIN = 0.1
GAIN_DEG = 1.0
#: MeshAdapt's mesh may have at most this many times the triangles of the face's first mesh, or
#: :data:`HALVING_GROWTH` times where it at least halves the share under ``GOOD_DEG``: surf114's second
#: lens face at 1e-2, 26.7% -> 4.0% under 20 degrees and 0.1 -> 2.6 degrees at 1 274 -> 2 294 triangles,
#: was left as Frontal-Delaunay made it.
GROWTH = 1.5
HALVING_GROWTH = 2.0
#: No retry starts once the faces retried hold this share of the triangles meshed (all faces of the job),
#: or :data:`MIN_TRIANGLES` where that is more (times the job's share, ``MeshJob.share``, for a split
#: job's shard; the poorest faces go first): a budget counted in triangles, not in time, so that a model
#: meshes the same way on every run (:mod:`cadedge.mesh.work`). MeshAdapt takes about ten times the CPU a
#: triangle that the job took before it (the Onshape gear's 3 000-4 800-triangle faces at 1e-2:
#: 1.1-2.5 ms a triangle, against 1.5e-4 s for everything before), so this is about half of that time, at
#: least about 10 s, as the CPU-time budget it replaces. It can be slower still on B-spline faces:
#: wing_fuselage's fuselage face at 1e-3 (3 753 triangles) took it 61 s.
BUDGET_SHARE = 0.05
MIN_TRIANGLES = 6_000
#: The strategy name a face kept as MeshAdapt meshed it is recorded with (``FaceOutcome.strategy``).
MESH_ADAPT = "MeshAdapt"
#: A planar face Frontal-Delaunay meshed with a triangle under this many degrees is meshed by Delaunay
#: too, and keeps the mesh with the larger smallest angle (see the module docstring).
FAN_ANGLE = 10.0


def face_quality(surface: int) -> tuple[float, float, int] | None:
    """Gmsh surface ``surface``'s smallest triangle angle (degrees), its share of triangles under
    :data:`~cadedge.mesh.quality.GOOD_DEG` and its triangle count; None if it has no (readable) triangles."""
    from .facemesh import triangle_min_angles
    from .quality import GOOD_DEG

    angles = triangle_min_angles(surface)
    if angles is None:
        return None
    return float(angles.min()), float(np.mean(angles < GOOD_DEG)), len(angles)


def poor(quality: tuple[float, float, int]) -> bool:
    """Whether a face of this :func:`face_quality` is worth meshing again."""
    return quality[1] > POOR_SHARE


def better(new: tuple[float, float, int], old: tuple[float, float, int]) -> bool:
    """Whether quality ``new`` beats ``old``: no lower smallest angle, no larger share under 20 degrees,
    at most :data:`GROWTH` times the triangles (:data:`HALVING_GROWTH` where the share is halved), and a
    share at least :data:`GAIN` smaller or a smallest angle :data:`GAIN_DEG` larger."""
    growth = HALVING_GROWTH if new[1] <= 0.5 * old[1] else GROWTH
    return (new[0] >= old[0] and new[1] <= old[1] and new[2] <= growth * old[2]
            and (new[1] <= (1.0 - GAIN) * old[1] or new[0] >= old[0] + GAIN_DEG))


def after_generate(ctx) -> None:
    """Hook (after :func:`cadedge.mesh.fidelity.after_generate`): mesh the poor faces again by MeshAdapt
    and keep the better mesh (see the module docstring), the poorest first, each where its triangles fit
    what is left of :data:`BUDGET_SHARE` of the job's triangles (at least :data:`MIN_TRIANGLES`), before
    the job's soft deadline. Each attempt
    is announced as ``refine F`` / ``refined F``: the watchdog bounds it like a refinement, and a hang or
    crash there keeps the face as first meshed (it joins ``job.no_refine``, which this hook skips)."""
    import gmsh

    from .areas import unfolded_areas
    from .floored import DELAUNAY
    from .remesh import keep_better_angles, mesh_again
    from .strategies import STRATEGIES
    from .work import Meter

    opts = ctx.job.options.get("fidelity")
    if not opts:
        return
    target = opts["surface_ald"]
    areas = np.asarray(opts["brep_areas"], dtype=float)
    face_of = ctx.emap.face_of_surface
    done = getattr(ctx, "fidelity", None) or {}
    counts = {**done.get("refined", {}), **done.get("coarsened", {})}  # face -> the count it was meshed at
    adapt = next(st for st in STRATEGIES if st.name == MESH_ADAPT)
    say = ctx.progress or (lambda line: None)
    first = STRATEGIES[0].name  # each face Frontal-Delaunay meshed, and how well
    measured = {s: q for s, outcome in ctx.outcomes.items()
                if outcome.ok and outcome.strategy == first and face_of.get(s, s) not in ctx.job.no_refine
                and (q := face_quality(s)) is not None}
    for s, q in measured.items():  # planes Frontal-Delaunay fanned: Delaunay grades them
        f = face_of.get(s, s)
        if (opts["meshed_kinds"][f - 1] == "Plane" and q[0] < FAN_ANGLE
                and not (ctx.job.deadline is not None and time.time() > ctx.job.deadline)):
            say(f"refine {f}")
            keep_better_angles(s, DELAUNAY, opts["per_circle"], ctx.outcomes, q[0])
            say(f"refined {f}")
    quality = {s: q for s, q in measured.items()  # a face kept as Delaunay made it is not tried again
               if ctx.outcomes[s].strategy == first and 1 <= (f := face_of.get(s, s)) <= len(areas)
               and areas[f - 1] > 0 and poor(q)}
    meter = Meter(max(MIN_TRIANGLES * ctx.job.share, BUDGET_SHARE * len(gmsh.model.mesh.getElementsByType(2)[0])),
                  ctx.job.deadline)
    for s in sorted(quality, key=lambda s: (-quality[s][1], s)):  # the poorest first
        if meter.late():
            break
        outcome, f, old = ctx.outcomes[s], face_of.get(s, s), quality[s]
        if old[2] > meter.left():  # this face alone would overrun what is left: a smaller one may fit
            continue
        meter.charge(old[2])
        before = 1.0 - unfolded_areas([s]).get(s, 0.0) / areas[f - 1]

        def improved() -> bool:  # called at once, with the new mesh in place
            new = face_quality(s)
            return (new is not None and better(new, old)
                    and abs(1.0 - unfolded_areas([s]).get(s, 0.0) / areas[f - 1]) <= max(target, abs(before)))

        say(f"refine {f}")
        if mesh_again(s, adapt, counts.get(f, opts["face_per_circle"].get(f, opts["per_circle"])), improved):
            triangles = len(gmsh.model.mesh.getElementsByType(2, s)[0])
            ctx.outcomes[s] = dataclasses.replace(outcome, strategy=adapt.name, triangles=triangles)
        say(f"refined {f}")
