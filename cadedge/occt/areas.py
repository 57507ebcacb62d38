"""B-rep face areas that the mesh's area deficits can be measured against.

OCCT integrates a face's area two ways, and each is badly off on some faces:
``BRepGProp::SurfaceProperties`` with its default fixed order lost 0.3% on a planar face bounded by
B-spline curves (periodic_u_cst face 2: 229.73 instead of 230.41 mm2) and 4.8% on B-spline face 4 of
mesh_T106_V3; the adaptive integration to a precision gained 0.42% on a thickened wavy plate's offset
face and was 0.12% off on wing_fuselage's faces 7 and 15, more than the area targets measured against
it. Where the two agree (within :data:`AGREE`), that is the area. Where they do not, the surface's area
element ``|S_u x S_v|`` is integrated over the face's parameter domain independently: over a
triangulation of it (OCCT's ``BRepMesh`` on a copy of the face, a degree-4 rule per triangle) plus the
slivers between the boundary chords and the face's pcurves. On those faces it is within 3e-6 of the
converged value on a coarse triangulation (0.02-0.34 s a face), but one triangulation can be off, so it
is taken at finer deflections until two agree (:func:`settled_domain_area`); it is the area unless it
falls far outside both OCCT values (then the nearer of them).

A planar face bounded by curves other than lines, circles and ellipses is measured by its boundary
instead (:func:`plane_area`): the area its edges' curves enclose in its plane, which its mesh's
polygon tends to; OCCT's integrations were both 0.12% low on such a face read from a STEP file.

A face whose boundary is open in its parameter space (its wires leave gaps between one edge's pcurve and
the next, as loose tolerances allow: a sewn model, 917_fusee's faces with gaps up to 0.08 mm) has no
area until the gaps are closed. OCCT's integrations (``F dv`` along the pcurves, ``F`` the area element
integrated over u from the face's smallest u) leave the gaps out, so what they give depends on where the
face's u range starts: gapped_sewn's planar face 6 came out 40.154 where the polygon of its pcurves,
closed by chords, is 40.018 and its mesh 40.028. The chords closing the gaps are integrated the same
way and added (:func:`closure`): the sum is the area of the face with its gaps closed. It agrees to 1e-9
with the polygon of a gapped box's planar pcurves, and to 1e-6 on gapped_sewn's faces with Green's
theorem taken along v from the middle of the face (no reference left to depend on).
"""

from __future__ import annotations

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy
from OCP.BRepGProp import BRepGProp
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepTools import BRepTools
from OCP.GeomAbs import (GeomAbs_Circle, GeomAbs_CN, GeomAbs_Ellipse, GeomAbs_Line, GeomAbs_Plane,
                         GeomAbs_SurfaceOfExtrusion)
from OCP.GProp import GProp_GProps
from OCP.gp import gp_Pnt, gp_Pnt2d, gp_Vec, gp_Vec2d
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FORWARD, TopAbs_REVERSED
from OCP.TopExp import TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS_Face, TopoDS_Shape

from ..errors import GeometryError
from ..grid import polygon_area
from .compat import OCCT_ERRORS, TColStd_Array1OfReal, TopoDS
from .topology import Topology, walked_wires

#: Precision asked of OCCT's adaptive integration.
AREA_EPS = 1e-6
#: Relative difference under which OCCT's two integrations are taken to agree (a hundredth of the
#: finest face target, 1e-3).
AGREE = 1e-5
#: The check triangulation: linear deflection as a fraction of the square root of the face's area,
#: and angular deflection in radians.
CHECK_DEFLECTION = 1e-3
CHECK_ANGLE = 0.2
#: The check counts where it agrees within this share with one of OCCT's integrations, or with the check at
#: the deflection three times coarser (down to the :data:`CHECK_LEVELS`-th).
CHECK_AGREE = 2e-4
CHECK_LEVELS = 4
#: The most nodes a check triangulation may have; a level is not meshed where the level before it had
#: over a third of this (the nodes about triple a level). On the corpus, the fixtures and the Koch leader
#: arm a check stays under 6 000 nodes. A revolved spline of 10 sine waves (radius of curvature 0.46) took
#: 14 139, 60 316, 106 357 and 363 221 nodes over its four levels, 141 s in all (BRepMesh 68 s on the
#: last), and the 0.8 mm shell's offset of it, whose curvature radius goes below its offset (a surface
#: folding on itself), 215 266 at the first level: its areas were measured for minutes before anything
#: was meshed.
CHECK_NODES = 100_000
#: The 6-point degree-4 rule on a triangle (Dunavant): barycentric points and weights summing to 1.
_A1, _B1, _A2, _B2 = 0.445948490915965, 0.108103018168070, 0.091576213509771, 0.816847572980459
_BARY = np.array([[_A1, _A1, _B1], [_A1, _B1, _A1], [_B1, _A1, _A1],
                  [_A2, _A2, _B2], [_A2, _B2, _A2], [_B2, _A2, _A2]])
