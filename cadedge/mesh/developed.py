"""Inside the gmsh job: a cone face with its apex on its boundary, cut along its seam, laid flat, meshed
in the plane by gmsh and rolled back up.

gmsh meshes a face in its parameters, where a cone's apex is a whole line of them. On cones narrower than
about 20 degrees at the apex, gmsh 4.15 leaves triangles that overlap beside the seam near the apex, in
each of its algorithms and at any size (a cone of radius 1 and height 6, sizes 0.05 to 1), and every
strategy of :mod:`cadedge.mesh.generate` failed: a cone of radius 1 and height 40 took 175 s and was
reported as failed. A cone is developable: cut along a generator it unrolls without stretching into a
circular sector, its radius the slant length and its angle ``2 pi sin(a)`` (``a`` the half-angle). The
face's boundary nodes are laid out in that sector (the seam's nodes twice, on its two straight sides, the
apex once at its centre), the sector is meshed by gmsh as a plane face whose only boundary nodes are
those, sized as the cone face would be at the matching points of the cone, and its interior nodes are
rolled back onto the cone, where lengths and angles are those of the plane.

Near the apex, where the sector is narrower than the seam's segments, gmsh's triangles on those segments
either span the sector (wrapping round the axis) or are slivers beside them. There the mesh is made
here (:func:`_tip`): a fan of three triangles at the apex, then bands of six between rings of three
points at the seam's nodes, out to where the sector is :data:`TIP` segments wide; gmsh meshes the rest.
A 1 x 40 cone's sector at sizes 0.002-0.155 (118k triangles), in gmsh alone: MeshAdapt 53 s, 20 s with
the tip; Frontal-Delaunay 6 s with the tip, and without it triangles wrapped round the axis. MeshAdapt
is tried first all the same: a 1 x 20 cone at 1e-3 took 38k triangles with it, 56k with Frontal-Delaunay.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .flat import add_triangles, boundary_sizes, mesh_plane

#: A boundary point of the face this close to the cone's apex (a share of the cone's size) is its apex.
APEX_TOL = 1e-7
#: A node this close (radians) to the seam's generator lies on the seam.
SEAM_TOL = 1e-7
#: Sizes in the plane are at most the sector's width at their distance from the apex over this: each
#: triangle then turns about a quarter of the way round the axis, however narrow the cone (a triangle
#: across the whole sector, between the seam's two sides, would wrap round it; sizes clamped at
#: ``Mesh.MeshSizeMin`` left 3 triangles round a 1 x 40 cone near its apex). An eighth left slivers beside
#: the seam's segments near the apex (0.8 degrees on that cone at 1e-2, 1.97% of its triangles under 20
#: degrees; a quarter: 0.99%).
WRAP = 4
#: The apex's fan has this many triangles for a whole turn round the axis: the fewest that close round
#: it, whose angles at the apex (the sector's over 3) are the largest it allows.
FAN_TURN = 3
#: The apex's fan is carried out along the seam (:func:`_tip`) while the sector at the ring is narrower
#: than this many of the seam's next segments: on a 1 x 40 cone at 1e-3 (seam segments 0.027 near the
#: apex, the sector 0.157 radians wide) gmsh's Frontal-Delaunay joined the seam's two sides by triangles
#: spanning the sector out to 0.2 from the apex, where the sector is as wide as a segment; with 0.002
#: segments, 2 left triangles turning 136 degrees just beyond the rings.
TIP = 3.0
#: A cone whose half-angle's sine is under this (15 degrees) is meshed unrolled before gmsh tries it as
#: it is (:data:`cadedge.mesh.strategies.NARROW_CONE_ORDER`): gmsh's Frontal-Delaunay hung for 60 s on a
#: 1 x 40 cone at 1e-3 (1.4 degrees) before the unrolled strategies had their turn, and it fails on a
#: 1 x 6 one (9.5 degrees); it meshes a 1 x 3 one (18.4 degrees) well.
NARROW = float(np.sin(np.radians(15.0)))
#: A rolled-up triangle whose nodes spread round the axis by more than this (radians) is refused.
MOST_TURN = 0.75 * np.pi


@dataclass(frozen=True)
class Cone:
    """A cone by its ``apex``, unit ``axis`` (from the apex into the cone), unit ``e1`` (towards the
    seam) and ``e2`` (the way its first parameter turns), and its half-angle's sine and cosine."""

    apex: np.ndarray
    axis: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    sin: float
    cos: float

    def unroll(self, xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points (k, 3) on the cone as (distance from the apex, angle round the axis from the seam in
        [0, 2 pi))."""
        w = np.asarray(xyz, dtype=float) - self.apex
        rho = np.linalg.norm(w, axis=1)
        phi = np.mod(np.arctan2(w @ self.e2, w @ self.e1), 2.0 * np.pi)
        return rho, phi

    def roll_up(self, rho: np.ndarray, phi: np.ndarray) -> np.ndarray:
        """The cone's points (k, 3) at distances ``rho`` from the apex and angles ``phi`` round the axis."""
        radial = np.cos(phi)[:, None] * self.e1 + np.sin(phi)[:, None] * self.e2
        return self.apex + rho[:, None] * (self.cos * self.axis + self.sin * radial)


def _circle(p: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre and radius of the circle through three points (3, 3)."""
    a, b = p[1] - p[0], p[2] - p[0]
    n = np.cross(a, b)
    centre = p[0] + np.cross(np.dot(a, a) * b - np.dot(b, b) * a, n) / (2.0 * np.dot(n, n))
    return centre, float(np.linalg.norm(p[0] - centre))


def cone_of(surface: int) -> Cone | None:
    """The cone of gmsh surface ``surface`` if it is a cone (gmsh's type) with its apex at one of the face's
    boundary points; else None."""
    import gmsh

    if gmsh.model.getType(2, surface) != "Cone":
        return None
    lo, hi = (np.asarray(b, dtype=float) for b in gmsh.model.getParametrizationBounds(2, surface))
    u = lo[0] + (hi[0] - lo[0]) * np.array([0.0, 0.25, 0.5])
    rings = []
    for v in lo[1] + (hi[1] - lo[1]) * np.array([0.25, 0.75]):
        p = np.asarray(gmsh.model.getValue(2, surface, np.column_stack([u, np.full(3, v)]).ravel().tolist()),
                       dtype=float).reshape(3, 3)
        rings.append((*_circle(p), p))
    (c0, r0, p0), (c1, r1, _) = rings
    step = float(np.linalg.norm(c1 - c0))
    if not (np.isfinite(r0) and np.isfinite(r1)) or abs(r1 - r0) <= 1e-9 * max(r0, r1, step) or step == 0.0:
        return None
    apex = c0 + (c1 - c0) * r0 / (r0 - r1)
    axis = (c1 - c0) / step * np.sign(r1 - r0)
    slant = float(np.hypot(step, r1 - r0))
    e1 = (p0[0] - c0) / r0
    e2 = np.cross(axis, e1)
    if np.dot(p0[1] - c0, e2) < 0:  # the first parameter turns the other way
        e2 = -e2
    size = float(np.linalg.norm(p0[0] - apex)) + slant
    points = [t for _, t in gmsh.model.getBoundary([(2, surface)], combined=False, recursive=True)]
    at_apex = [np.linalg.norm(np.asarray(gmsh.model.getValue(0, abs(t), []), dtype=float) - apex)
               <= APEX_TOL * size for t in points]
    if not any(at_apex):
        return None
    return Cone(apex, axis, e1, e2, abs(r1 - r0) / slant, step / slant)


def mesh_unrolled(surface: int, cone: Cone, algorithm: int) -> str | None:
    """Mesh (empty) gmsh surface ``surface`` on ``cone`` unrolled (see the module doc) with gmsh's 2-D
    ``algorithm``, at the sizes gmsh's options and the face's sampled sizes give it now (:func:`_sizes`);
    None if it passed, else why not (the surface is then left empty)."""
    import gmsh

    from .gmsh_model import surface_curve_uses

    segments, keys = [], {}  # plane points: (node tag, copy on the far side of the seam?) -> (rho, psi)
    for curve, uses in surface_curve_uses(surface).items():
        tags, coords, _ = gmsh.model.mesh.getNodes(1, curve, includeBoundary=True)
        at = {t: i for i, t in enumerate(np.asarray(tags, dtype=np.int64).tolist())}
        curve_rho, curve_phi = cone.unroll(np.asarray(coords, dtype=float).reshape(-1, 3))  # once per curve
        _, seg = gmsh.model.mesh.getElementsByType(1, curve)
        for a, b in np.asarray(seg, dtype=np.int64).reshape(-1, 2).tolist():
            rho, phi = curve_rho[[at[a], at[b]]], curve_phi[[at[a], at[b]]]
            apex = rho <= APEX_TOL * max(rho.max(), 1e-300)
            seam = ~apex & ((phi < SEAM_TOL) | (phi > 2.0 * np.pi - SEAM_TOL))
            if uses == 2 and not seam.all() and not (seam | apex).all():
                return "its seam's nodes do not lie on the cone's seam"
            sides = (False, True) if uses == 2 else (None,)
            for far in sides:
                ends = []
                for k, node in enumerate((a, b)):
                    if apex[k]:
                        key, angle = (node, False), 0.0
                    elif seam[k]:
                        other = phi[1 - k] if not (seam[1 - k] or apex[1 - k]) else None
                        side = far if far is not None else bool(other is not None and other > np.pi)
                        key, angle = (node, side), 2.0 * np.pi if side else 0.0
                    else:
                        key, angle = (node, False), float(phi[k])
                    keys[key] = (float(rho[k]), angle * cone.sin)
                    ends.append(key)
                if ends[0] != ends[1]:  # a segment of the apex's degenerate edge has no length
                    segments.append(tuple(ends))
    tol = APEX_TOL * max(k[0] for k in keys.values())
    apex = [key for key, (r, _) in keys.items() if r <= tol]
    if len(apex) != 1:
        return "its apex is not one node"
    sector = 2.0 * np.pi * cone.sin
    fan, segments = _tip(keys, segments, apex[0], sector, cone)
    if fan is None:
        return "its apex does not join two boundary segments"
    order = list(keys)
    index = {key: i for i, key in enumerate(order)}
    rows = [(index[a], index[b]) for a, b in segments]
    rho = np.array([keys[k][0] for k in order])
    psi = np.array([keys[k][1] for k in order])
    plane = np.column_stack([rho * np.cos(psi), rho * np.sin(psi)])
    near = np.minimum(boundary_sizes(plane, rows), rho * sector / WRAP)
    sizes = _sizes(surface, cone, sector)
    got = mesh_plane(plane, rows, near, algorithm, lambda: _size_field(*sizes),
                     {"Mesh.MeshSizeMin": 0.0})  # the field's floor, but near the apex
    if isinstance(got, str):
        return got
    xy, tri = got
    inner = xy[len(order):]
    rho = np.concatenate([rho, np.hypot(inner[:, 0], inner[:, 1])])
    psi = np.concatenate([psi, np.mod(np.arctan2(inner[:, 1], inner[:, 0]), 2.0 * np.pi)])
    fans = np.array([[index[k] for k in f] for f in fan], dtype=np.int64)
    xy = np.column_stack([rho * np.cos(psi), rho * np.sin(psi)])
    p = xy[np.vstack([tri[:1], fans])]
    u, v = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    turn = np.sign(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    flip = turn[1:] != turn[0]  # the fan turns as gmsh's triangles do
    fans[flip] = fans[flip][:, [0, 2, 1]]
    tri = np.vstack([tri, fans])
    phi = np.where(rho > tol, psi / cone.sin, np.nan)[tri]
    if np.nanmax(np.nanmax(phi, axis=1) - np.nanmin(phi, axis=1)) > MOST_TURN:
        return "unrolled: a triangle wraps round the cone's axis"
    tags = np.array([k[0] if isinstance(k[0], int) and k[0] > 0 else -1 for k in order]
                    + [-1] * len(inner), dtype=np.int64)  # the face's own nodes keep their tags
    add_triangles(surface, tags, cone.roll_up(rho, psi / cone.sin), tri)
    return None


def _sizes(surface: int, cone: Cone, sector: float) -> tuple[float, float, float, float]:
    """The cone face's size at a distance ``r`` from the apex (in the plane as on the cone), as gmsh would
    size the face now, is ``min(max(min(c r, b sqrt(r)), floor), w r)``; returns (c, b, floor, w), ``c``
    ``inf`` and ``b`` 0 where unused. gmsh's curvature size is ``2 pi / (N k)`` with ``k = 1 / (r tan a)``;
    the face's sampled sizes (:mod:`cadedge.mesh.interior`) are ``alpha / sqrt(k)``; the floor is
    ``Mesh.MeshSizeMin`` or the face's size floor; ``w r`` is the sector's width at ``r`` over
    :data:`WRAP`."""
    import gmsh

    from .interior import SIZES

    tan = cone.sin / max(cone.cos, 1e-300)
    per_circle = gmsh.option.getNumber("Mesh.MeshSizeFromCurvature")
    curvature = 2.0 * np.pi * tan / per_circle if per_circle > 0 else np.inf
    root = 0.0
    face = SIZES.faces.get(surface)
    if face is not None and face.sizes is not None and len(face.sizes):
        root = float(np.median(face.sizes * np.sqrt(face.k))) * np.sqrt(tan)
    floor = max(gmsh.option.getNumber("Mesh.MeshSizeMin"), SIZES.floors.get(surface, 0.0))
    return float(curvature), float(root), float(floor), float(sector / WRAP)


def _size_field(curvature: float, root: float, floor: float, wrap: float) -> None:
    """:func:`_sizes`' sizes as the background field of the current (plane) model."""
    import gmsh

    field = gmsh.model.mesh.field

    def formula(text: str) -> int:
        tag = field.add("MathEval")
        field.setString(tag, "F", text)
        return tag

    r = "Sqrt(x*x+y*y)"
    terms = ([formula(f"{float(curvature):.17g}*{r}")] if np.isfinite(curvature) else []) + (
        [formula(f"{float(root):.17g}*Sqrt({r})")] if root > 0 else [])
    if terms:
        low = field.add("Min")
        field.setNumbers(low, "FieldsList", terms)
        high = field.add("Max")
        field.setNumbers(high, "FieldsList", [low, formula(f"{float(floor):.17g}")])
        terms = [high]
    final = field.add("Min")
    field.setNumbers(final, "FieldsList", terms + [formula(f"{float(wrap):.17g}*{r}")])
    field.setAsBackgroundMesh(final)


def _fan(keys: dict, segments: list, apex, sector: float) -> tuple[list | None, list]:
    """The apex's two boundary segments replaced by a polyline of new points (added to ``keys``) between
    their other ends, :data:`FAN_TURN` segments for the ``sector``'s whole angle (at least 3), and the
    triangles (key triples) that fan from the apex to it; (None, segments) if the apex does not join
    exactly two segments. A cone's apex closes round in at least three triangles (two would lie on each
    other), each turning a share of the way round, so they are made here: gmsh's isotropic triangles
    spanned the whole sector of a narrow cone between the seam's two sides."""
    ends = [(a if b == apex else b) for a, b in segments if apex in (a, b)]
    if len(ends) != 2:
        return None, segments
    ring = _ring(keys, *ends, max(3, int(np.ceil(FAN_TURN * abs(keys[ends[1]][1] - keys[ends[0]][1]) / sector))))
    kept = [seg for seg in segments if apex not in seg]
    return [(apex, ring[j], ring[j + 1]) for j in range(len(ring) - 1)], kept + list(zip(ring[:-1], ring[1:]))


def _ring(keys: dict, first, last, k: int) -> list:
    """``k`` segments from plane point ``first`` to ``last`` (keys of ``keys``), their new points (added to
    ``keys``) evenly between them in distance from the apex and in angle."""
    (r0, a0), (r1, a1) = keys[first], keys[last]
    ring = [first]
    for j in range(1, k):
        key = (-(len(keys) + 1), False)  # a new node: negative, unlike gmsh's tags
        keys[key] = (r0 + (r1 - r0) * j / k, a0 + (a1 - a0) * j / k)
        ring.append(key)
    return ring + [last]


def _tip(keys: dict, segments: list, apex, sector: float, cone: Cone) -> tuple[list | None, list]:
    """:func:`_fan`, then carried out along the seam: while the sector at the ring is narrower than
    :data:`TIP` of the seam's next segments (gmsh's triangles on such a segment either span the sector,
    wrapping round the axis, or are slivers beside it), the ring's two ends step out to the seam's next
    node and a ring as many points round joins them; the band between the two rings is filled with two
    triangles per step round, split along the diagonal that gives them the larger smallest angle on the
    cone. Stops before the seam's last segment and before any other boundary point comes as near the apex
    as one segment beyond the ring. Returns the triangles and the boundary segments left for gmsh."""
    from .quality import triangle_angles

    fan, segments = _fan(keys, segments, apex, sector)
    if fan is None:
        return None, segments
    ring = [fan[0][1]] + [f[2] for f in fan]
    if ring[0][0] != ring[-1][0]:  # not the seam's two copies of one node: the apex's fan only
        return fan, segments
    tri = list(fan)
    seam = {key[0] for key in keys if key[1] is True}
    nearest = min((r for key, (r, _) in keys.items() if key[0] not in seam and key != apex and key[0] > 0),
                  default=np.inf)  # the nearest boundary point off the seam
    while True:
        around = {}
        for seg in segments:
            for x, y in (seg, seg[::-1]):
                around.setdefault(x, []).append(y)
        step = [[n for n in around[end] if n != inner] for end, inner in ((ring[0], ring[1]), (ring[-1], ring[-2]))]
        if any(len(nx) != 1 for nx in step):
            return tri, segments
        a, b = step[0][0], step[1][0]
        beyond = [[n for n in around.get(x, []) if n != y] for x, y in ((a, ring[0]), (b, ring[-1]))]
        rho, gap = keys[ring[0]][0], keys[a][0] - keys[ring[0]][0]
        if (a[0] != b[0] or any(len(n) != 1 for n in beyond) or beyond[0][0][0] != beyond[1][0][0]
                or not gap > 0 or rho * sector >= TIP * gap or keys[a][0] + gap >= nearest):
            return tri, segments
        out = _ring(keys, a, b, len(ring) - 1)
        for j in range(len(ring) - 1):
            options = [((ring[j], ring[j + 1], out[j + 1]), (ring[j], out[j + 1], out[j])),
                       ((ring[j], ring[j + 1], out[j]), (ring[j + 1], out[j + 1], out[j]))]
            corners = [keys[k] for option in options for t in option for k in t]
            pts = cone.roll_up(np.array([r for r, _ in corners]), np.array([q for _, q in corners]) / cone.sin)
            worst = triangle_angles(pts, np.arange(12).reshape(-1, 3)).min(axis=1).reshape(2, 2).min(axis=1)
            tri.extend(options[int(np.argmax(worst))])
        old = set(zip(ring[:-1], ring[1:])) | {(ring[0], a), (a, ring[0]), (ring[-1], b), (b, ring[-1])}
        segments = [seg for seg in segments if seg not in old] + list(zip(out[:-1], out[1:]))
        ring = out
