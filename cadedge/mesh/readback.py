"""The mesh read back from gmsh: nodes, triangles by surface, and how often each curve segment must be
used by triangles (the check's multiplicities)."""

from __future__ import annotations

from dataclasses import dataclass

import gmsh
import numpy as np

from .gmsh_model import surface_curve_uses


@dataclass
class RawMesh:
    """Triangles read back from gmsh: ``nodes`` (n, 3), ``tags`` (n,), ``triangles`` (m, 3) indices."""

    nodes: np.ndarray
    tags: np.ndarray
    triangles: np.ndarray
    triangle_surfaces: np.ndarray

    def index_of(self, node_tags: np.ndarray) -> np.ndarray:
        return node_lookup(self.tags)[np.asarray(node_tags, dtype=np.int64)]


def node_lookup(tags: np.ndarray) -> np.ndarray:
    """gmsh node tag -> row of ``tags`` (-1 for tags not among them), as an array indexed by tag."""
    tags = np.asarray(tags, dtype=np.int64)
    lookup = np.full(int(tags.max()) + 1 if len(tags) else 1, -1, dtype=np.int64)
    lookup[tags] = np.arange(len(tags))
    return lookup


def read_mesh(surfaces: list[int]) -> RawMesh:
    """All nodes and the triangles of ``surfaces`` from the current gmsh model."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    tags = np.asarray(tags, dtype=np.int64)
    nodes = np.asarray(coords, dtype=float).reshape(-1, 3)
    tris, owners = [], []
    for s in surfaces:
        _, tri_nodes = gmsh.model.mesh.getElementsByType(2, s)
        t = np.asarray(tri_nodes, dtype=np.int64).reshape(-1, 3)
        tris.append(t)
        owners.append(np.full(len(t), s, dtype=np.int64))
    raw = RawMesh(nodes=nodes, tags=tags, triangles=np.zeros((0, 3), dtype=np.int64),
                  triangle_surfaces=np.concatenate(owners) if owners else np.zeros(0, dtype=np.int64))
    if tris:
        raw.triangles = raw.index_of(np.vstack(tris))
    return raw


def boundary_multiplicity(raw: RawMesh, meshed: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Every curve segment as a sorted node-index pair (k, 2), and how many triangles it should have:
    the number of times its curve bounds a meshed surface (a failed neighbour leaves a boundary)."""
    uses: dict[int, int] = {}
    for s in meshed:
        for c, n in surface_curve_uses(s).items():
            uses[c] = uses.get(c, 0) + n
    pairs, counts = [], []
    for c, n in uses.items():
        _, seg = gmsh.model.mesh.getElementsByType(1, c)
        p = np.sort(raw.index_of(np.asarray(seg, dtype=np.int64).reshape(-1, 2)), axis=1)
        pairs.append(p)
        counts.append(np.full(len(p), n, dtype=np.int64))
    if not pairs:
        return np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.vstack(pairs), np.concatenate(counts)
