"""One meshed gmsh surface as plain arrays, read from and written back to the gmsh model.

The face optimiser (:mod:`cadedge.mesh.optimize`) works on a face's triangles as numpy arrays and hands
the result back to gmsh; the surface target (:mod:`cadedge.mesh.fidelity`) keeps a face's mesh aside
while it tries another and puts it back if that one is worse. Only the face's interior nodes and its
triangles are ever rewritten, its curves' nodes stay, so neighbours stay conforming.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class FaceMesh:
    """A face's mesh as gmsh holds it: node tags and coordinates (boundary nodes included), triangles as
    rows of them, which nodes are interior (may move), the interior nodes' parameters (NaN rows for the
    others), the triangles' element tags, the curve segments as sorted pairs of node rows (and the edges
    along folds, :func:`crease_nodes`), and the interior nodes pinned on those folds (not movable)."""

    tags: np.ndarray
    x: np.ndarray
    tri: np.ndarray
    movable: np.ndarray
    uv: np.ndarray
    el_tags: np.ndarray
    fixed: set[tuple[int, int]]
    pinned: np.ndarray


def read_face(surface: int) -> FaceMesh | None:
    """The mesh of gmsh surface ``surface``; None if it has no triangles or they name nodes it does not
    hold."""
    import gmsh

    from .readback import node_lookup
    from .gmsh_model import surface_curve_uses

    el_tags, tri_tags = gmsh.model.mesh.getElementsByType(2, surface)
    if not len(tri_tags):
        return None
    tags, coords, _ = gmsh.model.mesh.getNodes(2, surface, includeBoundary=True)
    # a seam's nodes come twice (its curve bounds the face on both sides): each node once, or the copies
    # no triangle uses are projected on the surface for their parameters (2 ms a node on a B-spline face)
    tags = np.asarray(tags, dtype=np.int64)
    once = np.sort(np.unique(tags, return_index=True)[1])
    tags, coords = tags[once], np.asarray(coords, dtype=float).reshape(-1, 3)[once]
    lookup = node_lookup(tags)
    tri_tags = np.asarray(tri_tags, dtype=np.int64)
    if tri_tags.max() >= len(lookup) or (lookup[tri_tags] < 0).any():
        return None
    fixed: set[tuple[int, int]] = set()
    for curve in surface_curve_uses(surface):
        seg = np.asarray(gmsh.model.mesh.getElementsByType(1, curve)[1], dtype=np.int64).reshape(-1, 2)
        seg = lookup[seg[(seg < len(lookup)).all(axis=1)]]
        fixed.update((int(min(p, q)), int(max(p, q))) for p, q in seg if p >= 0 and q >= 0)
    inner_tags, _, inner_uv = gmsh.model.mesh.getNodes(2, surface, includeBoundary=False,
                                                       returnParametricCoord=True)
    inner = np.asarray(inner_tags, dtype=np.int64)
    movable = np.zeros(len(tags), dtype=bool)
    movable[lookup[inner]] = True
    uv = np.full((len(tags), 2), np.nan)
    if len(inner) and len(inner_uv) == 2 * len(inner):
        uv[lookup[inner]] = np.asarray(inner_uv, dtype=float).reshape(-1, 2)
    tri = lookup[tri_tags].reshape(-1, 3)
    pinned, creases = crease_nodes(surface, uv, tri, tags)
    movable &= ~pinned
    fixed.update(creases)
    return FaceMesh(tags, coords, tri,
                    movable, uv, np.asarray(el_tags, dtype=np.int64), fixed, pinned)


def crease_nodes(surface: int, uv: np.ndarray, tri: np.ndarray, tags: np.ndarray
                 ) -> tuple[np.ndarray, set[tuple[int, int]]]:
    """The interior nodes (a mask over the rows of ``uv``, the nodes' parameters, NaN rows for the
    boundary's; ``tags``, their gmsh tags) on the folds of gmsh surface ``surface`` that
    :mod:`cadedge.mesh.extruded` meshed along (:data:`~cadedge.mesh.creases.CREASES`), and the edges of
    triangles ``tri`` between two nodes on one fold, the lines' boundary ends included (sorted pairs of
    rows). They stay as meshed: a node moved off a fold, or an edge swapped across one, puts a triangle
    across it again (a line from one boundary node to the other, or its end edges, swapped by the
    optimiser: a key blade's 90-degree corners spanned, 10.6 degrees)."""
    from .creases import CREASES

    pinned = np.zeros(len(uv), dtype=bool)
    if surface not in CREASES:
        return pinned, set()
    creases = CREASES[surface]
    fold = np.full(len(uv), -1, dtype=np.int64)
    for k, t in enumerate(creases.at):
        on = np.abs(uv[:, creases.column] - t) <= 1e-9 * max(1.0, abs(t))
        fold[on], pinned[on] = k, True
    if creases.ends:
        end_tags = np.fromiter(creases.ends, dtype=np.int64)
        end_folds = np.fromiter(creases.ends.values(), dtype=np.int64)
        order = np.argsort(end_tags)
        end_tags, end_folds = end_tags[order], end_folds[order]
        at = np.minimum(np.searchsorted(end_tags, tags), len(end_tags) - 1)
        hit = end_tags[at] == tags
        fold[hit] = end_folds[at[hit]]
    edges = np.sort(tri[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    along = (fold[edges[:, 0]] >= 0) & (fold[edges[:, 0]] == fold[edges[:, 1]])
    return pinned, {(int(p), int(q)) for p, q in edges[along]}


def write_interior(surface: int, face: FaceMesh, x: np.ndarray, tri: np.ndarray, movable: np.ndarray,
                   uv: np.ndarray) -> None:
    """Replace the interior of gmsh surface ``surface`` (read as ``face``) by nodes ``x`` (``face``'s rows
    first, new rows appended), the triangles ``tri`` and the parameters ``uv`` of the nodes still
    ``movable`` (or pinned on a fold) and used; the curves' nodes stay as they are.

    The interior nodes and the triangles get tags gmsh assigns, never ones chosen here: gmsh's own
    numbering does not count tags given to it, so a node added under its old tag (a face's mesh put back)
    or under ``getMaxNodeTag() + 1`` could later share its tag with a node gmsh made for another face, and
    triangles written by tag then held that face's node: once it was meshed again, a dangling one
    (sharp_blade, where a blade face's Delaunay mesh came back broken and was meshed anew)."""
    import gmsh

    own = np.array(movable, dtype=bool)
    own[:len(face.pinned)] |= face.pinned
    rows = np.flatnonzero(own & np.bincount(tri.ravel(), minlength=len(x)).astype(bool))
    gmsh.model.mesh.clear([(2, surface)])
    params = [] if np.isnan(uv[rows]).any() else uv[rows].ravel().tolist()
    gmsh.model.mesh.addNodes(2, surface, [], x[rows].ravel().tolist(), params)
    added, _, _ = gmsh.model.mesh.getNodes(2, surface, includeBoundary=False)
    tags = np.concatenate([face.tags, np.zeros(len(x) - len(face.tags), dtype=np.int64)])
    tags[rows] = np.asarray(added, dtype=np.int64)  # in the order they were added
    gmsh.model.mesh.addElementsByType(surface, 2, [], tags[tri].ravel().tolist())


def element_corners(dim: int, tag: int) -> np.ndarray:
    """The linear elements of one gmsh entity as corner coordinates: a surface's triangles (``dim`` 2,
    shape (m, 3, 3)) or a curve's segments (``dim`` 1, shape (k, 2, 3)); none when they reference a node
    gmsh does not list on the entity or its boundary."""
    import gmsh

    from .readback import node_lookup

    k = dim + 1
    _, elements = gmsh.model.mesh.getElementsByType(dim, tag)  # element type 1: 2-node line, 2: 3-node triangle
    if not len(elements):
        return np.zeros((0, k, 3))
    tags, coords, _ = gmsh.model.mesh.getNodes(dim, tag, includeBoundary=True)
    lookup = node_lookup(tags)
    elements = np.asarray(elements, dtype=np.int64)
    if elements.max() >= len(lookup) or (lookup[elements] < 0).any():  # a node off the entity: not ours
        return np.zeros((0, k, 3))
    return np.asarray(coords, dtype=float).reshape(-1, 3)[lookup[elements]].reshape(-1, k, 3)


def triangle_min_angles(surface: int) -> np.ndarray | None:
    """The smallest angle (degrees) of each triangle of gmsh surface ``surface``, from its corners
    (:func:`element_corners`); None if it has no triangles or they name nodes it does not hold."""
    from .quality import min_angles

    corners = element_corners(2, surface)
    if not len(corners):
        return None
    return min_angles(corners.reshape(-1, 3), np.arange(3 * len(corners)).reshape(-1, 3))
