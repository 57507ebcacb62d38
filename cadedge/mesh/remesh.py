"""Inside the gmsh job: faces meshed again with like curvature sizes share one gmsh call.

Every ``gmsh.model.mesh.generate`` call also walks the whole model (it turns every element back to first
order, orients every curve and surface mesh, measures every element's quality), so meshing faces again one
call each grew with the model: LLNL boxed_sphere at ALD 1e-3 (192 faces, 470k triangles) spent 0.8 s a
call, 63 s for the 79 faces the surface target meshed again finer or back as first meshed. Faces whose
``Mesh.MeshSizeFromCurvature`` is within 5% (boxed_sphere's families of identical faces) share one call
here, at the largest of their counts.
Only the faces' interiors change: their boundary curves keep their nodes, so neighbours stay conforming.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .strategies import Strategy

#: Faces meshed again in one gmsh call, at most (the watchdog bounds a call like one face attempt).
BATCH_FACES = 24
#: Faces whose per-circle counts are within this factor share a call, all at the largest of them (a
#: face meshed up to this much finer than it needs: about 10% more triangles at most on that face).
#: Identical faces are measured a few percent apart (their meshes are not identical).
SHARE = 1.05


def groups(per_circle: dict[int, float], share: float = SHARE, *,
           sizing: dict[int, str] | None = None) -> list[tuple[float, list[int]]]:
    """The gmsh surfaces of ``per_circle`` (surface -> count it needs) in groups whose counts are within
    ``share`` of each other (1: equal counts only), each at most :data:`BATCH_FACES` long, with the count
    to mesh the group with (its largest): ``[(count, surfaces), ...]``, smallest counts first. Surfaces
    sized differently (``sizing``: surface -> how; missing: by gmsh's curvature sizes) never share a group."""
    sizing = sizing or {}
    out: list[tuple[float, list[int]]] = []
    for how in sorted({sizing.get(s, "") for s in per_circle}):
        group: list[int] = []
        for s in sorted((s for s in per_circle if sizing.get(s, "") == how), key=lambda s: (per_circle[s], s)):
            if group and (per_circle[s] > share * per_circle[group[0]] or len(group) == BATCH_FACES):
                out.append((per_circle[group[-1]], group))
                group = []
            group.append(s)
        if group:
            out.append((per_circle[group[-1]], group))
    return sorted(out, key=lambda g: (g[0], g[1][0]))


def job_groups(per_circle: dict[int, float], share: float = SHARE) -> list[tuple[float, list[int]]]:
    """:func:`groups` for this job's surfaces: those the ``k**-1/2`` callback sizes
    (:data:`cadedge.mesh.interior.SIZES`), those held at a size floor and those on gmsh's curvature sizes
    apart, since one gmsh call has one ``Mesh.MeshSizeFromCurvature`` and one
    ``Mesh.AlgorithmSwitchOnFailure`` setting (see :func:`cadedge.mesh.interior.use_per_circle`)."""
    from .interior import SIZES

    sizing = {s: "floored" for s in SIZES.floors} | {s: "sampled" for s in SIZES.faces}
    return groups(per_circle, share, sizing=sizing)


def attempt_again(surfaces: list[int], strategy: Strategy) -> dict[int, str | None]:
    """Clear gmsh ``surfaces`` and mesh them again in one call with ``strategy`` at the gmsh options set
    now, the rest of the model hidden; per surface None if it passed, else gmsh's reason."""
    import gmsh

    from .generate import _attempt_many, clear

    clear([(2, s) for s in surfaces])
    gmsh.option.setNumber("Mesh.MeshOnlyEmpty", 1)
    gmsh.option.setNumber("Mesh.MeshOnlyVisible", 1)
    gmsh.model.setVisibility(gmsh.model.getEntities(), 0)
    try:
        return _attempt_many(surfaces, strategy)
    finally:
        gmsh.model.setVisibility(gmsh.model.getEntities(), 1)
        gmsh.option.setNumber("Mesh.MeshOnlyVisible", 0)


def mesh_again(surface: int, strategy: Strategy, per_circle: float, keep: Callable[[], bool]) -> bool:
    """Mesh gmsh ``surface`` again from scratch with ``strategy`` at ``per_circle`` (see
    :func:`cadedge.mesh.interior.use_per_circle`) and keep the new mesh if it meshed and ``keep()`` (called
    with it in place) says so; otherwise put the face's first mesh back. Returns whether the new mesh was
    kept (False, nothing tried, for a face without a readable mesh). Only the face's interior changes."""
    from .facemesh import read_face, write_interior
    from .interior import use_per_circle

    first = read_face(surface)
    if first is None:
        return False
    use_per_circle(surface, per_circle)
    if attempt_again([surface], strategy)[surface] is None and keep():
        return True
    write_interior(surface, first, first.x, first.tri, first.movable, first.uv)
    return False


def keep_closer(s: int, name: str, per_circle: float, measured: float, outcomes: dict,
                deficit: Callable[[float], float], *, within: float = float("inf"),
                min_angle: float = 0.0) -> float:
    """Mesh gmsh surface ``s`` (over its area target at ``measured``) again by the gmsh strategy ``name``
    at ``per_circle`` (the sizes it was meshed with); keep whichever mesh has the smaller area deficit
    (``deficit(mesh area)``), the new one only if that is at most ``within`` and its smallest angle at
    least ``min_angle`` degrees, and return it (``outcomes[s]`` names the strategy kept)."""
    import gmsh

    from .areas import unfolded_areas
    from .facemesh import triangle_min_angles
    from .outcomes import FaceOutcome
    from .strategies import STRATEGIES

    strategy = next(st for st in STRATEGIES if st.name == name)
    other = measured

    def closer() -> bool:
        nonlocal other
        other = deficit(unfolded_areas([s]).get(s, 0.0))
        if not (abs(other) < abs(measured) and abs(other) <= within):
            return False
        if min_angle <= 0:
            return True
        angles = triangle_min_angles(s)
        return angles is not None and float(angles.min()) >= min_angle

    if not mesh_again(s, strategy, per_circle, closer):
        return measured
    outcomes[s] = FaceOutcome(face=outcomes[s].face, surface=s, strategy=strategy.name,
                              triangles=len(gmsh.model.mesh.getElementsByType(2, s)[0]))
    return other


def keep_better_angles(s: int, name: str, per_circle: float, outcomes: dict, smallest: float) -> float:
    """Mesh gmsh surface ``s`` (its smallest angle ``smallest`` degrees now) again by the gmsh strategy
    ``name`` at ``per_circle`` and keep whichever mesh has the larger smallest angle; returns that angle
    (``outcomes[s]`` names the strategy kept)."""
    import gmsh

    from .facemesh import triangle_min_angles
    from .outcomes import FaceOutcome
    from .strategies import STRATEGIES

    strategy = next(st for st in STRATEGIES if st.name == name)
    best = smallest

    def better() -> bool:
        nonlocal best
        now = triangle_min_angles(s)
        if now is None or float(now.min()) <= best:
            return False
        best = float(now.min())
        return True

    if mesh_again(s, strategy, per_circle, better):
        outcomes[s] = FaceOutcome(face=outcomes[s].face, surface=s, strategy=strategy.name,
                                  triangles=len(gmsh.model.mesh.getElementsByType(2, s)[0]))
    return best


def remesh_group(surfaces: list[int], per_circle: float, face_of: dict[int, int]) -> dict:
    """Mesh gmsh ``surfaces`` (one group of :func:`job_groups`) again from scratch in one call at
    ``per_circle`` triangles per ``2 pi`` (see :func:`cadedge.mesh.interior.use_per_circle`); a face that
    call fails, or whose first strategy is not gmsh's (a face laid flat, :func:`~cadedge.mesh.strategies.face_order`),
    is meshed again on its own through every strategy (:func:`cadedge.mesh.fidelity.remesh_face`).
    Returns each surface's :class:`~cadedge.mesh.outcomes.FaceOutcome`."""
    import gmsh

    from .fidelity import remesh_face
    from .interior import use_per_circle
    from .outcomes import FaceOutcome
    from .strategies import STRATEGIES, face_order

    for s in surfaces:  # one group is sized one way (see job_groups), so the gmsh options agree
        use_per_circle(s, per_circle)
    together = [s for s in surfaces if face_order(s)[0] == 0]  # the others are meshed first another way
    reasons = attempt_again(together, STRATEGIES[0]) if together else {}
    out = {}
    for s in surfaces:
        if reasons.get(s, "") is None:
            out[s] = FaceOutcome(face=face_of.get(s, s), surface=s, strategy=STRATEGIES[0].name,
                                 triangles=len(gmsh.model.mesh.getElementsByType(2, s)[0]))
        else:
            out[s] = remesh_face(s, per_circle, face_of)
    return out
