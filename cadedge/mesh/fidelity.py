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
#: A boundary segment is split when longer than this many times the curvature size of a face it bounds:
#: gmsh does not refine triangles standing on a long boundary segment, so a fillet between two straight
#: 40 mm edges is otherwise spanned by triangles across its whole arc (4% area lost).
CURVATURE_RATIO = 2.0
#: The same for straight edges (a line across a curved face, a cylinder's seam): their ALD leaves them one
#: segment, and a cylinder's 6 mm seam segments beside 3 mm interior triangles gave 24-degree triangles
#: (38 once split to the interior size, as gmsh alone gets). Curved edges keep 2: their ALD spacing is
#: already near the size, and splitting circles too cost the bracket 30% more triangles.
STRAIGHT_RATIO = 1.0
#: An edge is straight when it is a line or its curve stays within this share of each segment's length
#: of the chord (STEP files often carry lines as B-splines: LLNL boxed_sphere's 3.2 mm straight B-spline
#: edges along its fillets kept one segment beside 0.12 mm triangles, 23.6 degrees).
STRAIGHT_TOL = 1e-6
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


def _face_probe(face):
    """A callable (u) -> (normals (n, 3), largest |curvature| (n,)) along one edge on ``face``."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve2d, BRepAdaptor_Surface
    from OCP.BRepLProp import BRepLProp_SLProps

    surface = BRepAdaptor_Surface(face)
    props = BRepLProp_SLProps(surface, 2, 1e-9)

    def probe(edge, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        pcurve = BRepAdaptor_Curve2d(edge, face)
        normals = np.zeros((len(u), 3))
        curv = np.zeros(len(u))
        for k, uk in enumerate(u.tolist()):
            p = pcurve.Value(uk)
            props.SetParameters(p.X(), p.Y())
            if props.IsNormalDefined():
                normals[k] = props.Normal().Coord()
            if props.IsCurvatureDefined():
                curv[k] = max(abs(props.MaxCurvature()), abs(props.MinCurvature()))
        return normals, curv

    return probe


#: A planar face given a cancellation credit keeps its boundary segments within this many times its mean
#: width ``2 area / perimeter``: periodic_u_cst's 1 mm strip, credited down to 4.4 mm segments, was filled
#: with 11-degree triangles (6% of them under 20 degrees); the unsigned rule had split it finer than that.
THIN_RATIO = 2.0
#: Rounds of the planar faces' signed fit (see :func:`fit_boundaries`); each divides the cancellation
#: credit of a face still over its budget by :data:`CREDIT_STEP`.
PLANAR_ROUNDS, CREDIT_STEP = 4, 4.0


def fit_boundaries(grid, surface_ald: float, *, brep_areas: np.ndarray | None = None,
                   kinds: list[str] | None = None, ratio: float = CURVATURE_RATIO):
    """A copy of ``grid`` whose edge segments suit the surface target of every face they bound (the rules:
    :func:`_fit_boundaries`).

    Planar faces are then checked exactly: their triangles will cover their boundary polygon, whose area
    :func:`cadedge.mesh.planar.planar_polygon_areas` gives with signs, so a face whose slivers cancel (a
    curved strip losing on one side what it gains on the other) needs far fewer splits than the unsigned
    rule asks. Its budget is credited with the measured cancellation, ``sum |slivers| / |net deficit|``
    (halved), and the fit is repeated; a face the credit puts over its budget gets a quarter of it
    next round, and a credit of 1 or less is dropped (the unsigned rule). After :data:`PLANAR_ROUNDS`
    rounds without every credited face within its budget, the fit with the credits left is kept. Planar
    faces still over their budget then have their edges fitted again (:func:`fit_planes`)."""
    areas = brep_face_areas(grid.shape) if brep_areas is None else np.asarray(brep_areas, dtype=float)
    kinds = meshed_kinds(grid.shape) if kinds is None else kinds
    planes = _planes(areas, kinds)
    limit = AIM * surface_ald

    def net(g) -> dict[int, float]:
        return _plane_deficits(g, planes, areas)

    def fit(g, credit: dict[int, float]):
        return _fit_boundaries(g, surface_ald, brep_areas=areas, kinds=kinds, ratio=ratio, credit=credit)

    fitted, gross = fit(grid, {})
    if not planes:
        return fitted
    before = net(grid)
    credit = {f: 0.5 * gross[f - 1] / max(d * areas[f - 1], 1e-300) for f, d in before.items()}
    credit = {f: c for f, c in credit.items() if c > 1.0}
    for _ in range(PLANAR_ROUNDS):
        if not credit:
            break
        trial, _ = fit(grid, credit)
        now = net(trial)
        over = {f for f in credit if now.get(f, np.inf) > limit}
        if not over:
            fitted, credit = trial, {}
            break
        credit = {f: c / CREDIT_STEP if f in over else c for f, c in credit.items()}
        credit = {f: c for f, c in credit.items() if c > 1.0}
    if credit:
        fitted = fit(grid, credit)[0]
    return fit_planes(fitted, surface_ald, brep_areas=areas, kinds=kinds, ratio=ratio)


def _planes(areas: np.ndarray, kinds: list[str]) -> list[int]:
    """Ids of the faces meshed as planes with a positive B-rep area."""
    return [i + 1 for i, k in enumerate(kinds) if k == "Plane" and areas[i] > 0]


def _plane_deficits(grid, planes: list[int], areas: np.ndarray) -> dict[int, float]:
    """Exact |area deficit| of each checkable planar face of ``planes``: its boundary polygon's area
    (:func:`cadedge.mesh.planar.planar_polygon_areas`) against its B-rep area."""
    from .planar import planar_polygon_areas

    return {f: abs(1.0 - a / areas[f - 1]) for f, a in planar_polygon_areas(grid.shape, grid, planes).items()}


#: Rounds of :func:`fit_planes`.
REFIT_ROUNDS = 4


def fit_planes(grid, surface_ald: float, *, brep_areas: np.ndarray, kinds: list[str],
               ratio: float = CURVATURE_RATIO):
    """``grid`` with the edges of planar faces whose boundary polygon is over :data:`AIM` times
    ``surface_ald`` (measured exactly) fitted again by the unsigned rule of :func:`_fit_boundaries` on their
    present segments, round after round while that at least halves one such face's deficit
    (:data:`REFIT_ROUNDS` at most).

    The rule estimates a segment's sliver from its sagitta and divides it by ``k**2`` when the segment is
    cut in ``k``: on a segment that spans a bend (the 0.3 mm round end of a 20 mm stadium outline,
    first 4 segments for 41 mm) most pieces fall on the straight part, and the flat cap stood at 5.5%
    after the fit (1.49% once its thin sides were split for their width) against 0.7% aimed at. Splits
    made after the fit move a polygon too: where a spline outline bulges in and out, splitting its convex
    stretches for other reasons (thin sides, grading) leaves the concave ones' gain uncancelled (a stadium
    with 1 mm round ends at 1e-3: -5.1e-4 after the fit, -1.14e-3 as meshed), so the mesher calls this
    again once its boundary splits are done."""
    areas = np.asarray(brep_areas, dtype=float)
    planes = _planes(areas, kinds)
    if not planes:
        return grid
    limit = AIM * surface_ald
    for _ in range(REFIT_ROUNDS):
        now = _plane_deficits(grid, planes, areas)
        over = {f for f, d in now.items() if d > limit}
        if not over:
            break
        trial, _ = _fit_boundaries(grid, surface_ald, brep_areas=areas, kinds=kinds, ratio=ratio, credit={},
                                   only=over)
        after = _plane_deficits(trial, planes, areas)
        if not any(after.get(f, np.inf) <= 0.5 * now[f] for f in over):
            break
        grid = trial
    return grid


def _fit_boundaries(grid, surface_ald: float, *, brep_areas: np.ndarray, kinds: list[str], ratio: float,
                    credit: dict[int, float], only: set[int] | None = None):
    """A copy of ``grid`` whose edge segments suit the surface target of every face they bound (``only``:
    the edges of those faces only), and the summed unsigned sliver estimate of each face's boundary before
    the splits (index ``id - 1``; of the edges looked at).

    Two reasons to split a segment (into equal parameter steps on its OCCT curve; grid points are kept,
    nodes only added, so both faces of an edge still share its nodes). Equal parameter steps, unlike the
    equal arc lengths of the later passes: wing_fuselage's fuselage meridians slow their parameter towards
    the pointed tail, where the surface's curvature grows without bound, and there equal arc lengths left
    10 mm segments beside the tip (faces 1 and 8 were then triangulated from their boundary nodes alone
    and meshed again far finer: 78 206 triangles at ALD 1e-2 against 38 102). The pieces' sizes come from
    this fit's own rules, so a short piece here is not copied along the boundary as a proximity pass
    copies a size (see :func:`cadedge.splitting.split_by_arc`):

    - its face is curved across it: longer than ``ratio`` times the face's curvature size there (see
      :func:`per_circle`; :data:`STRAIGHT_RATIO` times on a straight edge, see :data:`STRAIGHT_TOL`),
      into pieces no shorter than the size that fills the face with its triangle budget
      (:func:`cadedge.mesh.budget.filling_size`: a 14 mm seam along a blade's sharp edge had been split
      into 1 838 pieces of 0.008 mm, finer than the face's interior could follow);
    - the face's boundary polygon loses too much area: the sliver between a segment and its curve,
      ``2/3 * chord * sagitta`` with the sagitta's component tangent to the face (a circle on a cylinder
      loses nothing to the cylinder, all to a planar cap), summed over the face's boundary, must stay
      within ``(1 - INTERIOR_SHARE) * surface_ald`` of its B-rep area (``AIM * surface_ald`` on a plane).
      Splitting a segment in ``k`` divides its sliver by ``k**2``; each segment gets a share of the
      budget by its length.
    """
    import dataclasses

    from OCP.Standard import Standard_Failure

    from ..errors import GeometryError
    from ..occt.edgecurve import EdgeCurve
    from ..occt.topology import Topology
    from ..shapegrid import with_edges
    from ..splitting import fits_curve, split_segments
    from .budget import filling_size

    topo = Topology(grid.shape)
    areas = brep_areas
    h_factor = np.array([2.0 * np.pi / per_circle(surface_ald, k) for k in kinds])  # size = h_factor / k
    share = np.array([AIM if k == "Plane" else 1.0 - INTERIOR_SHARE for k in kinds])
    filled = filling_size(areas)
    budget = share * surface_ald * areas
    for f, c in credit.items():
        budget[f - 1] *= c
    gross = np.zeros(len(areas))
    perimeter = np.zeros(len(areas))
    for e in grid.edges:
        if not e.degenerate and len(e.points) >= 2:
            for f in e.faces:
                perimeter[f - 1] += e.segment_lengths.sum()
    with np.errstate(divide="ignore", invalid="ignore"):
        width = np.where(perimeter > 0, 2.0 * areas / perimeter, np.inf)  # a strip's width, exactly
    probes: dict[int, object] = {}
    edges = list(grid.edges)
    for i, e in enumerate(edges):
        if e.degenerate or len(e.points) < 2 or not e.faces or not np.all(np.diff(e.params) > 0):
            continue
        if only is not None and not set(e.faces) & only:
            continue
        try:
            curve = EdgeCurve(topo.edges[e.id - 1], e.id)
            if not fits_curve(e.params, e.points, curve.evaluate, e.tolerance):
                continue  # the grid's parameters are not this curve's: leave the edge alone
            mid_u = 0.5 * (e.params[:-1] + e.params[1:])
            sagitta = _sagittas(e.params, e.points, curve.evaluate)
            for f in e.faces:  # one probe per face (its adaptor bounds the face's pcurves: costly on many holes)
                if f not in probes:
                    probes[f] = _face_probe(topo.faces[f - 1])
            probed = [(f, *probes[f](curve.edge, mid_u)) for f in e.faces]
        except (GeometryError, Standard_Failure):  # OCCT cannot evaluate this edge: keep its grid
            continue
        chord = e.segment_lengths
        straight = e.curve == "Line" or bool(np.all(np.linalg.norm(sagitta, axis=1) <= STRAIGHT_TOL * chord))
        edge_ratio = min(ratio, STRAIGHT_RATIO) if straight else ratio
        pieces = np.ones(len(chord), dtype=int)
        for f, normals, curv in probed:
            tangential = sagitta - np.sum(sagitta * normals, axis=1)[:, None] * normals
            sliver = 2.0 / 3.0 * chord * np.linalg.norm(tangential, axis=1)
            gross[f - 1] += sliver.sum()
            allowed = budget[f - 1] * chord / max(perimeter[f - 1], 1e-300)
            with np.errstate(divide="ignore", invalid="ignore"):
                k_area = np.where(sliver > allowed, np.ceil(np.sqrt(sliver / allowed)), 1)
                k_curv = np.where(curv > 0, np.ceil(chord * curv / (edge_ratio * h_factor[f - 1])), 1)
                k_curv = np.minimum(k_curv, np.maximum(np.floor(chord / filled[f - 1]), 1))
                k_thin = np.ceil(chord / (THIN_RATIO * width[f - 1])) if f in credit else 1
            pieces = np.maximum(pieces, np.nan_to_num(np.maximum(np.maximum(k_area, k_curv), k_thin),
                                                      nan=1).astype(int))
        if not np.any(pieces > 1):
            continue
        params, points = split_segments(e.params, e.points, pieces, curve.evaluate, spacing="parameter")
        edges[i] = dataclasses.replace(e, params=params, points=points)
    return with_edges(grid, edges), gross


#: Where along each segment's parameter span :func:`_sagittas` looks for the curve's farthest point.
SAGITTA_AT = (0.25, 0.5, 0.75)


def _sagittas(params: np.ndarray, points: np.ndarray, evaluate) -> np.ndarray:
    """Each segment's sagitta: the vector from its chord to the farthest of the curve's points at
    :data:`SAGITTA_AT` of its parameter span, perpendicular to the chord, shape (segments, 3).

    The curve's point at mid-parameter alone is not the arc's middle where the parameter speed varies:
    on mesh_T106_V3's B-spline curves it lay up to 14 mm along the chord from the chord's midpoint,
    which counted as a sliver of the face and split 40 mm segments of a nearly straight curve into 30-50
    pieces. Only the distance across the chord is a sliver's height."""
    a, b = points[:-1], points[1:]
    chord = b - a
    length = np.linalg.norm(chord, axis=1)
    t = np.divide(chord, length[:, None], out=np.zeros_like(chord), where=length[:, None] > 0)
    best = np.zeros_like(chord)
    for f in SAGITTA_AT:
        off = evaluate(params[:-1] + f * np.diff(params)) - a
        across = off - np.sum(off * t, axis=1)[:, None] * t
        farther = np.linalg.norm(across, axis=1) > np.linalg.norm(best, axis=1)
        best[farther] = across[farther]
    return best


