"""Several gmsh processes at once: a mesh job's faces split into shards, and their meshes joined.

Every face is meshed on its own boundary, and in ``nodes`` mode those boundaries are the imposed edge
grids, the same in every process: a face meshed in one process conforms to its neighbour meshed in
another, and the meshes join by exact node coordinates. :func:`plan` splits the faces into one shard per
worker, balanced by boundary segments (what gmsh's time grows with, see
:func:`cadedge.mesh.isolate.attempt_bound`); faces bounded by the same edges (two faces on one boundary
loop) stay together, so the job's check for faces that repeat another's triangles still sees both.

The one way shards can disagree: a face's fallback strategy splits its curves or meshes them itself
(:data:`cadedge.mesh.strategies.STRATEGIES`), which changes the edge under the neighbour meshed elsewhere.
Each shard reports such edges (:func:`cadedge.mesh.worker.changed_edges`); :func:`conflicts` finds the
neighbours meshed on the old edge, and they are meshed again in a new process with the new edge imposed
(``MeshJob.adopt``), at most :data:`ADOPT_ROUNDS` times. Faces still on a disagreeing edge after that are
dropped and named (:func:`drop_faces`): a mesh with a face missing is reported as such, a non-conforming
one would not be.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .check import row_keys
from .outcomes import FaceOutcome
from .worker import JobResult, empty_result

#: A job is split only when its faces have at least this many boundary segments in all: below it one
#: process takes a few seconds. On 2 cores a second process saved time on every job measured, down to
#: the cylinder fixture's 270 segments (3.3 -> 2.9 s); at 20 000 the countersunk screw at 1e-3 (12 400)
#: took 44 s in one process, 28 in two, its face optimiser's budget shared between them.
MIN_SEGMENTS = 5_000
#: Rounds of meshing neighbours again on an edge another shard changed, at most.
ADOPT_ROUNDS = 2


def default_workers() -> int:
    """Processes to mesh in at once by default: the CPUs this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on this platform
        return max(1, os.cpu_count() or 1)


def face_edges(grid) -> dict[int, set[int]]:
    """Face id -> the ids of its non-degenerate edges."""
    out: dict[int, set[int]] = {f: set() for f in range(1, grid.faces + 1)}
    for e in grid.edges:
        if not e.degenerate:
            for f in e.faces:
                out.setdefault(f, set()).add(e.id)
    return out


def weight(faces, segments: dict[int, int]) -> int:
    """What meshing ``faces`` weighs: their boundary ``segments`` (face -> count), and 1 a face."""
    return sum(segments.get(f, 0) + 1 for f in faces)


def plan(grid, workers: int, segments: dict[int, int], *, leave: frozenset[int] = frozenset()) -> list[frozenset[int]]:
    """The faces of ``grid`` but those to ``leave`` (copies another face's mesh is moved to:
    :mod:`cadedge.mesh.instances`) in at most ``workers`` shards of about equal boundary ``segments``
    (face -> count); one shard with every face when ``workers`` is 1 or the job is small
    (:data:`MIN_SEGMENTS`).

    Four faces in a row (edge 1 between faces 1 and 2, ...), then faces 1 and 2 bounded by edge 1 alone:

    >>> from types import SimpleNamespace as E
    >>> def edge(i, faces):  # an edge with no points between its ends
    ...     return E(id=i, degenerate=False, faces=faces, points=np.zeros((2, 3)), vertices=(i, i + 1))
    >>> row = E(faces=4, vertices=[], edges=[edge(i, [i, i + 1]) for i in (1, 2, 3)])
    >>> plan(row, 2, {1: 30_000, 2: 30_000, 3: 10_000, 4: 5_000})
    [frozenset({1, 3}), frozenset({2, 4})]
    >>> lens = E(faces=4, vertices=[], edges=[edge(1, [1, 2]), edge(2, [3, 4])])
    >>> plan(lens, 2, {1: 30_000, 2: 30_000, 3: 10_000, 4: 5_000})
    [frozenset({1, 2}), frozenset({3, 4})]
    >>> plan(row, 2, {1: 3, 2: 3, 3: 1, 4: 1})
    [frozenset({1, 2, 3, 4})]
    """
    every = frozenset(range(1, grid.faces + 1)) - leave
    if workers < 2 or len(every) < 2 or weight(every, segments) - len(every) < MIN_SEGMENTS or coincident(grid):
        return [every]
    units: dict[frozenset[int], list[int]] = {}
    for f, edges in sorted(face_edges(grid).items()):
        if f in every:
            units.setdefault(frozenset(edges) or frozenset({-f}), []).append(f)
    weights = {key: weight(faces, segments) for key, faces in units.items()}
    shards: list[list[int]] = [[] for _ in range(min(workers, len(units)))]
    loads = [0] * len(shards)
    for key in sorted(units, key=lambda k: (-weights[k], min(units[k]))):  # heaviest first, to the lightest
        i = loads.index(min(loads))
        shards[i] += units[key]
        loads[i] += weights[key]
    return [frozenset(s) for s in shards if s]


