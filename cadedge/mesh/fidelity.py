"""Per-face area deficit: how far a face's triangles are from its B-rep area.

The area deficit of a face is ``1 - mesh area / B-rep area`` (B-rep area from OCCT's
``BRepGProp::SurfaceProperties``, cross-checked: :mod:`cadedge.occt.areas`), the 2-simplex sibling of
the edges' arc-length deficit. It is signed: flat triangles inscribed in a convex surface lose area
(positive), while a plate whose hole is an inscribed polygon gains some (negative). The target is
``|deficit| <= surface_ald`` on every face.
"""

from __future__ import annotations

import numpy as np

from .areas import unfolded_areas


def brep_face_areas(shape: object) -> np.ndarray:
    """Area of every face of ``shape`` in ``TopExp::MapShapes`` order (index ``id - 1``), OCCT's
    integrations cross-checked (:mod:`cadedge.occt.areas`)."""
    from ..occt.areas import face_areas

    return face_areas(shape)


# --- sizes for the surface target -------------------------------------------------------------------------

#: Area deficit of flat triangles of size ``h`` inscribed in a surface of largest curvature ``k`` is about
#: ``C * (h k)**2``, measured with gmsh's frontal mesher: 0.21 on a sphere (both directions curved),
#: 0.03 on a cylinder, 0.035 on a torus. Other surfaces start from :data:`DEFAULT_C`; a face that then
#: misses its target is meshed again finer (see :func:`after_generate`).
INSCRIBED_C = {"Sphere": 0.21, "Cylinder": 0.035, "Cone": 0.035, "Torus": 0.05}
DEFAULT_C = 0.05
#: Share of a curved face's area target spent on its interior triangles; the rest goes to its boundary
#: polygon. A planar face has no interior error: its boundary gets :data:`AIM` of the target.
INTERIOR_SHARE = 0.6
#: A face meshed again aims at this share of the target (the deficit does not fall exactly as ``h**2``).
AIM = 0.7


def per_circle(surface_ald: float, kind: str = "") -> float:
    """gmsh's ``Mesh.MeshSizeFromCurvature`` (triangles per 2 pi of curvature) giving a face of surface type
    ``kind`` the interior share of ``surface_ald``: ``h k = sqrt(INTERIOR_SHARE * surface_ald / C)``."""
    return 2.0 * np.pi / np.sqrt(INTERIOR_SHARE * surface_ald / INSCRIBED_C.get(kind, DEFAULT_C))