_WEIGHTS = np.array([0.223381589678011] * 3 + [0.109951743655322] * 3)
#: A face of linear extrusion: Gauss-Legendre points per part of a span of its swept curve (the parts
#: doubled until the section's integral changes by less than a hundredth of ``AREA_EPS``), and the
#: composite rule along each pcurve, its pieces doubled from the first count until the integral changes
#: by less than ``AREA_EPS`` (each at most :data:`SWEPT_LEVELS` times).
SWEPT_POINTS = 8
SWEPT_PIECES = 4
SWEPT_LEVELS = 8
#: Gauss-Legendre points per boundary chord for its sliver.
SLIVER_POINTS = 6
#: Gaps in a face's boundary narrower than this share of the square root of its area (in 3-D, through its
#: surface) are left open: closing one moves the area by about that share. The faces of closed wires on the
#: corpus and the hard models stay under 7e-8 (periodic_u_cst face 1); 917_fusee's gaps reach 1e-2.
OPEN = 1e-6
#: :func:`closure`'s rule: Gauss-Legendre points (along a chord, and per piece of ``F``'s integral), pieces
#: of ``F``'s integral at the first level, and the levels (pieces doubled each time) it may take.
GREEN_POINTS = 8
GREEN_PIECES = 2
GREEN_LEVELS = 3


def face_areas(shape: TopoDS_Shape) -> np.ndarray:
    """Area of every face of ``shape`` in ``TopExp::MapShapes`` order (index ``id - 1``). A face that is an
    earlier one placed again by a rigid motion (:func:`cadedge.occt.instances.same_faces`) has its area:
    the Koch leader arm's 4 704 faces, 3 358 of them placed again, 4.3 -> 1.4 s (areas within 6e-13)."""
    from .instances import same_faces

    faces = Topology(shape).faces
    again = same_faces(shape)
    out = np.zeros(len(faces))
    for i, face in enumerate(faces):
        out[i] = out[again[i + 1] - 1] if i + 1 in again else face_area(face)
    return out


def face_area(face: TopoDS_Face) -> float:
    """One face's area: a face of linear extrusion's by :func:`extrusion_area`, a planar face with curved
    edges other than circles and ellipses by :func:`plane_area`; else OCCT's two
    integrations (with the gaps of an open boundary closed, see :func:`closure`) where they agree, else
    the one the check confirms."""
    forward = TopoDS.Face_s(face.Oriented(TopAbs_FORWARD))
    exact = extrusion_area(forward)
    if exact is None:
        exact = plane_area(forward)
    if exact is not None:
        return exact
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(forward, props, AREA_EPS)
    adaptive = props.Mass()
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(forward, props)
    fixed = props.Mass()
    shift = closure(forward, max(abs(adaptive), abs(fixed)))
    adaptive, fixed = abs(adaptive + shift), abs(fixed + shift)
    gap = abs(adaptive - fixed)
    if gap <= AGREE * max(adaptive, fixed):
        return adaptive
    check = settled_domain_area(face, CHECK_DEFLECTION * np.sqrt(max(adaptive, fixed)), (adaptive, fixed))
    low, high = min(adaptive, fixed) - gap, max(adaptive, fixed) + gap
    if check is None or not low <= check <= high:  # no check, or one far from both: OCCT's nearest
        return adaptive if check is None else min((adaptive, fixed), key=lambda a: abs(a - check))
    return check


