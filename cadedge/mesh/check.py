"""Watertight / conforming check of a triangle surface mesh against its edge grids.

Per connected shell of triangles (trimesh's face-adjacency components): every triangle edge must be
shared by exactly two triangles, except edges on B-rep edges that bound fewer or more faces (free
boundaries of open shells are expected once; non-manifold edges as often as they have faces). Nodes at
identical coordinates under different tags within one shell are a hidden crack and fail the check
(separate shells may touch; nodes that all lie on free-boundary segments of B-rep edges are a gap of the
input itself, as where an IGES face's seam is two edges; nodes at points two B-rep edges or vertices
share, :func:`twin_points`, are the input's own too: a solid that touches itself along a line; and nodes
of two or more faces, none on a B-rep edge, where the faces' surfaces meet inside their boundaries: the
SolidWorks part 2242-A's planes 337 and 367 share an edge and both lie on its same side, one overlapping
the other, and at 1e-3 an interior node of each fell on one point; they are named, not failed). Every
edge-grid point must be a node of some triangle, at exactly its coordinates. Quality is reported, not
judged: the minimum angle, the share of triangles under :data:`SMALL_ANGLE` degrees and the faces that
hold them (worst first).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .quality import min_angles

#: Triangles with an angle below this many degrees are counted and their faces named.
SMALL_ANGLE = 10.0
#: Faces named in the summary line, worst first.
MAX_FACES_SHOWN = 5


@dataclass
class ShellCheck:
    """One connected set of triangles."""

    triangles: int
    faces: list[int]
    watertight: bool
    boundary_edges: int
    bad_edges: int


@dataclass
class MeshCheck:
    """Result of :func:`check_triangles`; ``ok`` is the overall verdict, ``problems`` one line each."""

    nodes: int
    triangles: int
    shells: list[ShellCheck]
    grid_nodes: int
    missing_grid_nodes: int
    duplicate_nodes: int
    min_angle_deg: float
    problems: list[str] = field(default_factory=list)
    #: share of triangles with an angle under :data:`SMALL_ANGLE` degrees (0 to 1)
    small_angle_share: float = 0.0
    #: faces holding such triangles, worst first: (face id, how many, smallest angle in degrees)
    small_angle_faces: list[tuple[int, int, float]] = field(default_factory=list)
    #: faces (sorted ids, per point) with nodes at one point where none lies on a B-rep edge: the faces'
    #: own surfaces meet there, away from their edges (one overlapping another), which no mesh closes
    meeting_faces: list[tuple[int, ...]] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems

    def lines(self, *, missing: int = 0) -> list[str]:
        """Human-readable summary, one line per shell, then the verdict. ``missing``: faces that failed to
        mesh; the check passes the triangles there are, open where those faces would be, and says so."""
        out = [f"mesh: {self.nodes} nodes, {self.triangles} triangles, {len(self.shells)} shells, "
               f"min angle {self.min_angle_deg:.1f} deg"]
        for i, s in enumerate(self.shells, 1):
            kind = "closed, watertight" if s.watertight else (
                f"open, {s.boundary_edges} boundary edges" if not s.bad_edges else "NOT conforming")
            out.append(f"  shell {i}: {s.triangles} triangles on {len(s.faces)} faces: {kind}"
                       + (f", {s.bad_edges} bad edges" if s.bad_edges else ""))
        if self.grid_nodes:
            out.append(f"  edge-grid nodes in mesh: {self.grid_nodes - self.missing_grid_nodes}/{self.grid_nodes}")
        if self.small_angle_faces:
            worst = ", ".join(f"{f} ({a:.1f} deg, {n})" for f, n, a in self.small_angle_faces[:MAX_FACES_SHOWN])
            more = len(self.small_angle_faces) - MAX_FACES_SHOWN
            out.append(f"  quality: {100 * self.small_angle_share:.2g}% of triangles under {SMALL_ANGLE:g} deg, "
                       f"on faces {worst}" + (f" and {more} more" if more > 0 else ""))
        if self.meeting_faces:
            pairs = ", ".join(" with ".join(map(str, f)) for f in self.meeting_faces[:MAX_FACES_SHOWN])
            more = len(self.meeting_faces) - MAX_FACES_SHOWN
            out.append(f"  faces meeting inside their boundaries (the B-rep's own surfaces overlap or touch there; "
                       f"their nodes coincide, not joined): {pairs}" + (f" and {more} more" if more > 0 else ""))
        verdict = "check: ok" if self.ok else f"check: FAILED ({len(self.problems)} problems)"
        if self.ok and missing:
            verdict += (f" on the faces meshed, open where the {missing} failed "
                        f"face{'s are' if missing > 1 else ' is'} missing")
        elif self.ok and self.small_angle_faces:
            verdict += f" (watertight and conforming, but min angle {self.min_angle_deg:.1f} deg)"
        out.append(verdict)
        return out


def row_keys(a: np.ndarray) -> np.ndarray:
    """Rows of a float array as hashable byte strings (exact coordinate identity)."""
    a = np.ascontiguousarray(np.asarray(a, dtype=np.float64) + 0.0)  # +0.0 folds -0.0 into 0.0
    return a.view(np.dtype((np.void, a.dtype.itemsize * a.shape[1]))).ravel()


def _nodes_of(tris: np.ndarray, n: int) -> np.ndarray:
    """The sorted node indices (< ``n``) used by triangles ``tris``."""
    used = np.zeros(n, dtype=bool)
    used[tris.ravel()] = True
    return np.flatnonzero(used)


def small_angles(angles: np.ndarray, tri_faces: np.ndarray) -> tuple[float, list[tuple[int, int, float]]]:
    """Share of triangles under :data:`SMALL_ANGLE` and (face, count, worst angle) per face, worst first."""
    small = angles < SMALL_ANGLE
    if not small.any():
        return 0.0, []
    faces, inverse = np.unique(tri_faces[small], return_inverse=True)
    counts = np.bincount(inverse)
    worst = np.full(len(faces), np.inf)
    np.minimum.at(worst, inverse, angles[small])
    order = np.argsort(worst)
    return float(small.mean()), [(int(faces[i]), int(counts[i]), float(worst[i])) for i in order]


def twin_points(edges: list) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """The points that two of the B-rep's own edges or vertices share (its edge grids' inner points, by
    edge; their end points, by vertex), and the pairs of edges that share them (by id, each pair once).
    A solid may touch itself along a line as two edges at one place, each bounding two faces (a Fusion
    hub motor's spokes, 1.75 long: four such pairs); their nodes are apart in any mesh true to it."""
    keys, owners = [], []
    for e in edges:
        if e.degenerate or not len(e.points):
            continue
        inner = np.full(len(e.points), e.id, dtype=np.int64)
        if len(e.vertices) >= 2:  # ends by vertex (negative, apart from edge ids)
            inner[0], inner[-1] = -1 - e.vertices[0], -1 - e.vertices[-1]
        keys.append(row_keys(e.points))
        owners.append(inner)
    if not keys:
        return np.zeros((0, 3)), []
    _, first, index = np.unique(np.concatenate(keys), return_index=True, return_inverse=True)
    held = np.unique(np.column_stack([index.ravel(), np.concatenate(owners)]), axis=0)  # (point, owner) once
    at, counts = np.unique(held[:, 0], return_counts=True)
    both = (held[:-1, 0] == held[1:, 0]) & (held[:-1, 1] > 0) & (held[1:, 1] > 0)  # inner points of two edges
    twins = np.unique(np.column_stack([held[:-1, 1][both], held[1:, 1][both]]), axis=0)
    points = np.vstack([e.points for e in edges if not e.degenerate and len(e.points)])
    return points[first[at[counts > 1]]], [(int(a), int(b)) for a, b in twins]


def segment_uses(pairs: np.ndarray, uses: np.ndarray) -> dict[tuple[int, int], int]:
    """Sorted node pairs (k, 2) of the curves' segments and their triangle counts (k,) as the check's
    ``edge_multiplicity``: a pair that is a segment of two curves has both counts. Two B-rep edges may
    share their two vertices and lie on each other (Voron Trident's umbilical mount: a hole's 0.00067 arc
    on a wall's line, where the solid touches itself), and their faces put four triangles on the one
    segment; the check expected the last curve's two and failed a conforming mesh.

    >>> segment_uses(np.array([[0, 1], [1, 2], [0, 1]]), np.array([2, 2, 2]))
    {(0, 1): 4, (1, 2): 2}
    """
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if not len(pairs):
        return {}
    unique, inverse = np.unique(pairs, axis=0, return_inverse=True)
    total = np.bincount(inverse.ravel(), weights=np.asarray(uses, dtype=np.float64), minlength=len(unique))
    return {(int(a), int(b)): int(n) for (a, b), n in zip(unique.tolist(), total.round().astype(np.int64).tolist())}


def check_triangles(nodes: np.ndarray, triangles: np.ndarray, *, triangle_faces: np.ndarray | None = None,
                    grid_points: np.ndarray | None = None,
                    edge_multiplicity: dict[tuple[int, int], int] | None = None,
                    twins: np.ndarray | None = None) -> MeshCheck:
    """Check a triangle mesh: ``nodes`` (n, 3), ``triangles`` (m, 3) 0-based indices into ``nodes``.

    ``triangle_faces`` gives each triangle's B-rep face id (for the report); ``grid_points`` the edge-grid
    points that must be mesh nodes; ``edge_multiplicity`` maps a sorted node-index pair on a B-rep edge to
    the number of triangles it should have (1 on a free boundary, 2 normally, more on non-manifold edges,
    0 for "1 or 2": a single-face edge not known to be a seam); any other mesh edge must have exactly two.
    ``twins``: points (k, 3) the B-rep holds more than once (:func:`twin_points`), where coinciding nodes
    are no crack.
    """
    nodes = np.asarray(nodes, dtype=float)
    tris = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    tri_faces = np.zeros(len(tris), dtype=np.int64) if triangle_faces is None else np.asarray(triangle_faces)
    problems: list[str] = []
    import trimesh  # here, not at the top: the CLI's parser imports this module's callers (``--help``)

    mesh = trimesh.Trimesh(nodes, tris, process=False, validate=False)
    edges = mesh.edges_sorted  # (3m, 2), edge k belongs to triangle k // 3
    n = max(len(nodes), 1)
    # one int64 per edge: np.unique over rows sorted 4M pairs in 8 s on a 1.4M-triangle mesh
    edge_keys, inverse, counts = np.unique(edges[:, 0] * n + edges[:, 1], return_inverse=True, return_counts=True)
    uniq = np.column_stack([edge_keys // n, edge_keys % n])
    expected = np.full(len(uniq), 2)
    if edge_multiplicity and len(edge_keys):
        pairs = np.array(list(edge_multiplicity), dtype=np.int64).reshape(-1, 2)
        wanted = pairs[:, 0] * n + pairs[:, 1]
        at = np.minimum(np.searchsorted(edge_keys, wanted), len(edge_keys) - 1)
        known = edge_keys[at] == wanted
        expected[at[known]] = np.array(list(edge_multiplicity.values()), dtype=np.int64)[known]
    either = expected == 0  # a single-face edge that may be a seam: once (free boundary) or twice
    bad = np.where(either, (counts < 1) | (counts > 2), counts != expected)
    boundary = (counts == 1) & ((expected == 1) | either)
    labels = trimesh.graph.connected_components(mesh.face_adjacency, nodes=np.arange(len(tris)),
                                                min_len=1, engine=None)
    shells: list[ShellCheck] = []
    edge_tri = np.arange(len(edges)) // 3
    for comp in sorted(labels, key=lambda c: int(np.min(c))):
        comp = np.asarray(comp)
        in_comp = np.zeros(len(tris), dtype=bool)
        in_comp[comp] = True
        used = np.zeros(len(uniq), dtype=bool)  # masks, not np.unique: its hashing took 2-3 s a call at 1.4M
        used[inverse.ravel()[in_comp[edge_tri]]] = True
        n_bad, n_bnd = int(bad[used].sum()), int(boundary[used].sum())
        faces = sorted({int(f) for f in tri_faces[comp]})
        shells.append(ShellCheck(triangles=len(comp), faces=faces, watertight=n_bad == 0 and n_bnd == 0,
                                 boundary_edges=n_bnd, bad_edges=n_bad))
        if n_bad:
            problems.append(f"shell on faces {faces[:8]}{'...' if len(faces) > 8 else ''}: {n_bad} triangle "
                            "edges not shared by the expected number of triangles (not watertight/conforming)")
    used_nodes = _nodes_of(tris, len(nodes))
    keys = row_keys(nodes[used_nodes])
    # nodes on free-boundary segments of B-rep edges: where two such edges coincide the B-rep itself is open
    # (an IGES face whose seam is two edges), so their coinciding nodes are the input's gap, not a crack
    on_free = np.zeros(len(nodes), dtype=bool)
    on_free[uniq[boundary].ravel()] = True
    # nodes on B-rep edges: where none of a point's nodes is, faces meet there away from their boundaries
    on_edge = None
    if edge_multiplicity:
        on_edge = np.zeros(len(nodes), dtype=bool)
        on_edge[np.array(list(edge_multiplicity), dtype=np.int64).ravel()] = True
    n_dup = 0
    overlaps: set[tuple[int, ...]] = set()
    twin_keys = row_keys(twins) if twins is not None and len(twins) else None
    for comp in labels:  # separate shells may touch (an assembly); within one shell it is a crack
        comp_nodes = _nodes_of(tris[np.asarray(comp)], len(nodes))
        point_keys, dup_inverse, dup_counts = np.unique(row_keys(nodes[comp_nodes]), return_inverse=True,
                                                        return_counts=True)
        inner = np.zeros(len(dup_counts), dtype=bool)  # a copy not on a free boundary: a crack of the mesh
        np.logical_or.at(inner, dup_inverse.ravel(), ~on_free[comp_nodes])
        if twin_keys is not None:  # unless two of the B-rep's own edges or vertices hold it
            inner &= ~np.isin(point_keys, twin_keys)
        dup = (dup_counts > 1) & inner
        if on_edge is not None and dup.any():  # every node there inside its face: the faces meet, no crack
            edged = np.zeros(len(dup_counts), dtype=bool)
            np.logical_or.at(edged, dup_inverse.ravel(), on_edge[comp_nodes])
            away = dup & ~edged
            if away.any():
                point = dup_inverse.ravel()
                mine = away[point]
                for k, faces in _faces_at(tris, tri_faces, comp_nodes[mine], point[mine]).items():
                    if len(faces) > 1:  # nodes of one face alone at one point stay a crack
                        overlaps.add(faces)
                        dup[k] = False
        n_dup += int(dup.sum())
    if n_dup:
        problems.append(f"{n_dup} coordinates carry more than one mesh node within a shell (a crack between faces)")
    n_grid = n_missing = 0
    if grid_points is not None and len(grid_points):
        gkeys = np.unique(row_keys(grid_points))
        n_grid = len(gkeys)
        n_missing = int((~np.isin(gkeys, keys)).sum())
        if n_missing:
            problems.append(f"{n_missing} of {n_grid} edge-grid nodes are not mesh nodes")
    angles = min_angles(nodes, tris) if len(tris) else np.zeros(0)
    share, worst_faces = small_angles(angles, tri_faces)
    return MeshCheck(nodes=len(used_nodes), triangles=len(tris), shells=shells, grid_nodes=n_grid,
                     missing_grid_nodes=n_missing, duplicate_nodes=n_dup,
                     min_angle_deg=float(angles.min()) if len(angles) else float("nan"), problems=problems,
                     small_angle_share=share, small_angle_faces=worst_faces, meeting_faces=sorted(overlaps))


def _faces_at(tris: np.ndarray, tri_faces: np.ndarray, at: np.ndarray,
              point: np.ndarray) -> dict[int, tuple[int, ...]]:
    """Point -> the faces (sorted ids) of the triangles on the nodes ``at`` that stand there (``point``:
    which point each node stands at)."""
    node_faces: dict[int, set[int]] = {}
    for t in np.flatnonzero(np.isin(tris, at).any(axis=1)):
        for v in tris[t]:
            node_faces.setdefault(int(v), set()).add(int(tri_faces[t]))
    faces: dict[int, set[int]] = {}
    for v, k in zip(at.tolist(), point.tolist()):
        faces.setdefault(k, set()).update(node_faces.get(v, ()))
    return {k: tuple(sorted(f)) for k, f in faces.items()}