def surface_types(shape: object) -> list[str]:
    """OCCT surface type name of every face (``Plane``, ``Cylinder``, ``BSplineSurface``...), MapShapes order."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface

    from ..occt.topology import Topology

    return [surface_type_name(BRepAdaptor_Surface(f)) for f in Topology(shape).faces]


def meshed_kinds(shape: object, kinds: list[str] | None = None) -> list[str]:
    """The surface types faces are meshed as: OCCT's (``kinds``, default :func:`surface_types`), with
    ``Plane`` for every face that is planar whatever its type (:mod:`cadedge.occt.planes`): its triangles
    cover exactly its boundary polygon, so it is fitted and checked as a plane and not sized by curvature."""
    from ..occt.planes import planar_faces

    kinds = list(surface_types(shape) if kinds is None else kinds)
    for f in planar_faces(shape):
        kinds[f - 1] = "Plane"
    return kinds


def surface_type_name(surface) -> str:
    """The type name of a ``BRepAdaptor_Surface`` (its ``GeomAbs_SurfaceType`` without the prefix)."""
    return str(surface.GetType()).rsplit(".", 1)[-1].removeprefix("GeomAbs_")


#: A face whose B-rep area is under this share of its perimeter squared has no area to speak of: it is
#: taken as degenerate (area 0: no area target, and the report says so). Gs001 of the dodgy-STEP catalogue,
#: a 3.9 KB file, holds a face of area 2.3e-13 inside 14 mm of edges (its pcurves nonsense, one edge of
#: tolerance 34 mm): the boundary fit, which cuts boundary segments to the face's area budget, asked 780
#: million pieces of one segment, and the caller's process grew to 24 GB and was killed.
DEGENERATE_AREA = 1e-9


def face_perimeters(grid, faces: int) -> np.ndarray:
    """Each face's perimeter (index ``id - 1``, ``faces`` of them): its edge grids' lengths summed."""
    perimeter = np.zeros(faces)
    for e in grid.edges:
        for f in e.faces:
            if 1 <= f <= faces:
                perimeter[f - 1] += e.length
    return perimeter


def without_degenerate(grid, areas: np.ndarray) -> np.ndarray:
    """``areas`` (per face, ``id - 1``) with 0 for every face whose area is under :data:`DEGENERATE_AREA`
    times its perimeter (:func:`face_perimeters`) squared."""
    perimeter = face_perimeters(grid, len(areas))
    return np.where(np.abs(areas) < DEGENERATE_AREA * perimeter ** 2, 0.0, areas)


def prepare(grid, surface_ald: float, *, fit: bool = True, aside=None) -> tuple[object, dict]:
    """Everything the surface target needs before meshing, in the caller's process (OCCT): the B-rep face
    areas (:func:`without_degenerate`) and surface types, the boundary-fitted grid
    (:func:`cadedge.mesh.boundary_fit.fit_boundaries`; with ``fit`` False the grid as it is, no credits:
    out of time, see :mod:`cadedge.mesh.jobclock`) and the job settings. ``aside``
    (:class:`~cadedge.mesh.instances.SetAside`): an assembly's copies, left out of the fit (the grid
    returned is ``aside.apart``; their areas and types are measured as any face's)."""
    from .boundary_fit import fit_boundaries

    areas = without_degenerate(grid, brep_face_areas(grid.shape))
    kinds = surface_types(grid.shape)
    meshed_as = meshed_kinds(grid.shape, kinds)
    if aside is not None:
        grid = aside.apart(grid)
    fitted, credits = (fit_boundaries(grid, surface_ald, brep_areas=areas if aside is None else aside.hide(areas),
                                      kinds=meshed_as) if fit else (grid, {}))
    opts = settings(surface_ald, areas, meshed_as)
    opts["curved_credits"] = credits  # the later boundary fits keep the curved faces' cancellation
    opts["surface_types"] = kinds  # the report names OCCT's types
    opts["meshed_kinds"] = meshed_as
    return fitted, opts


# --- inside the gmsh job (cadedge.mesh.worker hooks; gmsh's current model is the one being meshed) ---------

#: Faces over the target are meshed again at most this many times, each time finer.
PASSES = 3
#: Curvature sizes stop at this share of the finest edge spacing (see ``sizes.configure_curvature_sizes``).
MIN_SIZE_SHARE = 0.25
#: A face meshed finer whose |deficit| kept more than this share and is still over the target is not
#: converging (its gmsh face differs from the B-rep face, e.g. loose tolerances): it is meshed again as it
#: was first meshed, and reported. One within the target keeps its finer mesh however little it gained:
#: LLNL boxed_sphere's B-spline hemispheres, partly sized by the fine curves of the box around them, went
#: from 1.06e-3 to 8.7e-4 at 1e-3 (0.82 of it) and were put back to 1.06e-3 and reported.
CONVERGED = 0.8
#: A face whose first |deficit| is over this many times the target, and over :data:`DISAGREE_FLOOR`, is not
#: meshed again: sizes chosen for the target miss it by far less, so its mesh and B-rep areas disagree
#: (LLNL boxed_sphere: 16 B-spline faces 11-29% off in every mesher; meshing them finer only cost time).
#: Under the floor a face gets at least one finer mesh, and :data:`CONVERGED` judges it: a gear's side
#: face (a spline of 30 sharp lobes, extruded) came out 1.01% off at 1e-3, was taken for disagreeing under
#: a 1% floor and kept 10 times the target; meshed finer it is at 5.5e-4. A 5% floor let boxed_sphere's
#: faces 2.7-3.0% off (loose edge tolerances) be meshed finer at 1e-3: a batch of them hung for 120 s and
#: the run took 457 s instead of about 160.
DISAGREE = 10.0
DISAGREE_FLOOR = 0.02