def extrusion_area(face: TopoDS_Face) -> float | None:
    """The area of a FORWARD face of linear extrusion, by Green's theorem: ``F(u) dv`` integrated along
    its pcurves (and the chords closing any gaps between them), ``F`` the area element (alike at every
    v) integrated over u from the swept curve's first parameter, span by span of it (composite
    Gauss-Legendre, :data:`SWEPT_POINTS`). None if the face is not one, its wires cannot be walked or the surface
    fails to evaluate.

    OCCT's integrations sample such a face as any surface; on a gear's side, the extrusion by 10 mm of a
    periodic spline through 600 points with 30 sharp valleys (section 367.107 mm long, so 3 671.07 mm2),
    the adaptive one gave 3 940.4 and at a precision of 1e-9 4 143.1, and the check took minutes; here
    it is exact to rounding, in milliseconds a span."""
    try:
        surface = BRepAdaptor_Surface(face, False)
        if surface.GetType() != GeomAbs_SurfaceOfExtrusion:
            return None
        loops = _loops(face)
        if not loops:
            return None
        swept = surface.BasisCurve()
        n = swept.NbIntervals(GeomAbs_CN)
        knots = TColStd_Array1OfReal(1, n + 1)
        swept.Intervals(knots, GeomAbs_CN)
        knots = np.array([knots.Value(i) for i in range(1, n + 2)])
        period = swept.Period() if swept.IsPeriodic() else None
        v0 = 0.5 * sum(BRepTools.UVBounds_s(face)[2:])  # alike at every v; the surface's v may be infinite
        x, w = np.polynomial.legendre.leggauss(SWEPT_POINTS)

        def along(lo: np.ndarray, hi: np.ndarray, pieces: int) -> np.ndarray:
            """The area element integrated over u from ``lo`` to ``hi`` (within one span each), each in
            ``pieces`` equal parts."""
            edges = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, pieces + 1)
            half = 0.5 * np.diff(edges, axis=1)
            u = (edges[:, :-1] + half)[..., None] + half[..., None] * x
            element = _area_element(surface, np.column_stack([u.ravel(), np.full(u.size, v0)])).reshape(u.shape)
            return np.sum(half * (element @ w), axis=1)

        pieces, at_knots = 1, None
        for _ in range(SWEPT_LEVELS):  # the spans' parts doubled until the whole section's F settles
            spans = along(knots[:-1], knots[1:], pieces)
            if at_knots is not None and abs(spans.sum() - at_knots[-1]) <= 1e-2 * AREA_EPS * abs(spans.sum()):
                break
            at_knots = np.concatenate([[0.0], np.cumsum(spans)])
            pieces *= 2
        at_knots = np.concatenate([[0.0], np.cumsum(spans)])

        def integral(u: np.ndarray) -> np.ndarray:
            """``F(u)``: from the first knot, whole periods added for a periodic curve."""
            turns = np.floor((u - knots[0]) / period) if period else np.zeros(len(u))
            u = u - turns * (period or 0.0)
            span = np.clip(np.searchsorted(knots, u, side="right") - 1, 0, n - 1)
            return turns * at_knots[-1] + at_knots[span] + along(knots[span], u, pieces)

        def piece(points, a: float, b: float) -> float:
            """``F dv`` along the curve ``points(t) -> (uv, d uv / dt)`` from ``a`` to ``b``."""
            previous = None
            for level in range(SWEPT_LEVELS):
                s = np.linspace(a, b, (SWEPT_PIECES << level) + 1)
                half = 0.5 * np.diff(s)
                t = ((s[:-1] + half)[:, None] + half[:, None] * x).ravel()
                uv, d = points(t)
                moving = d[:, 1] != 0.0
                if not moving.any():
                    return 0.0
                f = np.zeros(len(t))
                f[moving] = integral(uv[moving, 0]) * d[moving, 1]
                total = float(np.sum(f.reshape(len(half), -1) @ w * half))
                if previous is not None and abs(total - previous) <= AREA_EPS * max(abs(total), 1e-300):
                    break
                previous = total
            return total

        total = 0.0
        for loop in loops:
            for pcurve, a, b in loop:
                total += piece(lambda t, c=pcurve: _pcurve_points(c, t), a, b)
            for start, end in _chord_gaps(loop):
                if np.any(start != end):
                    total += piece(lambda t, p=start, q=end: (p + np.outer(t, q - p), np.tile(q - p, (len(t), 1))),
                                   0.0, 1.0)
    except OCCT_ERRORS:
        return None
    return abs(total) if np.isfinite(total) else None