def prepare(grid, surface_ald: float) -> tuple[object, dict]:
    """Everything the surface target needs before meshing, in the caller's process (OCCT): the B-rep face
    areas and surface types, the boundary-fitted grid (:func:`fit_boundaries`) and the job settings."""
    areas = brep_face_areas(grid.shape)
    kinds = surface_types(grid.shape)
    meshed_as = meshed_kinds(grid.shape, kinds)
    fitted = fit_boundaries(grid, surface_ald, brep_areas=areas, kinds=meshed_as)
    opts = settings(surface_ald, areas, meshed_as)
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
    (its boundary curves keep their nodes); returns its :class:`~cadedge.mesh.generate.FaceOutcome`."""
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
    from .interior import CONSTANT_CURVATURE, install, size_floors
    from .sizes import configure_curvature_sizes

    opts = ctx.job.options.get("fidelity")
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

    from .generate import STRATEGIES
    from .interior import use_per_circle

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

    from .coarsen import coarsen
    from .facemesh import read_face, write_interior
    from .floored import DELAUNAY, try_delaunay
    from .generate import mesh_faces
    from .interior import use_per_circle
    from .midpoints import split_short_faces
    from .remesh import job_groups, remesh_group

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
    stuck: list[int] = []
    last: dict[int, float] = {}
    no_refine = ctx.job.no_refine
    say = ctx.progress or (lambda line: None)
    floored = getattr(ctx, "floored", {})  # held at a size floor: reported as such
    pending = [s for s, o in ctx.outcomes.items() if o.ok and face_of.get(s, s) in curved]
    say("measure")
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
        pending = [s for s, d in measured.items() if abs(d) > target and face_of.get(s, s) not in stuck
                   and face_of.get(s, s) not in no_refine]
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
    # leaving out every floored face cost mesh_T106_V3 at 1e-3 13 333 triangles against 8 975
    calm = [s for s in ok if face_of.get(s, s) in curved and face_of.get(s, s) not in no_refine
            and face_of.get(s, s) not in per_face and ctx.outcomes[s].strategy != DELAUNAY]
    coarser = coarsen(ctx, level=level, deficit=deficit, measured={s: final[s] for s in calm},
                      per_circle={s: opts["face_per_circle"].get(face_of.get(s, s), n0) for s in calm})
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", n0)
    # curved faces still short of their area (a sharp ridge spanned by triangles), and faces held at a size
    # floor past RIDGE_SPLIT of it: edges split on the surface
    short = [s for s, o in ctx.outcomes.items() if o.ok and s > 0 and face_of.get(s, s) in curved]
    split = split_short_faces(ctx, {s: RIDGE_SPLIT * target if s in floored else target for s in short},
                              target=target, most=DISAGREE * target, deficit=deficit, areas=areas,
                              ridged=frozenset(floored))
    stuck = [f for f in stuck if f not in split]  # within their target now: the optimiser keeps them there
    ctx.fidelity = {"per_circle": n0, "refined": per_face, "coarsened": coarser, "split": split,
                    "stuck": sorted(stuck),
                    "floored": {face_of.get(s, s): h for s, h in floored.items()}}


def after_mesh(ctx) -> dict:
    """Hook: what :func:`after_generate` did, and the faces with folded triangles (face -> how many,
    :func:`cadedge.mesh.folds.count_folded`), for the report (plain data)."""
    from .folds import count_folded

    out = dict(getattr(ctx, "fidelity", {}) or {})
    face_of = ctx.emap.face_of_surface
    counts = {face_of.get(s, s): count_folded(s) for s, outcome in sorted(ctx.outcomes.items()) if outcome.ok}
    out["folded"] = {f: k for f, k in counts.items() if k}
    return out
