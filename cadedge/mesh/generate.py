"""Run gmsh's surface meshers, retrying and reporting failed faces one by one; read the mesh back.

gmsh meshes all empty surfaces in one call. Afterwards each surface is checked on its own (it has
triangles, and its triangle edges on its boundary curves are exactly the curve segments, each used as
often as the curve bounds the face); surfaces that fail are cleared and retried with the next 2-D
algorithm, the others are kept. Faces that fail every algorithm are reported with gmsh's own messages.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import gmsh
import numpy as np

from .gmsh_model import surface_curve_uses

# Frontal-Delaunay, then MeshAdapt, then Delaunay: gmsh's robust fallbacks for difficult faces.
ALGORITHMS = {6: "Frontal-Delaunay", 1: "MeshAdapt", 5: "Delaunay"}


@dataclass
class FaceFailure:
    """A face gmsh could not mesh conformingly: B-rep face id, gmsh surface tag and gmsh's reason."""

    face: int
    surface: int
    reason: str

    def line(self) -> str:
        return f"face {self.face}: gmsh failed: {self.reason}"


def _surface_ok(surface: int) -> bool:
    """Does the surface carry triangles whose boundary is exactly its (imposed or meshed) curve segments?"""
    _, tri_nodes = gmsh.model.mesh.getElementsByType(2, surface)
    if len(tri_nodes) == 0:
        return False
    tri = np.asarray(tri_nodes, dtype=np.int64).reshape(-1, 3)
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    uniq, counts = np.unique(edges, axis=0, return_counts=True)
    expected: dict[tuple[int, int], int] = {}
    for curve, uses in surface_curve_uses(surface).items():
        _, seg = gmsh.model.mesh.getElementsByType(1, curve)
        for a, b in np.sort(np.asarray(seg, dtype=np.int64).reshape(-1, 2), axis=1):
            expected[(int(a), int(b))] = expected.get((int(a), int(b)), 0) + uses
    got = {(int(a), int(b)): int(c) for (a, b), c in zip(uniq, counts)}
    if any(got.get(k, 0) != v for k, v in expected.items()):
        return False
    return all(c == 2 for k, c in got.items() if k not in expected)


def _reason(surface: int, log: list[str], exc: str | None) -> str:
    pat = re.compile(rf"\b(surface|face)\s+{surface}\b", re.IGNORECASE)
    msgs = [m for m in log if pat.search(m) and ("rror" in m or "arning" in m)]
    if not msgs:
        msgs = [m for m in log if "rror" in m][-1:] or ([exc] if exc else [])
    text = "; ".join(dict.fromkeys(m.strip() for m in msgs))
    return text or "no triangles, or triangles that do not match the face's boundary curves"


def mesh_surfaces(surfaces: list[int]) -> dict[int, str]:
    """Mesh every empty surface; returns {surface tag: gmsh's reason} for the ones that failed."""
    gmsh.option.setNumber("Mesh.MeshOnlyEmpty", 1)
    pending = list(surfaces)
    reasons: dict[int, str] = {}
    for algo, name in ALGORITHMS.items():
        if not pending:
            break
        gmsh.option.setNumber("Mesh.Algorithm", algo)
        gmsh.logger.get()  # drop older messages
        exc = None
        try:
            gmsh.model.mesh.generate(2)
        except Exception as err:  # gmsh raises a bare Exception with its last error message
            exc = str(err)
        log = gmsh.logger.get()
        failed = [s for s in pending if not _surface_ok(s)]
        for s in failed:
            reasons[s] = f"{name}: {_reason(s, log, exc)}"
        if failed:
            gmsh.model.mesh.clear([(2, s) for s in failed])
        pending = failed
    return {s: reasons[s] for s in pending}


@dataclass
class RawMesh:
    """Triangles read back from gmsh: ``nodes`` (n, 3), ``tags`` (n,), ``triangles`` (m, 3) indices."""

    nodes: np.ndarray
    tags: np.ndarray
    triangles: np.ndarray
    triangle_surfaces: np.ndarray

    def index_of(self, node_tags: np.ndarray) -> np.ndarray:
        lookup = np.full(int(self.tags.max()) + 1 if len(self.tags) else 1, -1, dtype=np.int64)
        lookup[self.tags] = np.arange(len(self.tags))
        return lookup[np.asarray(node_tags, dtype=np.int64)]


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