def coincident(grid) -> bool:
    """Whether two of the grid's vertices and edge points in one connected piece of the shape
    (:func:`pieces`) are at the same coordinates (a non-manifold model's faces each on their own copy of
    an edge): the parts' meshes could not be joined by coordinates, so such a job is meshed in one
    process. Points of two pieces at one place (two solids of an assembly that touch) are told apart by
    their pieces: an Open CASCADE 6.8 circuit board of 75 solids, one point of one touching another, was
    meshed in one process and ran out of time at 1e-2 with 1 996 of its 3 379 faces."""
    _, edge_piece = pieces(grid)
    vertex_piece = {int(v): edge_piece[e.id] for e in grid.edges for v in e.vertices}
    points = [np.asarray(v.point, dtype=float).reshape(1, 3) for v in grid.vertices]
    groups = [np.array([vertex_piece.get(int(v.id), -1)], dtype=float) for v in grid.vertices]
    for e in grid.edges:
        if not e.degenerate:
            inner = np.asarray(e.points, dtype=float)[1:-1]
            points.append(inner)
            groups.append(np.full(len(inner), edge_piece[e.id], dtype=float))
    if not points:
        return False
    keys = row_keys(np.column_stack([np.concatenate(points), np.concatenate(groups)]))
    return len(np.unique(keys)) < len(keys)


@dataclass
class Part:
    """One process's share of a job: the faces it stands for, its result, and its edges' segments as it
    delivered them (edge -> (k, 2, 3) corners; see :func:`cadedge.mesh.delivered.read_deliveries`)."""

    faces: frozenset[int]
    result: JobResult
    edges: dict[int, np.ndarray] = field(default_factory=dict)
    adopted: frozenset[int] = frozenset()  # edges this part's job imposed from another part

    def meshed(self) -> set[int]:
        return {o.face for o in self.result.faces if o.ok and o.face in self.faces}


def conflicts(grid, parts: list[Part]) -> tuple[dict[int, tuple[np.ndarray, np.ndarray]], set[int], set[int]]:
    """Where the parts disagree on an edge: ``(adopt, redo, lost)``. An edge that one part changed and
    another part's meshed face has otherwise (as imposed, or changed its own way): that face is in
    ``redo``, to be meshed again with ``adopt[edge]`` (the first changing part's nodes) imposed; where the
    new chain cannot be imposed, the other parts' faces on it are in ``lost``."""
    on_edge = {e.id: list(e.faces) for e in grid.edges}
    adopt: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    changed_by: dict[int, int] = {}
    redo: set[int] = set()
    lost: set[int] = set()
    for i, part in enumerate(parts):
        for eid, chain in part.result.changed_edges.items():
            others = {f for j, p in enumerate(parts) if j != i for f in p.meshed()
                      if f in on_edge.get(eid, ()) and eid not in p.adopted}
            if not others:
                continue
            if eid in changed_by:  # changed here too: this part's faces on it are in redo already
                continue
            if chain is None:
                lost |= others
                continue
            changed_by[eid] = i
            adopt[eid] = chain
            redo |= others
    return adopt, redo - lost, lost