#: Edge curves OCCT integrates a planar face's area along well; a planar face bounded by anything else
#: (B-splines, offsets) is measured by :func:`plane_area`.
_EXACT_EDGES = (GeomAbs_Line, GeomAbs_Circle, GeomAbs_Ellipse)
#: :func:`plane_area`'s samples per edge at the first level, and the levels (samples doubled each time).
PLANE_SAMPLES = 64
PLANE_LEVELS = 10


def plane_area(face: TopoDS_Face) -> float | None:
    """The area a planar face's boundary encloses in its plane, for a FORWARD face on a plane with an
    edge that is not a line, circle or ellipse (None for any other face, or if its wires cannot be walked
    or an edge cannot be evaluated): the polygon of its edges' 3-D curves, each sampled at equal parameter
    steps in walking order (gaps closed by chords), the samples doubled and the areas extrapolated
    (Richardson, the polygon's error falling as the square of the step) until two agree within
    ``AREA_EPS``. The curves are what the mesh's boundary nodes lie on, so this is the area its polygon
    tends to.

    OCCT's two integrations were both 0.12% low on the cap of a 20 mm stadium outline with 1 mm round
    ends read from a STEP file, a periodic spline through 120 points (43.0896 against 43.1422 mm2): a mesh
    within 8e-5 of the cap was measured 1.14e-3 over it."""
    from .edgecurve import EdgeCurve
    from .planes import plane_of

    try:
        if BRepAdaptor_Surface(face, False).GetType() != GeomAbs_Plane:
            return None
        walked, plane = walked_wires(face), plane_of(face)
        if walked is None or plane is None:
            return None
        loops = [[(EdgeCurve(e), e.Orientation() == TopAbs_REVERSED) for e in edges if not BRep_Tool.Degenerated_s(e)]
                 for edges in walked]
        if all(c.kind in _EXACT_EDGES for loop in loops for c, _ in loop):
            return None
    except (GeometryError, *OCCT_ERRORS):
        return None
    origin, axes = plane[0], np.array(plane[1:])
    areas: list[float] = []
    for level in range(PLANE_LEVELS):
        t = np.linspace(0.0, 1.0, (PLANE_SAMPLES << level) + 1)[:-1]
        total = 0.0
        for loop in loops:
            points = []
            for curve, reversed_ in loop:
                a, b = curve.domain
                try:
                    points.append(curve.evaluate(b - t * (b - a) if reversed_ else a + t * (b - a)))
                except GeometryError:
                    return None
            if points:
                total += polygon_area((np.vstack(points) - origin) @ axes.T)
        areas.append(abs(total))
        if len(areas) >= 3:
            new, old = (4.0 * areas[-1] - areas[-2]) / 3.0, (4.0 * areas[-2] - areas[-3]) / 3.0
            if abs(new - old) <= AREA_EPS * abs(new):
                return new if np.isfinite(new) else None
    return None


def settled_domain_area(face: TopoDS_Face, deflection: float, near: tuple[float, ...] = ()) -> float | None:
    """:func:`domain_area` at ``deflection``, kept where it agrees within :data:`CHECK_AGREE` with one of
    ``near`` (OCCT's integrations); else at a third of the deflection, and so on (:data:`CHECK_LEVELS` at
    most), until two in a row agree: the finer of them. None if none do (or OCCT gives no triangulation).

    One triangulation alone can be off: the cap of an extruded stadium outline read from STEP came out
    43.0896 at the default deflection, 0.12% low and between OCCT's 43.1422 and 42.807, and 43.1425,
    43.1421, 43.1423 at a third, a ninth and a 27th of it (the outline encloses 43.1422)."""
    previous, nodes = None, 0
    for level in range(CHECK_LEVELS):
        if 3 * nodes > CHECK_NODES:  # the next level would be over the bound
            return None
        value, nodes = _domain_area(face, deflection / 3.0 ** level)
        if value is None:
            return None
        agree = near if previous is None else (previous,)
        if any(abs(value - other) <= CHECK_AGREE * abs(value) for other in agree):
            return value
        previous = value
    return None


def domain_area(face: TopoDS_Face, deflection: float) -> float | None:
    """``|S_u x S_v|`` integrated over the face's parameter domain: over a triangulation of it (a 6-point
    rule per triangle, exact for quartics), plus, along its boundary, the slivers between each
    boundary chord and the curve it cuts (the face's pcurves, Gauss-Legendre), so a coarse triangulation
    will do. None if OCCT gives no triangulation (or no boundary parameters), one of over
    :data:`CHECK_NODES` nodes, or the surface fails to evaluate. The triangulation is made on a copy:
    the caller's shape keeps what it carries."""
    return _domain_area(face, deflection)[0]