#: Curved faces are coarsened (:mod:`cadedge.mesh.coarsen`) up to the model's worst face, or up to this share
#: of the target where the worst face is under it. mesh_T106_V3 at 1e-3 came out with its worst face at
#: 2.6e-4 before its faces were optimised, and a blade face at 2.3e-4 was not coarsened for it: 14 036
#: triangles, against 8 996 coarsened up to half the target (the worst face after optimising: 3.45e-4 both).
COARSEN_FLOOR = 0.5
#: A face held at a size floor (a sharp ridge, see :mod:`cadedge.mesh.floored`) has its edges split on its
#: surface (:mod:`cadedge.mesh.midpoints`) from this share of the target on, not only once over it: its
#: triangles across the ridge cost it most of its deficit, and the face optimiser, which keeps the face
#: within its target, had no room left to move them (the propeller at 1e-2: 14.4 -> 25.8 degrees;
#: sharp_blade at 1e-3: 14.8 -> 27.4 degrees with 60 298 triangles for 67 130).
RIDGE_SPLIT = 0.5


#: A face over the target whose mesh holds this share of its triangle budget
#: (:data:`~cadedge.mesh.budget.MAX_FACE_TRIANGLES`), or whose curvature sizes are held to the budget
#: (:func:`cadedge.mesh.interior.use_per_circle`), is not meshed again, finer or on split edges: its
#: sizes are at the budget's already, and gmsh takes longer than one attempt on more. A torus R35 r0.2 at
#: 1e-3 (a small fillet along a 220 mm edge), 403 110 triangles at 1.24e-3 by the one-size strategy: its
#: finer mesh hung for 60 s, the replay took 24 s and the edge splits ran into the 70% cut, 213 s in all.
AT_BUDGET = 0.9


#: gmsh's other 2-D algorithms, tried in turn on a face whose mesh is too far from its B-rep area to be
#: chased (:func:`other_algorithms`). Delaunay alone: on a 270-degree revolved spline face between two
#: poles it took 0.1-0.3 s where MeshAdapt took 8.5-89 s (sizes 5 and 2), both the right side; with both
#: tried on every face far off (LLNL boxed_sphere's 20 faces off in every mesher) its run at 1e-3 took
#: 146 s instead of 90.
OTHER_ALGORITHMS = ("Delaunay",)
#: The strategies tried in turn on a face whose mesh is far *larger* than its B-rep area
#: (:func:`other_algorithms`): Delaunay-based meshers leave the triangulation of its boundary nodes in
#: ``(u, v)`` where the face's parameters stretch one way far more than the other, a Schwarz lantern. The
#: race car nose of a DesignModeler file has a B-spline strip 162 x 3 mm whose length takes 0.16 of ``u``
#: and its width all of ``v``, narrowing to a point: Frontal-Delaunay and Delaunay both fanned from the
#: wide end's nodes to the far side, edges up to 162 mm, 49-61% over the face's area (no triangle folded,
#: so nothing told gmsh's own switch to MeshAdapt); MeshAdapt meshed it within 1e-5 at 1e-2. Laid flat in
#: its parameters first (:mod:`cadedge.mesh.parametric`, scaled to lengths): a Fusion catamaran hull's
#: cylinder band 1.4 mm tall and 2.3 m round, 5.3 times its area by Frontal-Delaunay, took MeshAdapt 45 s
#: alone and over the 60 s bound in the whole model (kept at -4.3); laid flat it is within 2e-6 in 10 s.
OVER_ALGORITHMS = ("parameters laid flat, Frontal-Delaunay", "MeshAdapt")


