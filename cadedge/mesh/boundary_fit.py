"""Boundary segments fitted to the faces' area target, before meshing (in the caller's process, OCCT).

A face's triangles cannot be closer to its area than its boundary polygon lets them: a planar face's
triangles cover exactly that polygon, and a curved face's triangles standing on long boundary segments
miss the curvature across them. :func:`fit_boundaries` splits the edge grids' segments until each face's
boundary suits its share of the target (:mod:`cadedge.mesh.fidelity`), :func:`fit_planes` checks the
planar faces on their exact polygons and fits them again where the estimate fell short. Grid points are
kept and nodes only added, so faces sharing an edge still share its nodes.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .fidelity import AIM, INTERIOR_SHARE, brep_face_areas, face_perimeters, meshed_kinds, per_circle

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


def _face_probe(face, *, sided: bool = True):
    """A callable (edge, u, spans) -> (normals (n, 3), largest |curvature| (n,), inward (n, 3) or None) at
    parameters ``u`` of one edge on ``face`` (the middles of segments ``spans`` long in parameter):
    ``inward`` the unit vectors tangent to the face, across the edge, into it (zero on a seam, where the
    face lies on both sides; None where the side could not be told, or not ``sided``: a plane's polygon
    is measured exactly, and telling the side of each of a plate's 1 800 hole edges took 1.7 s)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Curve2d, BRepAdaptor_Surface
    from OCP.BRepLProp import BRepLProp_SLProps
    from OCP.TopAbs import TopAbs_FORWARD
    from OCP.gp import gp_Pnt2d, gp_Vec2d

    from ..occt.compat import TopoDS

    surface = BRepAdaptor_Surface(face)
    props = BRepLProp_SLProps(surface, 2, 1e-9)
    forward = TopoDS.Face_s(face.Oriented(TopAbs_FORWARD))  # the face as its wires bound it

    def probe(edge, u: np.ndarray, spans: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        pcurve = BRepAdaptor_Curve2d(edge, face)
        n = len(u)
        normals, curv, su, sv = np.zeros((n, 3)), np.zeros(n), np.zeros((n, 3)), np.zeros((n, 3))
        uv, tangent = np.zeros((n, 2)), np.zeros((n, 2))
        p, d = gp_Pnt2d(), gp_Vec2d()
        for k, uk in enumerate(u.tolist()):
            pcurve.D1(uk, p, d)
            props.SetParameters(p.X(), p.Y())
            if sided:
                uv[k], tangent[k] = p.Coord(), d.Coord()
                su[k], sv[k] = props.D1U().Coord(), props.D1V().Coord()
            if props.IsNormalDefined():
                normals[k] = props.Normal().Coord()
            if props.IsCurvatureDefined():
                curv[k] = max(abs(props.MaxCurvature()), abs(props.MinCurvature()))
        if not sided:
            return normals, curv, None
        if BRep_Tool.IsClosed_s(edge, face):
            return normals, curv, np.zeros((n, 3))
        side = _left_side(forward, uv, tangent, spans)
        if side is None:
            return normals, curv, None
        across = side * (tangent[:, :1] * sv - tangent[:, 1:] * su)  # the (u, v) left normal, on the surface
        size = np.linalg.norm(across, axis=1, keepdims=True)
        return normals, curv, np.divide(across, size, out=np.zeros_like(across), where=size > 0)

    return probe


#: How far off an edge :func:`_left_side` looks for the face, in shares of a segment's length in (u, v).
SIDE_STEPS = (0.05, 0.25)


def _left_side(face, uv: np.ndarray, tangent: np.ndarray, spans: np.ndarray) -> int | None:
    """+1 where ``face`` (FORWARD) lies left of the pcurve (in (u, v), looking along its parameter), -1
    right, None where a point on each side does not tell (both in, both out, on the boundary): probed
    beside the middle sample, a step of :data:`SIDE_STEPS` of its segment's (u, v) length off the pcurve
    (``BRepClass_FaceClassifier``: OCP 8.0 does not bind ``BRepTopAdaptor_FClass2d``)."""
    from OCP.BRepClass import BRepClass_FaceClassifier
    from OCP.TopAbs import TopAbs_IN, TopAbs_OUT
    from OCP.gp import gp_Pnt2d

    classifier = BRepClass_FaceClassifier()

    def state(point: np.ndarray):
        classifier.Perform(face, gp_Pnt2d(*point), 1e-9)
        return classifier.State()

    k = len(spans) // 2
    length = np.linalg.norm(tangent[k]) * spans[k]
    if not length > 0:
        return None
    left = np.array([-tangent[k, 1], tangent[k, 0]]) / np.linalg.norm(tangent[k])
    for step in SIDE_STEPS:
        states = [state(uv[k] + sign * step * length * left) for sign in (1.0, -1.0)]
        if states == [TopAbs_IN, TopAbs_OUT]:
            return 1
        if states == [TopAbs_OUT, TopAbs_IN]:
            return -1
    return None


#: A planar face given a cancellation credit keeps its boundary segments within this many times its mean
#: width ``2 area / perimeter``: periodic_u_cst's 1 mm strip, credited down to 4.4 mm segments, was filled
#: with 11-degree triangles (6% of them under 20 degrees); the unsigned rule had split it finer than that.
#: These splits are made only where they fit the thin faces' budget of :mod:`cadedge.mesh.widths`
#: (:func:`_thin_splits_fit`; else the widths' splits, which cut every thin face coarser to fit it): NX's
#: piattello plate (OCCT's test data) has twelve planar strips 0.001 wide along 14 mm arcs of radius 3,
#: and cut to 2 widths their arcs took 7 000 segments each (2 714 -> 179 986 in all at ALD 1e-2); the
#: 276 mm2 cylinders beside them took 92 000 triangles each, and 69 of the 313 faces ran out of the 300 s.
THIN_RATIO = 2.0
#: An edge is cut into at most about this many segments (the default per-face triangle budget,
#: :data:`~cadedge.mesh.budget.MAX_FACE_TRIANGLES`: a face cannot have more boundary segments than
#: triangles): a face 1e-9 of its length wide would otherwise ask billions of its edges.
MAX_PIECES = 400_000
#: Rounds of the planar faces' signed fit (see :func:`fit_boundaries`); each divides the cancellation
#: credit of a face still over its budget by :data:`CREDIT_STEP`.
PLANAR_ROUNDS, CREDIT_STEP = 4, 4.0
#: A curved face's boundary slivers cancel too where its edges bulge opposite ways (a flat coil's helical
#: band: the chords of its outer helix cut it short, those of its inner one add to it; a cone's chamfer
#: ring). Its budget is multiplied by the cancellation its signed slivers measure, ``sum |slivers| /
#: |sum of signed slivers|`` (on a planar ring the signed sum is the exact polygon's deficit within 1%),
#: where that is at least the first of these and at most the second. A 4-turn coil of 3 x 2 mm section on
#: a 15 mm radius had its helices cut into 366-416 segments of 0.8-1.0 mm at 1e-2 (10 092 triangles, its
#: bands at 1-2% of the target); credited 5x, 158-208 (2 436 triangles, every face within 0.13 of it).
CURVED_CREDIT = (2.0, 25.0)
#: A cone's credit is at most this. Its circles' chords leave the surface half along it (their slivers
#: cancel) and half off it (45-degree chamfers: the facets' tilt, which no cancellation offsets), so its
#: deficit grows with the credit: 0.03-0.12 of the target per unit of credit on the chamfers of
#: Kurbelwelle, the M6 screw, a cross-bored shaft and pocket_box at 1e-3, and io1-ug-214.stp's
#: chamfer ring (30 mm round, 1.4 mm wide), credited 25, was 1.57 times the target (0.47 at 8).
CONE_CREDIT = 8.0


def fit_boundaries(grid, surface_ald: float, *, brep_areas: np.ndarray | None = None,
                   kinds: list[str] | None = None, ratio: float = CURVATURE_RATIO) -> tuple[object, dict[int, float]]:
    """A copy of ``grid`` whose edge segments suit the surface target of every face they bound (the rules:
    :func:`_fit_boundaries`), and the cancellation credits of its curved faces (face id -> budget
    factor, :data:`CURVED_CREDIT`), which the later fits of the same faces take (:func:`fit_planes`,
    :func:`fit_grids`).

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

    measured = _Measured()  # every fit below is of ``grid``: its edges are probed once

    def fit(g, credit: dict[int, float]):
        return _fit_boundaries(g, surface_ald, brep_areas=areas, kinds=kinds, ratio=ratio, credit=credit,
                               measured=measured)

    fitted, gross, signed = fit(grid, {})
    curved = _curved_credits(gross, signed, kinds, (1.0 - INTERIOR_SHARE) * surface_ald * areas)
    if curved:
        fitted = fit(grid, curved)[0]
    if not planes:  # the grids' rows still: cut before other passes split the lines unevenly
        return fit_grids(fitted, surface_ald, brep_areas=areas, kinds=kinds, ratio=ratio, credit=curved), curved
    credit = _planar_credits(gross, net(grid), areas, limit, _shortest_shares(grid, len(areas)))
    for _ in range(PLANAR_ROUNDS):
        if not credit:
            break
        trial = fit(grid, {**curved, **credit})[0]
        now = net(trial)
        over = {f for f in credit if now.get(f, np.inf) > limit}
        if not over:
            fitted, credit = trial, {}
            break
        credit = {f: c / CREDIT_STEP if f in over else c for f, c in credit.items()}
        credit = {f: c for f, c in credit.items() if c > 1.0}
    if credit:
        fitted = fit(grid, {**curved, **credit})[0]
    fitted = fit_planes(fitted, surface_ald, brep_areas=areas, kinds=kinds, ratio=ratio, credit=curved)
    return fit_grids(fitted, surface_ald, brep_areas=areas, kinds=kinds, ratio=ratio, credit=curved), curved


def _planar_credits(gross: np.ndarray, deficits: dict[int, float], areas: np.ndarray, limit: float,
                    share: np.ndarray) -> dict[int, float]:
    """Face id -> budget factor of each planar face whose boundary slivers cancel: its unsigned estimate
    ``gross`` (as :func:`_fit_boundaries` sums it, index ``id - 1``) over its exact polygon's deficit
    (``deficits``, relative), halved, where that is over 1 and the unsigned rule could split one of its
    segments: a segment is split when its sliver is over its share of the face's budget (``limit`` times
    its area) by length, so not where all the face's slivers together are within the shortest segment's
    share (``share``: the face's shortest boundary segment over its perimeter). A face bounded by lines
    has slivers of rounding only: a KiCad barrel jack's ribbons 1-2e-6 wide and 0.3 long (sliver sums of
    1.6e-16, polygons 9e-11 off) were credited on that noise, and the credited faces' width rule
    (:data:`THIN_RATIO`) cut their edges into 93 385 pieces each; gmsh then hung on the face beside them."""
    credit = {f: 0.5 * gross[f - 1] / max(d * areas[f - 1], 1e-300) for f, d in deficits.items()
              if gross[f - 1] > limit * areas[f - 1] * share[f - 1]}
    return {f: c for f, c in credit.items() if c > 1.0}


def _shortest_shares(grid, faces: int) -> np.ndarray:
    """Each face's shortest boundary segment over its perimeter (index ``id - 1``, ``faces`` of them); a
    degenerate edge (a cone's apex: two points at one place) has no segment to split and is left out, as
    :func:`_fit_boundaries` leaves it out: its share of 0 would credit any rounding."""
    shortest = np.full(faces, np.inf)
    for e in grid.edges:
        if not e.degenerate and len(e.points) > 1:
            for f in e.faces:
                if 1 <= f <= faces:
                    shortest[f - 1] = min(shortest[f - 1], float(e.segment_lengths.min()))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(shortest / face_perimeters(grid, faces), nan=0.0, posinf=0.0)


def _curved_credits(gross: np.ndarray, signed: np.ndarray, kinds: list[str], budget: np.ndarray) -> dict[int, float]:
    """Face id -> budget factor of each curved face whose boundary slivers cancel (see
    :data:`CURVED_CREDIT`, a cone's at most :data:`CONE_CREDIT`) and are over its ``budget`` (elsewhere
    the unsigned rule splits nothing); ``gross`` and ``signed`` as :func:`_fit_boundaries` sums them."""
    least, most = CURVED_CREDIT
    cap = np.array([CONE_CREDIT if kind == "Cone" else most for kind in kinds])
    with np.errstate(divide="ignore", invalid="ignore"):
        credit = np.minimum(gross / np.abs(signed), cap)
    return {int(f) + 1: float(credit[f]) for f in np.nonzero((gross > budget) & (credit >= least))[0]
            if kinds[f] != "Plane"}


def fit_curved(grid, surface_ald: float, *, brep_areas: np.ndarray, kinds: list[str], ratio: float = CURVATURE_RATIO,
               credit: dict[int, float]) -> tuple[object, dict[int, float]]:
    """``grid`` with the edges of the credited curved faces whose signed slivers, on their present segments,
    are over :data:`AIM` times ``surface_ald`` of their area fitted again, each such face's credit halved
    round after round until they are within it (under :data:`CURVED_CREDIT`'s least, no credit: the
    unsigned rule), and the credits as lowered.

    A credit is measured on the segments before the fit, where a ring's two circles are cut alike; a
    neighbour's rule may then cut one of them far finer, and the other's loss is left uncancelled. A
    transistor can's top (KiCad's TO-18-3.step: a cone ring 0.34 mm wide, nearly flat) had its inner circle
    cut into 703 segments for the dome beside it and its outer one kept at 170 under a credit of 8: its
    signed slivers 1.06 times the target at 1e-3, meshed at 1.04 and named as not converging. The signed
    sum is what such a ring's mesh loses (1.03 and 1.06 of the target against 1.03 and 1.04 meshed, on
    the test can of ``tests/test_mesh_fidelity.py`` and TO-18-3), so the face is fitted again
    where it leaves less than the interior's share of the target, the same :data:`AIM` as a planar face's
    polygon. The mesher calls this once its boundary splits are done, after :func:`fit_planes`: the
    grading of a face's boundary from its own spacings cuts such an outer circle finer too, and checked
    before it, TO-5-3's ring at 1e-2 (1.48 times the target then, 0.07 as meshed) had its credit halved
    for nothing (2 122 -> 4 537 triangles)."""
    areas = np.asarray(brep_areas, dtype=float)
    limit = AIM * surface_ald * areas
    credit = dict(credit)
    measured = _Measured()  # every refit below is of ``grid``: its edges are probed once

    def over(g, faces: set[int], probed: _Measured | None = None) -> set[int]:  # signed slivers over the limit
        _, _, signed = _fit_boundaries(g, surface_ald, brep_areas=areas, kinds=kinds, ratio=ratio, credit=credit,
                                       only=faces, measured=probed)
        return {f for f in faces if abs(signed[f - 1]) > limit[f - 1]}

    fitted, refitted = grid, set()
    short = over(grid, {f for f in credit if kinds[f - 1] != "Plane"}, measured)
    while short:
        credit = {f: c / 2.0 if f in short else c for f, c in credit.items()}
        credit = {f: c for f, c in credit.items() if c >= CURVED_CREDIT[0] or f not in short}
        refitted |= short
        fitted = _fit_boundaries(grid, surface_ald, brep_areas=areas, kinds=kinds, ratio=ratio, credit=credit,
                                 only=refitted, measured=measured)[0]
        short = over(fitted, short & set(credit))
    return fitted, credit


def fit_grids(grid, surface_ald: float, *, brep_areas: np.ndarray, kinds: list[str], ratio: float = CURVATURE_RATIO,
              credit: dict[int, float] | None = None):
    """``grid`` with the lines of the cylinders that may be meshed as a grid
    (:func:`cadedge.mesh.gridded.grid_faces`) split into rows as tall as the grid's columns, the fewest
    for ``surface_ald``, are wide, graded from a finer circle at an end
    (:meth:`~cadedge.mesh.gridded.GridFit.line_params`), and the parallels and tube arc of such tori cut
    into their columns and rows (:meth:`~cadedge.mesh.gridded.GridFit.cut`); or by the curvature rule
    where that grid would take more than :data:`~cadedge.mesh.gridded.MOST_TRIANGLES`. The faces' other
    edges first, the grids' held: their circles may be split further (for a planar ring beside them), and
    a line graded from a circle's coarser segments keeps those nodes (a thin tube's: 3x steps where 1.3x
    were asked). ``credit``: the curved faces' cancellation credits (:func:`fit_boundaries`)."""
    from .gridded import MOST_TRIANGLES, grid_faces

    areas = np.asarray(brep_areas, dtype=float)
    for hold in (True, False):
        fits = grid_faces(grid, kinds, surface_ald, areas)
        if not fits:
            break
        grids = {f: 0 if hold else g if g.triangles(areas[f - 1]) <= MOST_TRIANGLES else None
                 for f, g in fits.items()}
        grid = _fit_boundaries(grid, surface_ald, brep_areas=areas, kinds=kinds, ratio=ratio, credit=credit or {},
                               only=set(fits), grids=grids)[0]
    return grid


