"""Folded triangles: triangles that face against the B-rep surface they mesh.

A folded triangle overlaps its neighbours: the mesh is no longer a surface a solver can use, and its
area counts twice, so a face's area deficit looks smaller than it is. The face optimiser's moves checked
each step only against the triangles' normals just before it, and small turns added up: on the thin
blades' rounded edges (twisted_blade and sharp_blade at 1e-2) edge swaps and the local search folded
1 to 3 triangles per model, and twisted_blade's blade face read 8.4e-3 where, unfolded, it is 1.03e-2.
The moves now refuse a fold and the optimiser undoes gmsh's on faces where folds are few
(:mod:`cadedge.mesh.moves`, :data:`cadedge.mesh.optimize.FOLD_TRUST`), the surface target measures
faces once unfolded (:func:`cadedge.mesh.areas.unfolded_areas`), and every face's folds are counted
after meshing (:func:`count_folded`, in the report).

A triangle is folded when its normal points against the sum of the surface's unit normals at its three
nodes. Where those disagree (a triangle across a rounded edge thinner than itself: the surface turns
nearly 180 degrees within it) its direction is not judged.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..kernels import tri_normals

#: A triangle's reference direction (the sum of its nodes' unit surface normals) is trusted only when it
#: is at least this long, the nodes' normals agreeing to within about 80 degrees.
AGREE = 1.5


def _normals(x: np.ndarray, tri: np.ndarray) -> np.ndarray:
    return tri_normals(x, tri)


def orientation(up: np.ndarray, tri: np.ndarray, x: np.ndarray) -> float:
    """+1 or -1: the sign that makes most of the face's triangle area agree with its nodes' unit surface
    normals ``up`` (a mesher orients a face's triangles one way, not necessarily the parametrisation's)."""
    return -1.0 if np.einsum("ij,ij->", _normals(x, tri), up[tri].sum(axis=1)) < 0 else 1.0


def reference_normals(up: np.ndarray, tri: np.ndarray, sign: float = 1.0) -> np.ndarray:
    """Each triangle's reference direction (m, 3): ``sign`` times the sum of its nodes' unit surface
    normals ``up`` (zero rows where unknown), zero where they disagree (see :data:`AGREE`)."""
    p = up[tri]
    ref = p[:, 0] + p[:, 1] + p[:, 2]
    if sign != 1.0:
        ref *= sign
    ref[np.einsum("ij,ij->i", ref, ref) < AGREE * AGREE] = 0.0
    return ref


def folded(x: np.ndarray, tri: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Which triangles face against their reference direction ``ref`` (:func:`reference_normals`)."""
    return np.einsum("ij,ij->i", _normals(x, tri), ref) < 0


@dataclass
class NodeNormals:
    """The oriented unit surface normals ``up`` (n, 3; zero rows where unknown) at a face's nodes, and
    ``at(params)``: those at surface parameters (k, 2), oriented alike. A move is judged against the
    normals at its nodes' new positions: a node moved across a ridge turns its normal, and a triangle
    across the ridge, not judged before the move (its nodes' normals disagreeing), may be judged and
    folded after it (the propeller at 1e-3: one triangle of a blade face, left folded)."""

    up: np.ndarray
    at: Callable[[np.ndarray], np.ndarray]

    def moved(self, rows: np.ndarray, params: np.ndarray) -> np.ndarray:
        """``up`` with the nodes ``rows`` at parameters ``params`` (a new array)."""
        out = self.up.copy()
        if len(rows):
            out[rows] = self.at(params)
        return out


def surface_normals(surface: int, x: np.ndarray, uv: np.ndarray, tags: np.ndarray | None = None) -> np.ndarray:
    """Unit normals (n, 3) of gmsh surface ``surface`` at nodes ``x``, from their parameters ``uv`` (NaN
    rows: the curves' nodes, see :func:`node_params`); zero rows where unknown (a pole). Inside the gmsh
    process."""
    return normals_at(surface, node_params(surface, x, uv, tags))