def _domain_area(face: TopoDS_Face, deflection: float) -> tuple[float | None, int]:
    """:func:`domain_area`, and the nodes of its triangulation (0 where there is none)."""
    nodes = 0
    try:
        copy = TopoDS.Face_s(BRepBuilderAPI_Copy(face).Shape().Oriented(TopAbs_FORWARD))
        BRepMesh_IncrementalMesh(copy, deflection, False, CHECK_ANGLE, False)
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(copy, loc)
        if tri is None or tri.NbTriangles() == 0:
            return None, 0
        nodes = tri.NbNodes()
        if nodes > CHECK_NODES:
            return None, nodes
        surface = BRepAdaptor_Surface(copy)
        uv = np.array([(p.X(), p.Y()) for p in (tri.UVNode(i) for i in range(1, tri.NbNodes() + 1))])
        corners = uv[np.array([[t.Value(1), t.Value(2), t.Value(3)]
                               for t in (tri.Triangle(i) for i in range(1, tri.NbTriangles() + 1))]) - 1]
        e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
        areas = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        points = np.einsum("qk,tkd->qtd", _BARY, corners).reshape(-1, 2)
        inner = float(_WEIGHTS @ (_area_element(surface, points).reshape(len(_WEIGHTS), -1) @ areas))
        slivers = _slivers(copy, tri, loc, surface)
    except OCCT_ERRORS:
        return None, nodes
    return (None if slivers is None else inner + slivers), nodes


def _loops(face: TopoDS_Face) -> list[list[tuple[object, float, float]]] | None:
    """Each wire of a FORWARD ``face`` as the pcurves of its edges in walking order, each with the
    parameters it is walked from and to; None if an edge has no pcurve or the walk skips an edge."""
    walked = walked_wires(face)
    if walked is None:
        return None
    loops = []
    for edges in walked:
        loop = []
        for edge in edges:
            pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
            if pcurve is None:
                return None
            a, b = BRep_Tool.Range_s(edge)
            loop.append((pcurve, b, a) if edge.Orientation() == TopAbs_REVERSED else (pcurve, a, b))
        loops.append(loop)
    return loops


def _chord_gaps(loop: list[tuple[object, float, float]]) -> list[tuple[np.ndarray, np.ndarray]]:
    """(end, next start) in parameter space between each pcurve of a loop and the next one."""
    ends = [(np.array(c.Value(a).Coord()), np.array(c.Value(b).Coord())) for c, a, b in loop]
    return [(ends[k][1], ends[(k + 1) % len(ends)][0]) for k in range(len(ends))]


def closure(face: TopoDS_Face, area: float) -> float:
    """What the chords closing the gaps of the face's boundary add to OCCT's integrals of its area.

    OCCT integrates ``F dv`` along the FORWARD face's pcurves, ``F(u, v)`` the area element integrated
    over u from the face's smallest u (``BRepTools::UVBounds``); on a closed boundary that is Green's
    theorem, on an open one the gaps are left out. Each chord from one pcurve's end to the next one's
    start adds its own ``F dv`` (composite Gauss-Legendre along it and for ``F``, the pieces doubled
    until the sum changes by less than ``AREA_EPS * area``). Gaps under ``OPEN * sqrt(area)`` in 3-D are
    skipped (their share of the area is under ``OPEN``). 0 where the wires cannot be walked or the
    surface fails to evaluate: OCCT's integrals are then taken as they are."""
    face = TopoDS.Face_s(face.Oriented(TopAbs_FORWARD))
    try:
        loops = _loops(face)
        if not loops:
            return 0.0
        surface = BRepAdaptor_Surface(face, False)
        tiny = OPEN * np.sqrt(area)
        chords = [(a, b) for loop in loops for a, b in _chord_gaps(loop)
                  if a[1] != b[1] and surface.Value(*a).Distance(surface.Value(*b)) > tiny]
        if not chords:
            return 0.0
        u_min = BRepTools.UVBounds_s(face)[0]
        previous = None
        for level in range(GREEN_LEVELS):
            total = sum(_chord_integral(surface, a, b, u_min, GREEN_PIECES << level) for a, b in chords)
            if previous is not None and abs(total - previous) <= AREA_EPS * area:
                break
            previous = total
    except OCCT_ERRORS:
        return 0.0
    return total


