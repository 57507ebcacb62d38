"""The ways a face is meshed: gmsh's 2-D algorithms at other sizes, split or gmsh-meshed boundaries, faces
laid flat, and the order each kind of face tries them in (:mod:`cadedge.mesh.generate` runs them)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Strategy:
    """One way to mesh a face: gmsh's 2-D ``algorithm``, a factor on the sizes, and whether to split the
    face's boundary segments first."""

    name: str
    algorithm: int
    size_factor: float = 1.0
    split: bool = False
    own_curves: bool = False  # drop the imposed curve meshes of the face: gmsh meshes its curves itself
    uniform: bool = False  # curvature sizes as one size from the face's sampled curvature (cheap to evaluate)
    unrolled: str = ""  # meshed flat: "cone", a cone with its apex on its boundary (:mod:`cadedge.mesh.developed`);
    # "extrusion", a face of linear extrusion (:mod:`cadedge.mesh.extruded`); "grid", a cylinder between two
    # circles as a grid of right triangles (:mod:`cadedge.mesh.gridded`); "parameters", any face whose
    # parameters are even on it, in them scaled to lengths (:mod:`cadedge.mesh.parametric`)

    @property
    def sizes(self) -> tuple:
        """What sets this strategy's sizes: strategies alike in it tend to hang alike (an unrolled cone is
        meshed in another model: gmsh hanging on the cone's face tells nothing of it). In an unrolled
        cone's plane sector the algorithm counts too: MeshAdapt's time grows faster with the sector's
        triangles than Frontal-Delaunay's (57 s against 24 s on a 1 x 60 cone at 1e-3, where it makes
        15% fewer triangles), and it hung on a 1 x 200 cone that Frontal-Delaunay meshes in 49 s."""
        return (self.size_factor, self.split, self.own_curves, self.uniform, self.unrolled,
                self.algorithm if self.unrolled == "cone" else 0)


#: Tried in this order until a face meshes. 6 = Frontal-Delaunay, 1 = MeshAdapt, 5 = Delaunay. "one
#: curvature size" replaces gmsh's curvature sizing (evaluated on the surface at every candidate point:
#: about 1 ms a triangle on the twisted blade's lofted B-spline face, 20 s for 19k triangles) by one size
#: from the face's sampled largest curvature (:func:`~cadedge.mesh.generate.uniform_curvature_size`).
#: "parameters laid flat" meshes a face whose parameters are even on it as a plane face in them
#: (:mod:`cadedge.mesh.parametric`), on the curves as they are: before any strategy changes them.
STRATEGIES = (
    Strategy("Frontal-Delaunay", 6),
    Strategy("MeshAdapt", 1),
    Strategy("Delaunay", 5),
    Strategy("Frontal-Delaunay, one curvature size", 6, 1.0, False, False, True),
    Strategy("Frontal-Delaunay, finer sizes", 6, 0.5),
    Strategy("MeshAdapt, coarser sizes", 1, 2.0),
    Strategy("parameters laid flat, Frontal-Delaunay", 6, unrolled="parameters"),
    Strategy("split boundary segments, Frontal-Delaunay", 6, 1.0, True),
    Strategy("split boundary segments, MeshAdapt", 1, 1.0, True),
    Strategy("gmsh's own curve mesh, Frontal-Delaunay", 6, 1.0, False, True),
    Strategy("gmsh's own curve mesh, MeshAdapt", 1, 1.0, False, True),
    Strategy("unrolled cone, MeshAdapt", 1, unrolled="cone"),
    Strategy("unrolled cone, Frontal-Delaunay", 6, unrolled="cone"),
    Strategy("unrolled extrusion, Frontal-Delaunay", 6, unrolled="extrusion"),
    Strategy("unrolled extrusion, MeshAdapt", 1, unrolled="extrusion"),
    Strategy("grid", 0, unrolled="grid"),
)
#: The strategies of any face, in order (gmsh's, with the parameters laid flat), and of a cone with its
#: apex on its boundary: unrolled right after the first (gmsh's meshers leave triangles overlapping beside
#: the seam near the apex of narrow cones, each attempt taking seconds: 10 s a strategy on a 1 x 40 cone at
#: 1e-2, 60 s and more at 1e-3), then the others; a cone narrower than
#: :data:`~cadedge.mesh.developed.NARROW` is unrolled first.
GMSH_ORDER = tuple(k for k, s in enumerate(STRATEGIES) if s.unrolled in ("", "parameters"))
#: A cylinder between two circles whose boundary suits a grid (:func:`cadedge.mesh.gridded.layout`) is
#: meshed as one first: its area deficit is its columns' polygon's, its triangles right-angled, and gmsh's
#: time saved.
GRID_ORDER = tuple(k for k, s in enumerate(STRATEGIES) if s.unrolled == "grid") + GMSH_ORDER
UNROLLED = tuple(k for k, s in enumerate(STRATEGIES) if s.unrolled == "cone")
APEX_CONE_ORDER = GMSH_ORDER[:1] + UNROLLED + GMSH_ORDER[1:]
NARROW_CONE_ORDER = UNROLLED + GMSH_ORDER
#: A face of linear extrusion is meshed flat first: in the plane gmsh meets no parameters to distort (on
#: a spline with sharp valleys it hung in its own, every strategy), and the triangles keep their shapes.
EXTRUSION_ORDER = tuple(k for k, s in enumerate(STRATEGIES) if s.unrolled == "extrusion") + GMSH_ORDER
#: A face whose boundary crosses itself in its parameters, its curves and not only their chords (edges
#: crossing within their tolerance, :func:`cadedge.mesh.parametric.crossed`), is laid flat and untangled
#: first: gmsh's meshers split the crossing segments again and again (the Fusion tyre's face 31 hung them
#: 60 s, then 15 s a strategy, and was left failed).
PARAMETERS = tuple(k for k, s in enumerate(STRATEGIES) if s.unrolled == "parameters")
CROSSED_ORDER = PARAMETERS + tuple(k for k in GMSH_ORDER if k not in PARAMETERS)
#: A curved face with at least :data:`HOLES` holes is meshed by Delaunay first. gmsh's Frontal-Delaunay
#: takes time on a curved face in proportion to its triangles times its holes, about 4% more a hole at
#: the same sizes (a plane's holes cost it nothing: 240 on a plate, 32 s for 980 000 triangles against
#: Delaunay's 26 s); Delaunay's time does not grow with them. At uniform sizes: a half tube 9.9 s with no
#: hole, 12.5 s with 8, 27.3 s with 48 (Delaunay 5.5-7.5 s); a tube with 92 holes 93 s for 434 000
#: triangles (Delaunay 11 s for 491 000); a ball with 150 dimples, 19.5 s for 72 000 on its sphere face
#: (Delaunay 2.0 s, and its smallest angle 16.2 degrees against 8.2). In the job that face took 90 s at
#: 1e-3, past an attempt's 60 s: it failed, and Delaunay, at the same sizes as the attempt that ran out
#: of time, was not tried.
HOLES = 16
HOLED_ORDER = tuple(sorted(GMSH_ORDER, key=lambda k: STRATEGIES[k].name != "Delaunay"))  # the rest in order
#: A face OCCT's check finds invalid (a wire not closed or crossing itself) is tried only as gmsh alone
#: would mesh it, on the imposed curves and on its own, sized as gmsh alone sizes them (from its boundary
#: field: ``MeshJob.as_gmsh_alone``; on the grids' spacings two tees' run faces, whose wires cross at the
#: branch's tangent point, failed): other sizes and algorithms do not mend its wires.
#: On a seam-tangent hole read back from STEP they hung 60 s each, 199 s before the face was named; on a
#: sweep mitred at a corner each of its four broken faces went through all 12 strategies. A face of no area
#: is tried the same way: no sizes or algorithm give it one.
INVALID_FACE_STRATEGIES = (0, next(k for k, s in enumerate(STRATEGIES) if s.own_curves))