def _planes(areas: np.ndarray, kinds: list[str]) -> list[int]:
    """Ids of the faces meshed as planes with a positive B-rep area."""
    return [i + 1 for i, k in enumerate(kinds) if k == "Plane" and areas[i] > 0]


def _plane_deficits(grid, planes: list[int], areas: np.ndarray) -> dict[int, float]:
    """Exact |area deficit| of each checkable planar face of ``planes``: its boundary polygon's area
    (:func:`cadedge.mesh.planar.planar_polygon_areas`) against its B-rep area."""
    from .planar import planar_polygon_areas

    return {f: abs(1.0 - a / areas[f - 1]) for f, a in planar_polygon_areas(grid.shape, grid, planes).items()}


def plane_room(grid, surface_ald: float, *, brep_areas: np.ndarray, kinds: list[str]) -> np.ndarray:
    """The area each face (by face id - 1) may still lose or gain before :func:`fit_planes` fits it again:
    for a checkable planar face, what its boundary polygon has left below :data:`AIM` times
    ``surface_ald`` of its area; for any other face, no bound (inf)."""
    areas = np.asarray(brep_areas, dtype=float)
    room = np.full(len(areas), np.inf)
    for f, d in _plane_deficits(grid, _planes(areas, kinds), areas).items():
        room[f - 1] = max(AIM * surface_ald - d, 0.0) * areas[f - 1]
    return room