def drop_faces(part: Part, faces: set[int], reason: str) -> None:
    """Take ``faces`` out of ``part``'s mesh: their triangles go, their outcomes fail with ``reason``."""
    r = part.result
    keep = ~np.isin(r.triangle_faces, sorted(faces))
    r.triangles, r.triangle_faces = r.triangles[keep], r.triangle_faces[keep]
    r.faces = [FaceOutcome(face=o.face, surface=o.surface, attempts=[("joining the shards", reason)] + o.attempts)
               if o.face in faces else o for o in r.faces]


def faces_text(faces: set[int], limit: int = 8, *, noun: str = "face") -> str:
    """``face 3``, ``faces 3, 7`` or ``faces 1, 2, ... (12 in all)`` (at most ``limit`` named); ``noun``
    for other ids (``edges 4, 9``)."""
    ids = sorted(faces)
    shown = ", ".join(map(str, ids[:limit])) + (f", ... ({len(ids)} in all)" if len(ids) > limit else "")
    return f"{noun}{'s' if len(ids) > 1 else ''} {shown}"


def edge_uses(grid, edge_ids: np.ndarray, meshed: set[int], seams: dict[int, tuple[int, ...]]) -> np.ndarray:
    """How many triangles each segment of the edges ``edge_ids`` should have: how many times the meshed
    faces hold its edge, twice each face in ``seams[edge]`` (a cylinder's side repeated on its edges
    puts four triangles on each seam segment); 0 (free boundary or seam, both fine) for an edge of a
    single face."""
    by_id = {e.id: e for e in grid.edges}
    uses = {}
    for e in np.unique(edge_ids).tolist():
        on = by_id[e].faces if e in by_id else []
        twice = seams.get(e, ())
        uses[e] = 0 if len(on) == 1 else sum(2 if f in twice else 1 for f in on if f in meshed)
    return np.array([uses[e] for e in edge_ids.tolist()], dtype=np.int64)


def merge_extras(values: list[Any]) -> Any:
    """One hook's extras from several parts as one: dicts merged key by key, lists and tuples joined
    (sorted when they hold numbers only), arrays concatenated; any other value is the first part's.

    >>> merge_extras([{"split": [4], "floored": {2: 0.1}, "per_circle": 40.0}, {"split": [1], "floored": {}}])
    {'split': [1, 4], 'floored': {2: 0.1}, 'per_circle': 40.0}
    """
    if all(isinstance(v, dict) for v in values):
        keys = dict.fromkeys(k for v in values for k in v)
        return {k: merge_extras([v[k] for v in values if k in v]) for k in keys}
    if all(isinstance(v, (list, tuple)) for v in values):
        joined = [x for v in values for x in v]
        return sorted(joined) if all(isinstance(x, (int, float)) for x in joined) else joined
    if all(isinstance(v, np.ndarray) for v in values):
        return np.concatenate(values)
    return values[0]