def other_algorithms(s: int, per_circle: float, measured: float, outcomes: dict, deficit, target: float) -> float:
    """Mesh gmsh surface ``s``, whose mesh is ``measured`` off its B-rep area (too far to be chased:
    :func:`not_converging` on one mesh), again by gmsh's other algorithms at the same sizes, until one is
    no longer that far; the deficit of the mesh kept is returned (:func:`cadedge.mesh.remesh.keep_closer`).
    A mesh short of its face is tried by :data:`OTHER_ALGORITHMS` and the new mesh kept only if its
    smallest angle is at least the first mesh's or 20 degrees; one larger than its face by
    :data:`OVER_ALGORITHMS`, whatever its angles: flat triangles cannot cover more than their face's area
    but by folding or spanning it (the optimiser then works on its angles).

    A face of a periodic surface spanning more than half a turn between two poles (a 270-degree sphere or
    revolved spline sector; the round corner patches of a swept elbow) was meshed by Frontal-Delaunay on
    the other side of its boundary, the missing quarter: 40 to 160 triangles, 73% short, watertight with
    its neighbours, and named as not converging. gmsh's Delaunay and MeshAdapt mesh the face itself.
    A new mesh nearer the area but worse is not kept: on LLNL boxed_sphere at 1e-3 four cylinders 2.7%
    short came out of Delaunay within the target but at 0.8 degrees, against 37.7. Their shortfall is
    within what their edges' 0.06 mm tolerances allow (:func:`cadedge.mesh.report.tolerance_bands`), and
    faces so are not tried at all (the attempts cost that run 11 s of 100)."""
    from .facemesh import triangle_min_angles
    from .quality import GOOD_DEG
    from .remesh import keep_closer

    first = triangle_min_angles(s)
    floor = min(GOOD_DEG, float(first.min())) if first is not None and measured > 0 else 0.0
    for name in OTHER_ALGORITHMS if measured > 0 else OVER_ALGORITHMS:
        if outcomes[s].strategy != name and not_converging(measured, None, target):
            measured = keep_closer(s, name, per_circle, measured, outcomes, deficit,
                                   within=max(DISAGREE * target, DISAGREE_FLOOR), min_angle=floor)
    return measured


def not_converging(deficit: float, before: float | None, target: float) -> bool:
    """Whether a face at ``deficit`` is not converging to ``target``: meshed finer (from ``before``), it is
    still over the target and kept more than :data:`CONVERGED` of its deficit; meshed once (``before``
    None), it is over :data:`DISAGREE` times the target and :data:`DISAGREE_FLOOR`."""
    if before is not None:
        return target < abs(deficit) > CONVERGED * abs(before)
    return abs(deficit) > max(DISAGREE * target, DISAGREE_FLOOR)


#: The hooks that carry the surface target into the gmsh job (see :mod:`cadedge.mesh.worker`).
HOOKS = {"before_generate": ["cadedge.mesh.fidelity:before_generate"],
         "before_face": ["cadedge.mesh.fidelity:before_face"],
         "after_generate": ["cadedge.mesh.fidelity:after_generate", "cadedge.mesh.adapt:after_generate",
                            "cadedge.mesh.optimize:after_generate"],
         "before_write": ["cadedge.mesh.groups:before_write"],
         "after_mesh": ["cadedge.mesh.fidelity:after_mesh"]}


def settings(surface_ald: float, brep_areas: np.ndarray, kinds: list[str]) -> dict:
    """The plain, picklable settings the job's hooks read from ``job.options["fidelity"]``."""
    return {"surface_ald": float(surface_ald), "per_circle": float(per_circle(surface_ald)),
            "face_per_circle": {i + 1: float(per_circle(surface_ald, k)) for i, k in enumerate(kinds)},
            "brep_areas": np.asarray(brep_areas, dtype=float),
            "curved_faces": [i + 1 for i, k in enumerate(kinds) if k != "Plane"]}