#: Rounds of :func:`fit_planes`.
REFIT_ROUNDS = 4


def fit_planes(grid, surface_ald: float, *, brep_areas: np.ndarray, kinds: list[str],
               ratio: float = CURVATURE_RATIO, credit: dict[int, float] | None = None):
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
    again once its boundary splits are done. ``credit``: the curved faces' cancellation credits
    (:func:`fit_boundaries`), for the curved faces beside the planes."""
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
        trial = _fit_boundaries(grid, surface_ald, brep_areas=areas, kinds=kinds, ratio=ratio,
                                credit=credit or {}, only=over)[0]
        after = _plane_deficits(trial, planes, areas)
        if not any(after.get(f, np.inf) <= 0.5 * now[f] for f in over):
            break
        grid = trial
    return grid


@dataclass
class _Measured:
    """What :func:`_fit_boundaries` measures of one grid, kept for its next fit of the same grid: the
    shape's topology, each face's probe and, per edge index, its curve, its segments' sagittas and the
    probes of its faces (None where the edge is left alone)."""

    topo: object = None
    probes: dict[int, object] = field(default_factory=dict)
    edges: dict[int, tuple | None] = field(default_factory=dict)


def _fit_boundaries(grid, surface_ald: float, *, brep_areas: np.ndarray, kinds: list[str], ratio: float,
                    credit: dict[int, float], only: set[int] | None = None,
                    grids: dict[int, object] | None = None, measured: _Measured | None = None):
    """A copy of ``grid`` whose edge segments suit the surface target of every face they bound (``only``:
    the edges of those faces only), and the summed unsigned sliver estimate of each face's boundary before
    the splits (index ``id - 1``; of the edges looked at), and the same with signs: positive where a
    curve bulges out of the face (its chord cuts the face short), negative where it bulges in (unsigned
    where the face's side of the edge cannot be told, nothing on a seam).

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
      into 1 838 pieces of 0.008 mm, finer than the face's interior could follow); a line of a cylinder
      that may be meshed as a grid (:func:`cadedge.mesh.gridded.grid_faces`) is not split for it until its
      circles are fitted, then into rows as tall as the grid's columns are wide, graded from a finer
      circle (``grids``: face -> its :class:`~cadedge.mesh.gridded.GridFit`, whose
      :meth:`~cadedge.mesh.gridded.GridFit.line_params` cuts it after the other rules; or None where the
      grid would take too many triangles and the curvature rule holds); a grid torus's parallels and tube
      arc are not split at all until then (for no face: its equal columns, finer than any other rule asks
      of its parallels, are what its neighbours get), then into its rows and columns, both parallels at
      the same angles (:meth:`~cadedge.mesh.gridded.GridFit.cut`);
    - the face's boundary polygon loses too much area: the sliver between a segment and its curve,
      ``2/3 * chord * sagitta`` with the sagitta's component tangent to the face (a circle on a cylinder
      loses nothing to the cylinder, all to a planar cap), summed over the face's boundary, must stay
      within ``(1 - INTERIOR_SHARE) * surface_ald`` of its B-rep area (``AIM * surface_ald`` on a plane).
      Splitting a segment in ``k`` divides its sliver by ``k**2``; each segment gets a share of the
      budget by its length.

    ``measured``: what an earlier call measured of the same ``grid`` (filled here), so that fitting it
    again with other credits does not probe its edges again.
    """
    from ..errors import GeometryError
    from ..occt.compat import OCCT_ERRORS
    from ..occt.edgecurve import EdgeCurve
    from ..occt.topology import Topology
    from ..shapegrid import end_tolerances, with_edges
    from ..splitting import fits_curve, insert_points, split_segments
    from .budget import filling_size
    from .gridded import grid_faces

    measured = measured or _Measured()
    if measured.topo is None:
        measured.topo = Topology(grid.shape)
    topo, probes = measured.topo, measured.probes
    if grids is None:  # 0: not fitted yet (fit_grids passes the faces it found, None: not a grid)
        grids = dict.fromkeys(grid_faces(grid, kinds, surface_ald, brep_areas), 0)
    grids = {f: g for f, g in grids.items() if g is not None}
    areas = brep_areas
    h_factor = np.array([2.0 * np.pi / per_circle(surface_ald, k) for k in kinds])  # size = h_factor / k
    share = np.array([AIM if k == "Plane" else 1.0 - INTERIOR_SHARE for k in kinds])
    filled = filling_size(areas)
    budget = share * surface_ald * areas
    for f, c in credit.items():
        budget[f - 1] *= c
    gross, net = np.zeros(len(areas)), np.zeros(len(areas))
    perimeter = face_perimeters(grid, len(areas))
    with np.errstate(divide="ignore", invalid="ignore"):
        width = np.where(perimeter > 0, 2.0 * areas / perimeter, np.inf)  # a strip's width, exactly
    within_tolerance = ~(areas > 0) | (width < _edge_tolerances(grid, len(areas)))  # no target to cut for
    edges = list(grid.edges)
    # dlr_f6.brep's edge 278, its ends off its curve within its vertices' tolerances, was never fitted, its
    # face 94 kept at 6.3e-3 against 1e-3 (8.6e-4 once fitted)
    ends = end_tolerances(grid)
    plans = []  # per edge: (index, curve, pieces, most, narrowest credited face, grid rows, grid cut)
    for i, e in enumerate(edges):
        if e.degenerate or len(e.points) < 2 or not e.faces or not np.all(np.diff(e.params) > 0):
            continue
        if only is not None and not set(e.faces) & only:
            continue
        if i not in measured.edges:
            measured.edges[i] = None
            try:
                curve = EdgeCurve(topo.edges[e.id - 1], e.id)
                if not fits_curve(e.params, e.points, curve.evaluate, ends[e.id]):
                    continue  # the grid's parameters are not this curve's: leave the edge alone
                mid_u = 0.5 * (e.params[:-1] + e.params[1:])
                sagitta = _sagittas(e.params, e.points, curve.evaluate)
                for f in e.faces:  # one probe per face (its adaptor bounds the face's pcurves: costly on many holes)
                    if f not in probes:
                        probes[f] = _face_probe(topo.faces[f - 1], sided=kinds[f - 1] != "Plane")
                measured.edges[i] = curve, sagitta, [(f, *probes[f](curve.edge, mid_u, np.diff(e.params)))
                                                     for f in e.faces]
            except (GeometryError, *OCCT_ERRORS):  # OCCT cannot evaluate this edge: keep its grid
                continue
        if measured.edges[i] is None:
            continue
        curve, sagitta, probed = measured.edges[i]
        chord = e.segment_lengths
        straight = e.curve == "Line" or bool(np.all(np.linalg.norm(sagitta, axis=1) <= STRAIGHT_TOL * chord))
        edge_ratio = min(ratio, STRAIGHT_RATIO) if straight else ratio
        pieces = np.ones(len(chord), dtype=int)
        thin = np.inf  # the narrowest credited face of this edge (THIN_RATIO): split after the loop
        most = max(1, MAX_PIECES // len(chord))  # a segment's pieces at most: the edge's, MAX_PIECES in all
        rows = None  # the GridFit of a grid face this edge is a line of
        torus = None  # the GridFit of a grid torus this edge bounds (0: held until fit_grids cuts it)
        for f, normals, curv, inward in probed:
            tangential = sagitta - np.sum(sagitta * normals, axis=1)[:, None] * normals
            sliver = 2.0 / 3.0 * chord * np.linalg.norm(tangential, axis=1)
            gross[f - 1] += sliver.sum()  # a curve bulging out of the face: its chords cut the face short
            net[f - 1] += sliver.sum() if inward is None else -np.sum(
                sliver * np.sign(np.sum(tangential * inward, axis=1)))
            allowed = budget[f - 1] * chord / max(perimeter[f - 1], 1e-300)
            with np.errstate(divide="ignore", invalid="ignore"):
                if within_tolerance[f - 1]:  # no area (degenerate), or all of it within its edges' tolerance
                    k_curv = k_area = 1
                else:
                    k_curv = np.where(curv > 0, np.ceil(chord * curv / (edge_ratio * h_factor[f - 1])), 1)
                    k_curv = np.minimum(k_curv, np.maximum(np.floor(chord / filled[f - 1]), 1))
                    k_area = np.where(sliver > allowed, np.ceil(np.sqrt(sliver / allowed)), 1)
                    if f in credit:
                        thin = min(thin, width[f - 1])
            if f in grids and kinds[f - 1] == "Torus":  # its columns and rows, cut below
                k_curv, torus = 1, grids[f]
            elif straight and f in grids:  # a grid's rows, cut below (not by the curvature rule)
                k_curv, rows = 1, grids[f] or rows
            asked = np.nan_to_num(np.maximum(k_area, k_curv), nan=1.0, posinf=1.0)
            pieces = np.maximum(pieces, np.minimum(asked, most).astype(int))
        if torus is not None and not torus:  # uncut: the torus's columns, cut later, suit its neighbours too
            continue
        cut = torus.cut(e.id, e.params) if torus else None  # the grid's columns or rows, finer than any
        if cut is not None:  # other rule asks
            pieces[:] = 1
            thin = np.inf
        plans.append((i, curve, pieces, most, thin, rows, cut))
    thin_cuts = _thin_splits_fit([(edges[i].segment_lengths, pieces, most, thin)
                                  for i, _, pieces, most, thin, _, _ in plans], grid.segments)
    for i, curve, pieces, most, thin, rows, cut in plans:
        e = edges[i]
        if thin_cuts and np.isfinite(thin) and thin > 0:
            pieces = np.maximum(pieces, np.minimum(np.ceil(e.segment_lengths / (THIN_RATIO * thin)), most).astype(int))
        params, points = e.params, e.points
        if np.any(pieces > 1):
            params, points = split_segments(params, points, pieces, curve.evaluate, spacing="parameter")
        if rows is not None:  # as tall as the grid's columns are wide, graded from a finer circle
            cut = rows.line_params(params, points)
        if cut is not None:  # a grid's parameters: the edge's all kept, the others new points on it
            if len(new := cut[~np.isin(cut, params)]):
                params, points = insert_points(params, points, new, curve.evaluate(new))
        if len(params) > len(e.params):
            edges[i] = replace(e, params=params, points=points)
    return with_edges(grid, edges), gross, net


def _edge_tolerances(grid, faces: int) -> np.ndarray:
    """The largest tolerance of each face's edges (index ``id - 1``). A face narrower than it (mean width
    ``2 area / perimeter``) is not cut for: its boundary may lie anywhere across it. OCCT's Alias test
    file trj3_s1-al-214.stp has faces of 1.6e-7 mm2 inside one loose edge 2.6 mm long (tolerance
    0.046): cut for their area target, each such edge took 58 000 segments (1 061 -> 466 592 in all at
    ALD 1e-2) and the faces beside them were never meshed."""
    out = np.zeros(faces)
    for e in grid.edges:
        for f in set(e.faces):
            if 0 < f <= faces:
                out[f - 1] = max(out[f - 1], e.tolerance)
    return out


def _thin_splits_fit(plans: list[tuple[np.ndarray, np.ndarray, int, float]], segments: int) -> bool:
    """Whether the pieces that cutting credited faces' edges to :data:`THIN_RATIO` times their width adds
    fit the budget of thin faces' splits (:data:`~cadedge.mesh.widths.BUDGET_FACTOR` times the grid's
    ``segments`` plus :data:`~cadedge.mesh.widths.MIN_BUDGET`, at most
    :data:`~cadedge.mesh.widths.MOST_ADDED`); where they do not, the thin faces are left to the widths'
    own splits, which hold to that budget by cutting every thin face coarser. ``plans``: per edge, its
    segments' lengths, the pieces the other rules cut them into, the most pieces a segment may take,
    and its narrowest credited face's width (``inf``: none)."""
    from .widths import BUDGET_FACTOR, MIN_BUDGET, MOST_ADDED

    rows = [p for p in plans if np.isfinite(p[3]) and p[3] > 0]
    if not rows:
        return True
    added = sum(int(np.sum(np.maximum(np.minimum(np.ceil(chord / (THIN_RATIO * width)), most), pieces) - pieces))
                for chord, pieces, most, width in rows)
    return added <= min(BUDGET_FACTOR * segments + MIN_BUDGET, MOST_ADDED)


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
