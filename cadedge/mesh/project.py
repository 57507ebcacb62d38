"""Projection of moved mesh nodes back onto their gmsh surface, started from each node's parameters.

Used by the face optimiser (:mod:`cadedge.mesh.optimize`, :mod:`cadedge.mesh.collapse`) inside the gmsh
child process.
"""

from __future__ import annotations

import numpy as np

#: Gauss-Newton steps of a projection started from the node's own parameters, and the tolerance (a share
#: of the face's bounding-box diagonal) under which its tangential residual counts as converged.
NEWTON_STEPS = 6
NEWTON_TOL = 1e-9


class Projector:
    """Moves points onto one gmsh surface, each from the parameters of the node it belongs to.

    ``gmsh.model.getClosestPoint`` searches the whole surface (OCCT's projection has no start): on B-spline
    faces it took nearly all the optimiser's time. A moved node lies a fraction of an edge from where it
    was, so a few Gauss-Newton steps on the parametrisation (``getValue`` and ``getDerivative``, batched)
    from its own ``(u, v)`` find the same foot point. A point whose start is unknown, whose steps leave
    the parametric bounds (a seam or the face's edge), hit a pole (singular derivatives) or do not
    converge goes to ``getClosestPoint`` instead. ``uv`` (node row -> parameters, NaN where unknown) is
    read at each call; :attr:`searched` counts the points given to ``getClosestPoint``.

    Planes and cylinders (gmsh types "Plane" and "Cylinder", as OCCT parametrises them) are projected in
    closed form, without gmsh, their normals too: on an assembly of 18 solids, mostly planes and
    cylinders (as1_pe_203 of the pythonocc-demos at 1e-2), gmsh's evaluations for the Gauss-Newton steps
    and the normals took a third of the optimiser's 30 s, in 38 000 calls."""

    def __init__(self, surface: int, uv: np.ndarray | None = None):
        import gmsh

        self.surface = surface
        self.uv = uv
        lo, hi = gmsh.model.getParametrizationBounds(2, surface)
        self.lo, self.hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        box = np.asarray(gmsh.model.getBoundingBox(2, surface), dtype=float)
        self.size = max(float(np.linalg.norm(box[3:] - box[:3])), 1e-300)
        self.searched = 0
        self.walked = 0
        kind = gmsh.model.getType(2, surface)
        self.plane = _plane(surface, self.lo, self.hi) if kind == "Plane" else None
        self.cylinder = _cylinder(surface, self.lo, self.hi) if kind == "Cylinder" else None

    def _search(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        import gmsh

        self.searched += len(points)
        coords, uv = gmsh.model.getClosestPoint(2, self.surface, points.ravel().tolist())
        return np.asarray(coords, dtype=float).reshape(-1, 3), np.asarray(uv, dtype=float).reshape(len(points), -1)

    def _walk(self, points: np.ndarray, start: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Gauss-Newton from ``start``: the foot points, their parameters and which converged (tangential
        residual under :data:`NEWTON_TOL` of the face's size within :data:`NEWTON_STEPS` steps, inside
        the parametric bounds, derivatives not singular)."""
        import gmsh

        uv = start.copy()
        span = self.hi - self.lo
        live = np.ones(len(points), dtype=bool)  # neither failed nor converged yet
        done = np.zeros(len(points), dtype=bool)
        foot = np.zeros_like(points)
        for step in range(NEWTON_STEPS + 1):
            k = np.flatnonzero(live)
            if not len(k):
                break
            q = uv[k].ravel().tolist()
            foot[k] = np.asarray(gmsh.model.getValue(2, self.surface, q), dtype=float).reshape(-1, 3)
            d = np.asarray(gmsh.model.getDerivative(2, self.surface, q), dtype=float).reshape(-1, 2, 3)
            g = np.einsum("nij,nj->ni", d, points[k] - foot[k])
            conv = np.all(np.abs(g) <= NEWTON_TOL * self.size * np.linalg.norm(d, axis=2), axis=1)
            done[k[conv]] = True
            live[k[conv]] = False
            if step == NEWTON_STEPS:
                break
            k, d, g = k[~conv], d[~conv], g[~conv]
            a = np.einsum("nij,nkj->nik", d, d)
            det = a[:, 0, 0] * a[:, 1, 1] - a[:, 0, 1] * a[:, 1, 0]
            sing = det <= 1e-12 * np.maximum(a[:, 0, 0] * a[:, 1, 1], 1e-300)
            safe = np.where(sing, 1.0, det)
            new = uv[k] + np.column_stack([a[:, 1, 1] * g[:, 0] - a[:, 0, 1] * g[:, 1],
                                           a[:, 0, 0] * g[:, 1] - a[:, 1, 0] * g[:, 0]]) / safe[:, None]
            out = sing | ~np.all((new >= self.lo - 1e-9 * span) & (new <= self.hi + 1e-9 * span), axis=1)
            live[k[out]] = False
            uv[k[~out]] = new[~out]
        return foot, uv, done

    def _onto_cylinder(self, points: np.ndarray, rows: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """Points onto the cylinder in closed form: the angle nearest the node's own, brought within the
        bounds (a node pushed across the seam gets the seam's other side)."""
        origin, radial, axis, radius, _ = self.cylinder
        d = points - origin
        v = d @ axis
        u = np.arctan2(d @ radial[1], d @ radial[0])
        start = np.full(len(points), np.nan)
        if rows is not None and self.uv is not None and len(points):
            start = self.uv[np.asarray(rows), 0]
        near = np.where(np.isnan(start), self.lo[0] + np.pi, start)  # the turn to land in
        u = u + 2.0 * np.pi * np.round((near - u) / (2.0 * np.pi))
        inside = self.lo[0] + np.mod(u - self.lo[0], 2.0 * np.pi)  # past the seam: its other side, as gmsh's
        u = np.where((u < self.lo[0]) | (u > self.hi[0]), inside, u)  # projection gives it
        self.walked += len(points)
        foot = origin + radius * (np.cos(u)[:, None] * radial[0] + np.sin(u)[:, None] * radial[1]) + v[:, None] * axis
        return foot, np.column_stack([u, v])

    def normals(self, params: np.ndarray) -> np.ndarray:
        """Unit surface normals (k, 3) at parameters ``params`` (k, 2); zero rows where there is none."""
        from .folds import normals_at

        if self.plane is not None or self.cylinder is not None:
            params = np.asarray(params, dtype=float).reshape(-1, 2)
            if self.plane is not None:
                out = np.broadcast_to(self.plane[3], (len(params), 3))
            else:
                _, radial, _, _, sign = self.cylinder
                out = sign * (np.cos(params[:, :1]) * radial[0] + np.sin(params[:, :1]) * radial[1])
            return np.where(np.isnan(params).any(axis=1)[:, None], 0.0, out)
        return normals_at(self.surface, params)

    def __call__(self, points: np.ndarray, rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The points (k, 3) moved onto the surface and their parameters (k, 2); ``rows``: the node row
        each point belongs to (its parameters start the search)."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        if self.plane is not None:
            origin, axes, inverse, _ = self.plane
            par = (points - origin) @ inverse
            self.walked += len(points)
            return origin + par @ axes, par
        if self.cylinder is not None:
            return self._onto_cylinder(points, rows)
        out = np.empty_like(points)
        par = np.full((len(points), 2), np.nan)
        todo = np.ones(len(points), dtype=bool)
        if rows is not None and self.uv is not None and len(points):
            start = self.uv[np.asarray(rows)]
            known = ~np.isnan(start).any(axis=1)
            if known.any():
                s, uv, ok = self._walk(points[known], start[known])
                idx = np.flatnonzero(known)[ok]
                out[idx], par[idx] = s[ok], uv[ok]
                todo[idx] = False
                self.walked += len(idx)
        if todo.any():
            out[todo], par[todo] = self._search(points[todo])
        return out, par


def _plane(surface: int, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, ...] | None:
    """A planar gmsh surface's ``origin`` (the point at parameters 0, 0), ``axes`` (2, 3: the derivatives
    along u and v), the (3, 2) matrix taking a point's offset from the origin to its parameters, and its
    unit normal as gmsh orients it; None if the parametrisation is not affine after all (checked at the
    middle of the bounds) or degenerate."""
    import gmsh

    mid = 0.5 * (lo + hi)
    probe = [0.0, 0.0, *mid.tolist()]
    values = np.asarray(gmsh.model.getValue(2, surface, probe), dtype=float).reshape(2, 3)
    axes = np.asarray(gmsh.model.getDerivative(2, surface, probe), dtype=float).reshape(2, 2, 3)
    normal = np.asarray(gmsh.model.getNormal(surface, mid.tolist()), dtype=float)
    origin, du, dv = values[0], axes[0, 0], axes[0, 1]
    gram = np.array([[du @ du, du @ dv], [du @ dv, dv @ dv]])
    if not np.all(np.isfinite(gram)) or np.linalg.det(gram) <= 1e-12 * gram[0, 0] * gram[1, 1]:
        return None
    scale = max(float(np.linalg.norm(values[1] - origin)), float(np.linalg.norm(du) + np.linalg.norm(dv)), 1e-300)
    if (np.abs(axes[1] - axes[0]).max() > 1e-9 * (np.linalg.norm(du) + np.linalg.norm(dv))
            or np.linalg.norm(origin + mid @ axes[0] - values[1]) > 1e-9 * scale
            or not abs(np.linalg.norm(normal) - 1.0) < 1e-6):
        return None
    return origin, axes[0], axes[0].T @ np.linalg.inv(gram), normal


def _cylinder(surface: int, lo: np.ndarray, hi: np.ndarray) -> tuple | None:
    """A cylindrical gmsh surface as OCCT parametrises it, ``origin + r (cos u x + sin u y) + v z``: its
    ``origin``, ``radial`` (2, 3: ``x`` and ``y``), ``axis`` ``z``, radius ``r`` and the sign of gmsh's
    normal against ``cos u x + sin u y``; None if gmsh's points differ from that (checked at three
    points inside the bounds) or it is degenerate."""
    import gmsh

    probe = np.array([[0.0, 0.0], [0.5 * np.pi, 0.0]])
    values = np.asarray(gmsh.model.getValue(2, surface, probe.ravel().tolist()), dtype=float).reshape(2, 3)
    du, dv = np.asarray(gmsh.model.getDerivative(2, surface, [0.0, 0.0]), dtype=float).reshape(2, 3)
    radius = float(np.linalg.norm(du))
    if not (np.isfinite(radius) and radius > 0 and abs(np.linalg.norm(dv) - 1.0) < 1e-9):
        return None
    y = du / radius
    origin = values[1] - radius * y
    x = (values[0] - origin) / radius
    check = lo + (hi - lo) * np.array([[0.3, 0.2], [0.55, 0.8], [0.9, 0.5]])
    got = np.asarray(gmsh.model.getValue(2, surface, check.ravel().tolist()), dtype=float).reshape(-1, 3)
    u, v = check[:, :1], check[:, 1:]
    want = origin + radius * (np.cos(u) * x + np.sin(u) * y) + v * dv
    scale = radius + float(np.abs(check[:, 1]).max()) + float(np.linalg.norm(origin))
    if np.abs(got - want).max() > 1e-9 * scale or abs(x @ y) > 1e-9 or abs(x @ dv) > 1e-9 or abs(y @ dv) > 1e-9:
        return None
    normal = np.asarray(gmsh.model.getNormal(surface, check[0].tolist()), dtype=float)
    sign = 1.0 if normal @ (np.cos(u[0, 0]) * x + np.sin(u[0, 0]) * y) >= 0 else -1.0
    return origin, np.array([x, y]), dv, radius, sign