#: Under a surface target, planar face interiors grow from their boundary sizes this many times faster
#: than ``growth`` (their boundaries stay graded at ``growth``): nothing inside a plane needs its finest
#: boundary segment. On the bracket at 1e-2: 5682 -> 4680 triangles, minimum angle 32.1 -> 32.0 degrees.
#: Curved faces keep ``growth``: on mesh_T106_V3's extrusion faces gmsh's Frontal-Delaunay ran out of
#: time on six of eight faces with the faster growth.
INTERIOR_GROWTH = 2.0


def remesh_face(s: int, per_circle: float, face_of: dict[int, int]):
    """Mesh gmsh surface ``s`` again from scratch with ``Mesh.MeshSizeFromCurvature`` at ``per_circle``
    (its boundary curves keep their nodes); returns its :class:`~cadedge.mesh.outcomes.FaceOutcome`."""
    import gmsh

    from .generate import mesh_faces
    from .interior import use_per_circle

    use_per_circle(s, per_circle)
    gmsh.model.mesh.clear([(2, s)])
    return mesh_faces([s], face_of)[s]


def before_generate(ctx) -> None:
    """Hook: face interiors sized by curvature for the surface target (see :func:`per_circle`; in nodes
    mode faces whose curvature varies as ``k**-1/2``, see :mod:`cadedge.mesh.interior`; faces with sharp
    ridges no finer than :func:`~cadedge.mesh.interior.size_floors`, and meshed one by one after the batches
    of the others: the propeller of ``scripts/hard_models.py`` hung gmsh on such faces, and each hang cost
    the hub's planes batched with them); planar interiors grow from their boundaries at
    :data:`INTERIOR_GROWTH` times the job's growth."""
    from .gridded import aim
    from .interior import CONSTANT_CURVATURE, install, size_floors
    from .sizes import configure_curvature_sizes

    opts = ctx.job.options.get("fidelity")
    # cylinders and tori meshed as grids: which (the caller's), and their columns for the target
    grids = [f for f in (opts or {}).get("grid_faces", ()) if f in ctx.emap.faces]
    aim(opts["surface_ald"] if opts else None, [ctx.emap.faces[f] for f in grids],
        [ctx.emap.faces[f] for f in grids if opts["meshed_kinds"][f - 1] == "Torus"])
    if opts:
        min_size = MIN_SIZE_SHARE * ctx.job.field.min_size
        configure_curvature_sizes(opts["per_circle"], min_size)
        kinds = opts.get("surface_types") or []
        curved = set(opts["curved_faces"])
        areas = opts["brep_areas"]
        floors = size_floors({s: areas[f - 1] for f, s in ctx.emap.faces.items() if f in curved
                              and f <= len(areas)}, min_size)
        install([s for f, s in sorted(ctx.emap.faces.items()) if ctx.job.mode == "nodes"
                 and f in curved and f <= len(kinds) and kinds[f - 1] not in CONSTANT_CURVATURE], floors,
                opts["surface_ald"])
        ctx.floored = floors  # gmsh surface -> its size floor
        ctx.alone.update(ctx.emap.face_of_surface.get(s, s) for s in floors)  # may take gmsh long: alone, last
        planes = [s for f, s in ctx.emap.faces.items() if f not in curved]
        if planes:
            grow_planes(ctx.job.field, INTERIOR_GROWTH * ctx.job.field.growth, planes)


def grow_planes(field, growth: float, planes: list[int]) -> None:
    """Let the interiors of gmsh surfaces ``planes`` grow from their boundary sizes at ``growth`` per unit
    distance: a faster copy of the ``Extend`` background field (see ``sizes.configure_gmsh_sizes``)
    restricted to them, the original restricted to the other surfaces, their minimum the background."""
    import gmsh

    fields = gmsh.model.mesh.field
    extend = [t for t in fields.list() if fields.getType(t) == "Extend"]
    if len(extend) != 1:
        return  # not the size field this hook knows: leave it as it is
    (slow,) = extend
    others = [t for _, t in gmsh.model.getEntities(2) if t not in set(planes)]
    fast = fields.add("Extend")
    fields.setNumbers(fast, "CurvesList", fields.getNumbers(slow, "CurvesList"))
    for name in ("SizeMax", "Power"):
        fields.setNumber(fast, name, fields.getNumber(slow, name))
    fields.setNumber(fast, "DistMax", max(field.max_size - field.min_size, 0.0) / growth)
    parts = []
    for source, surfaces in ((fast, planes), (slow, others)):
        if surfaces:
            part = fields.add("Restrict")
            fields.setNumber(part, "InField", source)
            fields.setNumbers(part, "SurfacesList", surfaces)
            parts.append(part)
    both = fields.add("Min")
    fields.setNumbers(both, "FieldsList", parts)
    fields.setAsBackgroundMesh(both)