def invalid_face_skips(problems: dict[int, str]) -> dict[int, dict[int, str]]:
    """``skip`` entries (see :func:`~cadedge.mesh.generate.mesh_faces`) barring every strategy but
    :data:`INVALID_FACE_STRATEGIES` on the faces of ``problems`` (face id -> what is wrong with it: what
    OCCT's check finds, or that it has no area)."""
    return {face: {k: f"not tried: the B-rep face is invalid ({why})"
                   for k in range(len(STRATEGIES)) if k not in INVALID_FACE_STRATEGIES}
            for face, why in problems.items()}


def face_order(surface: int) -> tuple[int, ...]:
    """The strategies (indices into :data:`STRATEGIES`) gmsh surface ``surface`` is tried with, in order:
    :data:`GRID_ORDER`, :data:`CROSSED_ORDER`, :data:`EXTRUSION_ORDER`, the cones' orders,
    :data:`HOLED_ORDER` or :data:`GMSH_ORDER`."""
    import gmsh

    from .developed import NARROW, cone_of
    from .extruded import is_extrusion
    from .gridded import layout
    from .parametric import crossed

    if not isinstance(layout(surface), str):
        return GRID_ORDER
    if crossed(surface):
        return CROSSED_ORDER
    cone = cone_of(surface)
    if cone is not None:
        return NARROW_CONE_ORDER if cone.sin < NARROW else APEX_CONE_ORDER
    if is_extrusion(surface):
        return EXTRUSION_ORDER
    return HOLED_ORDER if gmsh.model.getType(2, surface) != "Plane" and holes(surface) >= HOLES else GMSH_ORDER


def holes(surface: int) -> int:
    """How many holes gmsh surface ``surface`` has: its curve loops but one (a loop across a periodic
    face's seam holds the seam, so a hole that crosses it counts with the outline)."""
    import gmsh

    try:
        return max(len(gmsh.model.occ.getCurveLoops(surface)[0]) - 1, 0)
    except Exception:  # gmsh's bare Exception: a surface its OCC kernel does not hold
        return 0