def normals_at(surface: int, params: np.ndarray) -> np.ndarray:
    """Unit normals (k, 3) of gmsh surface ``surface`` at parameters ``params`` (k, 2); zero rows where
    a row is NaN or there is no normal (a pole). Inside the gmsh process."""
    import gmsh

    params = np.asarray(params, dtype=float).reshape(-1, 2)
    out = np.zeros((len(params), 3))
    ok = ~np.isnan(params).any(axis=1)
    if ok.any():
        out[ok] = unit_normals(gmsh.model.getNormal(surface, params[ok].ravel().tolist()))
    return out


def node_params(surface: int, x: np.ndarray, uv: np.ndarray, tags: np.ndarray | None = None) -> np.ndarray:
    """The parameters (n, 2) on gmsh surface ``surface`` of nodes ``x``: ``uv`` where known, the rest (NaN
    rows: the curves' nodes) found here; NaN where gmsh finds none. Inside the gmsh process.

    A curve's node (``tags``: the nodes' gmsh tags) gets its surface parameters from its curve parameter
    through the curve's trace on the surface (``reparametrizeOnSurface``); the rest, the points' nodes,
    by projection (``getParametrization``, about 0.5 ms a node: for every curve node it took 29 s of the
    M6 screw's meshing at 1e-3)."""
    import gmsh

    uv = np.array(uv, dtype=float)
    edge = np.isnan(uv).any(axis=1)
    if edge.any() and tags is not None:
        from .gmsh_model import surface_curve_uses
        from .readback import node_lookup

        lookup = node_lookup(np.asarray(tags, dtype=np.int64))
        for curve in surface_curve_uses(surface):
            ctags, _, cpar = gmsh.model.mesh.getNodes(1, curve, includeBoundary=False, returnParametricCoord=True)
            ctags = np.asarray(ctags, dtype=np.int64)
            if not len(ctags) or len(cpar) != len(ctags):
                continue
            known = ctags < len(lookup)
            rows = np.where(known, lookup[np.minimum(ctags, len(lookup) - 1)], -1)
            keep = rows >= 0
            if not keep.any():
                continue
            try:
                got = np.asarray(gmsh.model.reparametrizeOnSurface(1, curve, np.asarray(cpar)[keep].tolist(), surface),
                                 dtype=float)
            except Exception:  # gmsh's bare Exception: a curve it cannot trace on the surface
                continue
            if got.size == 2 * keep.sum():
                uv[rows[keep]] = got.reshape(-1, 2)
        edge = np.isnan(uv).any(axis=1)
    if edge.any():
        got = np.asarray(gmsh.model.getParametrization(2, surface, x[edge].ravel().tolist()), dtype=float)
        uv[edge] = got.reshape(-1, 2) if got.size == 2 * edge.sum() else np.nan
    return uv


def unit_normals(normals) -> np.ndarray:
    """Rows of ``normals`` (a flat list of 3-vectors, as gmsh gives them) as unit rows, zero where not
    finite or of no length (a pole)."""
    nn = np.nan_to_num(np.asarray(normals, dtype=float).reshape(-1, 3), nan=0.0, posinf=0.0, neginf=0.0)
    length = np.linalg.norm(nn, axis=1)
    return np.where(length[:, None] > 0.5, nn / np.maximum(length, 1e-300)[:, None], 0.0)


def count_folded(surface: int) -> int:
    """How many triangles of meshed gmsh surface ``surface`` are folded. Inside the gmsh process."""
    from .facemesh import read_face

    mesh = read_face(surface)
    if mesh is None:
        return 0
    up = surface_normals(surface, mesh.x, mesh.uv, mesh.tags)
    up[mesh.pinned] = 0.0  # on a fold: its normal belongs to neither flank
    ref = reference_normals(up, mesh.tri, orientation(up, mesh.tri, mesh.x))
    return int(folded(mesh.x, mesh.tri, ref).sum())