def before_face(ctx) -> None:
    """Hook: the curvature sizes of the face about to be meshed (its surface type's constant)."""
    import gmsh

    from .interior import use_per_circle
    from .strategies import STRATEGIES

    opts = ctx.job.options.get("fidelity")
    if opts:
        n = opts["face_per_circle"].get(ctx.face, opts["per_circle"])
        s = ctx.emap.faces.get(ctx.face)
        if s is None:
            gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", n)
        else:
            use_per_circle(s, n, uniform=STRATEGIES[ctx.strategy].uniform)


def after_generate(ctx) -> None:
    """Hook: measure every meshed face against its B-rep area; mesh curved faces over the target again,
    finer (``Mesh.MeshSizeFromCurvature`` raised by the measured excess), keeping the better mesh.

    Only the face's interior changes: its boundary curves keep their nodes, so neighbours stay conforming.
    Planar faces are left alone (their area is fixed by their boundary polygon). Then curved faces far
    under the worst face are meshed again coarser (:func:`cadedge.mesh.coarsen.coarsen`), and curved faces
    short of their area by more than the target (faces held at a size floor: :data:`RIDGE_SPLIT` of it) and
    at most :data:`DISAGREE` times it (faces held at a size floor: by any amount) get edges split on their
    surface (:func:`cadedge.mesh.midpoints.split_short_faces`). What was done lands in ``ctx.fidelity``: the
    per-circle count each re-meshed face ended with, the faces coarsened and split.
    """
    import time

    import gmsh

    from .budget import MAX_FACE_TRIANGLES
    from .coarsen import coarsen
    from .facemesh import read_face, write_interior
    from .floored import DELAUNAY, try_delaunay
    from .generate import mesh_faces
    from .gridded import NAME as GRID
    from .interior import SIZES, use_per_circle
    from .midpoints import split_short_faces
    from .remesh import job_groups, remesh_group
    from .report import tolerance_bands
    from .strategies import face_order

    opts = ctx.job.options.get("fidelity")
    if not opts:
        return
    target, n0 = opts["surface_ald"], opts["per_circle"]
    areas = np.asarray(opts["brep_areas"], dtype=float)
    curved = set(opts["curved_faces"])
    face_of = ctx.emap.face_of_surface

    def deficit(s: int, mesh_area: float) -> float:
        f = face_of.get(s, s)
        return 1.0 - mesh_area / areas[f - 1] if 1 <= f <= len(areas) and areas[f - 1] > 0 else 0.0

    per_face: dict[int, float] = {}
    loose = tolerance_bands(ctx.job.grid, areas)  # what a face's edges' tolerances let its area be off by
    stuck: list[int] = []
    last: dict[int, float] = {}
    no_refine = ctx.job.no_refine
    say = ctx.progress or (lambda line: None)
    floored = getattr(ctx, "floored", {})  # held at a size floor: reported as such
    pending = [s for s, o in ctx.outcomes.items() if o.ok and face_of.get(s, s) in curved]
    say("measure")
    full: set[int] = set()  # surfaces over the target at their triangle budget: not meshed again

    def at_budget(s: int) -> bool:  # or its curvature sizes held to the budget already
        return len(gmsh.model.mesh.getElementsByType(2, s)[0]) >= AT_BUDGET * MAX_FACE_TRIANGLES or SIZES.held(s)

    other: set[int] = set()  # surfaces kept as another algorithm meshed them (other_algorithms)
    best: dict[int, tuple] = {}  # floored surface -> its smallest deficit so far, that mesh, outcome, count

    def keep_best(s: int, d: float) -> float:
        """A floored face's best mesh so far back in place of one no closer to its B-rep area (neither
        algorithm is better everywhere, nor always finer sizes); returns the deficit it now has."""
        f = face_of.get(s, s)
        if s in best and abs(best[s][0]) <= abs(d):
            d, mesh, ctx.outcomes[s], n = best[s]
            write_interior(s, mesh, mesh.x, mesh.tri, mesh.movable, mesh.uv)
            if n is None:
                per_face.pop(f, None)
            else:
                per_face[f] = n
        elif (mesh := read_face(s)) is not None:
            best[s] = (d, mesh, ctx.outcomes[s], per_face.get(f))
        return d

    for k in range(PASSES + 1):
        late = ctx.job.deadline is not None and time.time() > ctx.job.deadline
        measured = {s: deficit(s, a) for s, a in unfolded_areas(pending).items()}
        for s in [s for s in measured if not late and s not in floored and s not in other
                  and face_of.get(s, s) not in no_refine and not_converging(measured[s], None, target)
                  and abs(measured[s]) > loose.get(face_of.get(s, s), (0.0, 0.0))[1] and face_order(s)[0] == 0]:
            f = face_of.get(s, s)  # far off on this mesh, first or finer, more than its edges' tolerances allow
            say(f"refine {f}")  # the watchdog bounds it; a hang or crash here keeps the face as first meshed
            was = ctx.outcomes[s].strategy
            measured[s] = other_algorithms(s, per_face.get(f, opts["face_per_circle"].get(f, n0)), measured[s],
                                           ctx.outcomes, lambda a, s=s: deficit(s, a), target)
            if ctx.outcomes[s].strategy != was:
                other.add(s)
            say(f"refined {f}")
        for s in [s for s in measured if s in floored and abs(measured[s]) > target and not late]:
            f = face_of.get(s, s)
            say(f"refine {f}")  # the watchdog bounds it; a hang or crash here keeps the face as first meshed
            n = per_face.get(f, opts["face_per_circle"].get(f, n0))
            measured[s] = try_delaunay(s, n, measured[s], ctx.outcomes, lambda a, s=s: deficit(s, a))
            say(f"refined {f}")
        for s in [s for s in measured if s in floored]:
            measured[s] = keep_best(s, measured[s])
        if late:
            break  # out of the job's time: what is meshed stays, the report names what is over
        back: dict[int, float] = {}
        for s, d in measured.items():  # finer did not help: the mesh's face is not the B-rep's
            # a floored face gains slowly (its ridge stays at the floor): it stops when its best stops
            if (abs(d) >= abs(last[s]) > target if s in floored and s in last
                    else not_converging(d, last.get(s), target)):
                stuck.append(face_of.get(s, s))
                # its finer mesh bought nothing: back to the first (LLNL boxed_sphere: 24 cylinders 2.8% off
                # at any size, 3x the triangles once refined); a floored face keeps its best (keep_best)
                if s in last and s not in floored:
                    f = face_of.get(s, s)
                    back[s] = opts["face_per_circle"].get(f, n0)
                    per_face.pop(f, None)
        for n, group in job_groups(back, share=1.0):  # faces of equal sizes in one gmsh call (see remesh.py)
            say("refine " + " ".join(str(face_of.get(s, s)) for s in group))
            ctx.outcomes.update(remesh_group(group, n, face_of))
            say("refined " + " ".join(str(face_of.get(s, s)) for s in group))
        # faces held at a size floor too: finer sizes away from the ridge remove triangles spanning it (the
        # propeller's blades at 1e-3: 7.5e-3 to 9.8e-3 -> within 1e-3)
        full.update(s for s, d in measured.items() if abs(d) > target and at_budget(s))
        pending = [s for s, d in measured.items() if abs(d) > target and face_of.get(s, s) not in stuck
                   and face_of.get(s, s) not in no_refine and s not in full and s not in other]
        if not pending or k == PASSES:
            break
        old = {s: per_face.get(face_of.get(s, s), opts["face_per_circle"].get(face_of.get(s, s), n0))
               for s in pending}
        finer = {s: old[s] * float(np.clip(np.sqrt(abs(measured[s]) / (AIM * target)), 1.25, 3.0))
                 for s in pending}
        for n_group, group in job_groups(finer):
            if ctx.job.deadline is not None and time.time() > ctx.job.deadline:
                break
            faces = " ".join(str(face_of.get(s, s)) for s in group)
            say(f"refine {faces}")  # the watchdog bounds it; a hang or crash here keeps them as first meshed
            for s, redo in remesh_group(group, n_group, face_of).items():
                n = n_group
                if not redo.ok:  # keep what met the boundary before: mesh it again as it was
                    use_per_circle(s, old[s])
                    redo = mesh_faces([s], face_of)[s]
                    n = old[s]
                ctx.outcomes[s] = redo
                per_face[face_of.get(s, s)] = n
                last[s] = measured[s]
            say(f"refined {faces}")
    ok = [s for s, o in ctx.outcomes.items() if o.ok and s > 0 and face_of.get(s, s) not in stuck]
    final = {s: deficit(s, a) for s, a in unfolded_areas(ok).items()}
    level = min(max(max(map(abs, final.values()), default=0.0), COARSEN_FLOOR * target), target)
    # a face kept as Delaunay meshed it is not coarsened: coarsening meshes a face it did not coarsen again
    # as it was, by Frontal-Delaunay (sharp_blade's face 3: 4.4e-3 as Delaunay meshed it, back at 2.6e-2);
    # leaving out every floored face cost mesh_T106_V3 at 1e-3 13 333 triangles against 8 975. Nor a grid,
    # whose mesh its boundary sets (cadedge.mesh.gridded), nor a face another algorithm meshed closer
    calm = [s for s in ok if face_of.get(s, s) in curved and face_of.get(s, s) not in no_refine
            and face_of.get(s, s) not in per_face and ctx.outcomes[s].strategy not in (DELAUNAY, GRID)
            and s not in other]
    coarser = coarsen(ctx, level=level, deficit=deficit, measured={s: final[s] for s in calm},
                      per_circle={s: opts["face_per_circle"].get(face_of.get(s, s), n0) for s in calm})
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", n0)
    # curved faces still short of their area (a sharp ridge spanned by triangles), and faces held at a size
    # floor past RIDGE_SPLIT of it: edges split on the surface
    short = [s for s, o in ctx.outcomes.items()
             if o.ok and s > 0 and face_of.get(s, s) in curved and s not in full]
    split = split_short_faces(ctx, {s: RIDGE_SPLIT * target if s in floored else target for s in short},
                              target=target, most=DISAGREE * target, deficit=deficit, areas=areas,
                              ridged=frozenset(floored))
    stuck = [f for f in stuck if f not in split]  # within their target now: the optimiser keeps them there
    ctx.fidelity = {"per_circle": n0, "refined": per_face, "coarsened": coarser, "split": split,
                    "stuck": sorted(stuck),
                    "floored": {face_of.get(s, s): h for s, h in floored.items()},
                    "budget": sorted(face_of.get(s, s) for s in full), "budget_triangles": MAX_FACE_TRIANGLES}


def after_mesh(ctx) -> dict:
    """Hook: what :func:`after_generate` did, and the faces with folded triangles (face -> how many,
    :func:`cadedge.mesh.folds.count_folded`), for the report (plain data)."""
    from .folds import count_folded

    out = dict(getattr(ctx, "fidelity", {}) or {})
    face_of = ctx.emap.face_of_surface
    counts = {face_of.get(s, s): count_folded(s) for s, outcome in sorted(ctx.outcomes.items()) if outcome.ok}
    out["folded"] = {f: k for f, k in counts.items() if k}
    return out