def _chord_integral(surface: BRepAdaptor_Surface, a: np.ndarray, b: np.ndarray, u_min: float,
                    pieces: int) -> float:
    """``F dv`` integrated along the chord from ``a`` to ``b`` (see :func:`closure`): one
    Gauss-Legendre rule along the short chord, ``pieces`` of them for ``F`` over the face's u range."""
    x, w = np.polynomial.legendre.leggauss(GREEN_POINTS)
    s = np.linspace(0.0, 1.0, pieces + 1)
    half = 0.5 * np.diff(s)
    frac = ((s[:-1] + half)[:, None] + half[:, None] * x).ravel()  # the composite rule on [0, 1]
    weights = (half[:, None] * w).ravel()
    uv = a + np.outer(0.5 * (x + 1.0), b - a)
    inner = np.empty((len(uv), len(frac), 2))
    inner[..., 0] = u_min + (uv[:, 0] - u_min)[:, None] * frac[None, :]
    inner[..., 1] = uv[:, 1][:, None]
    elements = _area_element(surface, inner.reshape(-1, 2)).reshape(len(uv), len(frac))
    f = (elements @ weights) * (uv[:, 0] - u_min)
    return 0.5 * float(f @ w) * float(b[1] - a[1])


def _area_element(surface: BRepAdaptor_Surface, uv: np.ndarray) -> np.ndarray:
    """``|S_u x S_v|`` at each (u, v) row (OCCT evaluates one point per call)."""
    p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
    out = np.empty(len(uv))
    for k, (u, v) in enumerate(uv):
        surface.D1(float(u), float(v), p, du, dv)
        out[k] = du.Crossed(dv).Magnitude()
    return out


def _slivers(face: TopoDS_Face, tri, loc: TopLoc_Location, surface: BRepAdaptor_Surface) -> float | None:
    """The area between the triangulation's boundary chords and the face's pcurves, each sliver's
    parameter-space area (signed: outside the chord adds, inside takes away) times the area element at
    its chord's midpoint; None where an edge has no boundary polygon with parameters."""
    x, w = np.polynomial.legendre.leggauss(SLIVER_POINTS)
    total = 0.0
    explorer = TopExp_Explorer(face, TopAbs_EDGE)
    while explorer.More():
        edge = TopoDS.Edge_s(explorer.Current())
        explorer.Next()
        if BRep_Tool.Degenerated_s(edge):
            continue
        poly = BRep_Tool.PolygonOnTriangulation_s(edge, tri, loc)
        if poly is None or not poly.HasParameters():
            return None
        params = poly.Parameters()
        t = np.array([params.Value(i) for i in range(params.Lower(), params.Upper() + 1)])
        pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
        half = 0.5 * np.diff(t)
        nodes = (0.5 * (t[:-1] + t[1:]))[:, None] + half[:, None] * x[None, :]
        ends = _pcurve_points(pcurve, t)[0]
        pts, ders = _pcurve_points(pcurve, nodes.ravel())
        rel = pts.reshape(len(half), SLIVER_POINTS, 2) - ends[:-1, None, :]
        ders = ders.reshape(len(half), SLIVER_POINTS, 2)
        # area swept from the chord's start along the arc, closed by the chord: positive when the arc
        # runs right of the chord, i.e. outside the face (the material is on the left of a FORWARD edge)
        swept = 0.5 * half * ((rel[..., 0] * ders[..., 1] - rel[..., 1] * ders[..., 0]) @ w)
        sliver = float(np.dot(swept, _area_element(surface, 0.5 * (ends[:-1] + ends[1:]))))
        total += -sliver if edge.Orientation() == TopAbs_REVERSED else sliver
    return total


def _pcurve_points(pcurve, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points and first derivatives of a 2-D curve at ``t``, shape (n, 2) each."""
    p, d = gp_Pnt2d(), gp_Vec2d()
    pts, ders = np.empty((len(t), 2)), np.empty((len(t), 2))
    for k, tk in enumerate(t):
        pcurve.D1(float(tk), p, d)
        pts[k] = p.X(), p.Y()
        ders[k] = d.X(), d.Y()
    return pts, ders