def weld(blocks: list[np.ndarray], edges: dict[int, np.ndarray], *, distinct: bool = False,
         groups: tuple[list[int], dict[int, int]] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Point blocks and edges' segments ((k, 2, 3) corners each) as one node array, merged by exact
    coordinates (:func:`cadedge.mesh.check.row_keys`: -0.0 is 0.0) across blocks: ``(nodes, index of
    each block row in nodes, lines (k, 2) node indices, line_edges (k,) edge ids)``, the edges in id
    order. ``distinct`` (blocks of a process's nodes, not of triangle corners): within a block nodes stay
    as gmsh made them, the k-th at a point merged with the k-th of another block there. Two faces on one
    surface meshed in one process (gmsh's dlr_f6.brep repeats a face) keep their own interior nodes, as
    in a job of one process; welded, their triangles shared every edge four times and the check failed.
    ``groups`` (each block's group, or an array with each of its rows' group; each edge's group): points
    merge only within a group (the faces of one connected piece of the shape, :func:`pieces`).

    >>> block = np.array([[0., 0, 0], [1, 0, 0], [0, 0, 0]])
    >>> nodes, index, lines, line_edges = weld([block], {7: np.array([[[1., 0, 0], [-0.0, 0, 0]]])})
    >>> len(nodes), index.tolist(), lines.tolist(), line_edges.tolist()
    (2, [0, 1, 0], [[1, 0]], [7])
    >>> nodes, index, lines, _ = weld([block], {7: np.array([[[1., 0, 0], [-0.0, 0, 0]]])}, distinct=True)
    >>> len(nodes), index.tolist(), lines.tolist()
    (3, [0, 2, 1], [[2, 0]])
    """
    order = sorted(edges)
    points = [np.asarray(b, dtype=np.float64).reshape(-1, 3) for b in blocks]
    n = sum(len(p) for p in points)
    rows = np.concatenate(points + [edges[e].reshape(-1, 3) for e in order])
    keyed = rows
    if groups is not None:
        of_block, of_edge = groups
        group = np.concatenate([np.broadcast_to(np.asarray(g, dtype=np.float64), (len(p),))
                                for p, g in zip(points, of_block)]
                               + [np.full(edges[e].size // 3, of_edge.get(e, -1), dtype=np.float64) for e in order])
        keyed = np.column_stack([rows, group])
    _, at = np.unique(row_keys(keyed), return_inverse=True)
    at = at.ravel().astype(np.int64)
    repeat = np.zeros(len(rows), dtype=np.int64)  # earlier rows of the same block at the same point
    start = 0
    for p in points if distinct else ():
        repeat[start:start + len(p)] = _repeats(at[start:start + len(p)])
        start += len(p)
    _, first, inverse = np.unique(at * (int(repeat.max(initial=0)) + 1) + repeat, return_index=True,
                                  return_inverse=True)
    inverse = inverse.ravel().astype(np.int64)
    line_edges = np.repeat(np.array(order, dtype=np.int64), np.array([len(edges[e]) for e in order], dtype=np.int64))
    return rows[first], inverse[:n], inverse[n:].reshape(-1, 2), line_edges


def pieces(grid) -> tuple[dict[int, int], dict[int, int]]:
    """The connected pieces of ``grid``'s shape (faces, edges and vertices joined where they bound one
    another): ``(face id -> piece, edge id -> piece)``. Two solids of an assembly touching along a face
    each have their own faces, edges and vertices there, at the same points: gmsh gives each its own
    nodes, so each solid's shell is closed. Welded by coordinates alone, a Fusion pump's two solids
    shared the 119 segments round their common face, each used four times, and the check failed.

    >>> from types import SimpleNamespace as E
    >>> grid = E(faces=3, edges=[E(id=1, faces=[1, 2], vertices=(1, 2)), E(id=2, faces=[3], vertices=(3, 3)),
    ...                          E(id=3, faces=[], vertices=(2, 4))])
    >>> pieces(grid)
    ({1: 0, 2: 0, 3: 1}, {1: 0, 2: 1, 3: 0})
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    vertex_ids = sorted({int(v) for e in grid.edges for v in e.vertices})
    vertex = {v: grid.faces + len(grid.edges) + k for k, v in enumerate(vertex_ids)}
    pairs = [(grid.faces + i, f - 1) for i, e in enumerate(grid.edges) for f in e.faces] + \
            [(grid.faces + i, vertex[int(v)]) for i, e in enumerate(grid.edges) for v in e.vertices]
    a, b = np.array(pairs, dtype=np.int64).reshape(-1, 2).T
    n = grid.faces + len(grid.edges) + len(vertex_ids)  # nodes: faces, then edges, then vertices
    _, label = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)), directed=False)
    return ({f: int(label[f - 1]) for f in range(1, grid.faces + 1)},
            {e.id: int(label[grid.faces + i]) for i, e in enumerate(grid.edges)})


def _repeats(keys: np.ndarray) -> np.ndarray:
    """For each key, how many earlier entries have the same one.

    >>> _repeats(np.array([5, 3, 5, 5, 3])).tolist()
    [0, 0, 1, 2, 1]
    """
    order = np.argsort(keys, kind="stable")
    ranked = keys[order]
    k = np.arange(len(keys))
    starts = np.maximum.accumulate(np.where(np.r_[True, ranked[1:] != ranked[:-1]], k, 0)) if len(keys) else k
    out = np.empty(len(keys), dtype=np.int64)
    out[order] = k - starts
    return out


def join(grid, parts: list[Part], seams: dict[int, tuple[int, ...]]) -> tuple[JobResult, np.ndarray, np.ndarray]:
    """The parts' meshes as one result, nodes merged by exact coordinates within each connected piece of
    the shape (:func:`pieces`; a node's piece is that of its triangles' faces), and the edges' segments for
    the writer: ``(result, lines (k, 2) node indices, line_edges (k,) edge ids)``. An edge's segments are
    those of the last part that changed or adopted it, else the first part's. ``seams``: the job's
    (:attr:`cadedge.mesh.worker.MeshJob.seams`)."""
    errors = [p.result.error for p in parts if p.result.error is not None]
    if len(errors) == len(parts):
        result = empty_result(errors[0])
        result.notes = list(dict.fromkeys(n for p in parts for n in p.result.notes))
        return result, np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int64)
    edges: dict[int, np.ndarray] = {}
    for p in parts:
        for eid, corners in p.edges.items():
            if eid not in edges or eid in p.result.changed_edges or eid in p.adopted:
                edges[eid] = corners
    piece, edge_piece = pieces(grid)
    face_piece = np.full(grid.faces + 1, -1.0)
    face_piece[list(piece)] = list(piece.values())
    blocks, of_block, tris, tri_faces, offset = [], [], [], [], 0
    for p in parts:
        r = p.result
        sel = np.isin(r.triangle_faces, sorted(p.faces))
        node_piece = np.full(len(r.nodes), -1.0)  # a node's piece: its triangles' faces' (none: dropped below)
        node_piece[r.triangles[sel]] = face_piece[r.triangle_faces[sel]][:, None]
        blocks.append(r.nodes)
        of_block.append(node_piece)
        tris.append(r.triangles[sel] + offset)
        tri_faces.append(r.triangle_faces[sel])
        offset += len(r.nodes)
    result = empty_result("")
    result.error = None
    nodes, index, lines, line_edges = weld(blocks, edges, distinct=True, groups=(of_block, edge_piece))
    triangles = index[np.concatenate(tris)]
    used = np.zeros(len(nodes), dtype=bool)  # a part's nodes off its own faces (other faces' edges) are
    used[triangles] = used[lines] = True  # in no piece there: kept only where a triangle or an edge is
    renumber = np.cumsum(used) - 1
    result.nodes, result.triangles, lines = nodes[used], renumber[triangles], renumber[lines]
    result.triangle_faces = np.concatenate(tri_faces).astype(np.int64)
    outcomes: dict[int, FaceOutcome] = {}
    for p in parts:
        if p.result.error is not None:
            outcomes.update({f: FaceOutcome(face=f, surface=f, attempts=[("meshing", p.result.error)])
                             for f in p.faces})
        else:
            outcomes.update({o.face: o for o in p.result.faces if o.face in p.faces})
    result.faces = [outcomes.get(f, FaceOutcome(face=f, surface=f)) for f in range(1, grid.faces + 1)]
    meshed = {o.face for o in result.faces if o.ok}
    result.edge_pairs = np.sort(lines, axis=1)
    result.edge_uses = edge_uses(grid, line_edges, meshed, seams)
    ok = [p.result for p in parts if p.result.error is None]
    result.own_mesh_edges = sorted({e for r in ok for e in r.own_mesh_edges})
    result.imposed_edges = sorted({e for r in ok for e in r.imposed_edges} - set(result.own_mesh_edges))
    result.unmatched_edges = sorted({e for r in ok for e in r.unmatched_edges})
    result.notes = list(dict.fromkeys(n for p in parts for n in p.result.notes))
    result.details = list(dict.fromkeys(d for r in ok for d in r.details))
    names = dict.fromkeys(k for r in ok for k in r.extras)
    result.extras = {k: merge_extras([r.extras[k] for r in ok if k in r.extras]) for k in names}
    return result, lines, line_edges
