"""An assembly's repeated parts meshed once: faces placed again get their first's triangles, moved.

A STEP assembly that places a part several times holds one B-rep face under several locations
(:func:`cadedge.occt.instances.face_placements`). Such faces get the same edge grids, moved: the copies
are set aside while the grids are fitted to the faces (:class:`SetAside`), and :func:`unify` gives the
other placed edges their first edges' grids where a length at a threshold gave one a node more. Meshing
each again would cost gmsh the same work for the same triangles. :func:`copies` keeps
the placed faces whose grids are their first face's moved point for point (within
:data:`TOLERANCE` of the shortest boundary segment); the job meshes the first faces only
(:mod:`cadedge.mesh.isolate`), and :func:`place` adds each copy's triangles, the first's moved, on the
copy's own boundary nodes, so its neighbours stay conforming. A copy whose first face was meshed on other
boundary nodes (a strategy split its curves) is left to be meshed on its own. The triangles moved are
as good and as close to the surface as the first's: a rigid motion keeps angles and areas, and the
copy's surface is the first's, moved.

The Koch low-cost robot's leader arm (Fusion 360, servos and screws placed several times) has 4 704
faces, 3 358 of them copies: at 1e-2 its job had taken the default 300 s on 2 cores, with faces left
out of time; 216-261 s with every face meshed once the copies were placed, and 165 s since they are
also fitted once.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .outcomes import FaceOutcome
from .shards import edge_uses, face_edges, faces_text

#: Points of two grids (or meshes) are the same when they are this share of the shortest boundary
#: segment apart, or less.
TOLERANCE = 1e-4
#: The fidelity hook's extras that hold face ids (lists) or map face ids to values (dicts), for the
#: report (:func:`cadedge.mesh.fidelity.after_mesh`): a copy has its first face's.
FACE_LISTS = ("stuck", "budget")
FACE_DICTS = ("floored", "folded")


def moved(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """``points`` (n, 3) under ``matrix`` (3, 4): ``A x + b``."""
    return np.asarray(points, dtype=float) @ matrix[:, :3].T + matrix[:, 3]


def unify(grid, faces: dict[int, tuple[int, np.ndarray]], edges: dict[int, tuple[int, np.ndarray]]):
    """``grid`` with each edge placed again (``edges``: edge -> first edge, matrix) whose faces are all
    copies (``faces``) of its first edge's faces, by the same motion, given its first edge's grid moved
    (its own end points kept: its vertices' nodes). Refined and fitted on their own, a repeated part's grids
    differ now and then by a node, where a length sits at a threshold (a bracket turned by 0.7 radians:
    3 of its 14 faces); each then costs gmsh a face of its own. The moved grid is as fine: the same curve,
    the same neighbourhood. An edge refined to a target of its own (``ald_for``, by edge or face:
    :func:`cadedge.shapegrid.recorded_targets`) other than its first edge's keeps its grid."""
    from ..shapegrid import recorded_targets, with_edges

    by_id = {e.id: e for e in grid.edges}
    targets = recorded_targets(grid)
    new = {}
    for e in grid.edges:
        if not _follows(e, by_id, faces, edges, targets):
            continue
        first, matrix = edges[e.id]
        points = moved(by_id[first].points, matrix)
        if len(points) < 2 or np.abs(points[[0, -1]] - e.points[[0, -1]]).max() > \
                TOLERANCE * float(np.linalg.norm(np.diff(points, axis=0), axis=1).min()):
            continue
        new[e.id] = _moved_grid(e, by_id[first], matrix)
    return with_edges(grid, [new.get(e.id, e) for e in grid.edges]) if new else grid


def _follows(e, by_id: dict, faces: dict[int, tuple[int, np.ndarray]], edges: dict[int, tuple[int, np.ndarray]],
             targets: dict[int, float]) -> bool:
    """Whether edge grid ``e`` is its first edge placed again with all its faces: each of them a copy
    (``faces``) of one of the first edge's faces, by the edge's motion (``edges``), and refined to the
    first edge's target (``targets``, by edge id)."""
    if e.degenerate or e.id not in edges or not e.faces:
        return False
    first, matrix = edges[e.id]
    if targets[e.id] != targets[first]:
        return False
    placed = [faces.get(f) for f in set(e.faces)]
    return all(p is not None and _same_motion(p[1], matrix) for p in placed) and \
        {p[0] for p in placed} == set(by_id[first].faces)


def _moved_grid(e, first, matrix: np.ndarray):
    """Edge grid ``e`` given ``first``'s grid moved by ``matrix``, its own end points (its vertices') kept."""
    points = moved(first.points, matrix)
    points[[0, -1]] = e.points[[0, -1]]
    return replace(e, points=points, params=first.params.copy(), ald_estimate=first.ald_estimate)


@dataclass
class SetAside:
    """The copies of an assembly's repeated parts, set aside while the edge grids are fitted to the faces
    (:func:`cadedge.mesh.fidelity.prepare`, :func:`cadedge.mesh.node_grids.fit_node_grids`): each pass
    fits the first faces only, and :meth:`back` gives the copies' edges their first edges' grids, moved,
    as :func:`unify` gave them after fitting every placement. The Koch leader arm's 8 490 edges of
    copies (of 12 104) were fitted for nothing: the stages before gmsh took 67 s at 1e-2, now 34.

    ``faces``: copy face -> its first face; ``edges``: each edge all of whose faces are copies -> its
    first edge and the motion; ``owners``: those edges' faces; ``placements``: the faces' and edges'
    placements, for :func:`unify`."""

    faces: dict[int, int]
    edges: dict[int, tuple[int, np.ndarray]]
    owners: dict[int, list[int]]
    placements: tuple[dict[int, tuple[int, np.ndarray]], dict[int, tuple[int, np.ndarray]]]

    def apart(self, grid):
        """``grid`` with the set-aside edges bounding no face: the passes, which take a face's boundary
        from its edges' ``faces``, see the copies' faces as bounded by nothing (and their edges as free
        edges, left alone by every fit to a face)."""
        from ..shapegrid import with_edges

        if not self.edges:
            return grid
        return with_edges(grid, [replace(e, faces=[]) if e.id in self.edges else e for e in grid.edges])

    def hide(self, areas: np.ndarray) -> np.ndarray:
        """Face areas (index ``id - 1``) with the copies' 0: no area target to fit them to."""
        out = np.array(areas, dtype=float)
        out[[f - 1 for f in self.faces]] = 0.0
        return out

    def follow(self, grid):
        """``grid`` (:meth:`apart`) with the set-aside edges on their first edges' grids, moved: before
        the proximity split, whose size field feels every edge near a point, of any part, so that it
        sees the copies as fitted, as it did when every placement was fitted."""
        from ..shapegrid import with_edges

        if not self.edges:
            return grid
        by_id = {e.id: e for e in grid.edges}
        return with_edges(grid, [_moved_grid(e, by_id[self.edges[e.id][0]], self.edges[e.id][1])
                                 if e.id in self.edges else e for e in grid.edges])

    def back(self, grid):
        """``grid`` (fitted :meth:`apart`) with the set-aside edges bounding their faces again, on their
        first edges' grids moved, then :func:`unify`'d (placed edges that were not set aside)."""
        from ..shapegrid import with_edges

        grid = self.follow(grid)
        if self.edges:
            grid = with_edges(grid, [replace(e, faces=self.owners[e.id]) if e.id in self.edges else e
                                     for e in grid.edges])
        return unify(grid, *self.placements)


def set_aside(grid, faces: dict[int, tuple[int, np.ndarray]], edges: dict[int, tuple[int, np.ndarray]]) -> SetAside:
    """What of ``grid`` to set aside while fitting (:class:`SetAside`), from the faces' and edges'
    placements (:func:`cadedge.occt.instances.face_placements`, ``edge_placements``): the copies whose
    every edge :func:`unify` would give its first edge's grid, not on a degenerate edge (such faces are
    meshed on their own, :func:`copies`), and their edges, each of whose faces is such a copy."""
    from ..shapegrid import recorded_targets

    by_id = {e.id: e for e in grid.edges}
    targets = recorded_targets(grid)
    follows = {e.id for e in grid.edges if _follows(e, by_id, faces, edges, targets)}
    edges_of = face_edges(grid)
    on_degenerate = {f for e in grid.edges if e.degenerate for f in e.faces}
    kept = {f for f, (first, _) in faces.items() if f not in on_degenerate and first not in on_degenerate
            and edges_of.get(f) and edges_of[f] <= follows}
    while True:  # an edge also bounding a face that is not set aside stays, and so does that edge's face
        aside = {e for e in follows if set(by_id[e].faces) <= kept}
        fewer = {f for f in kept if edges_of[f] <= aside}
        if fewer == kept:
            break
        kept = fewer
    return SetAside(faces={f: faces[f][0] for f in sorted(kept)}, edges={e: edges[e] for e in sorted(aside)},
                    owners={e: list(by_id[e].faces) for e in aside}, placements=(faces, edges))


def _same_motion(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two (3, 4) motions are one, to rounding."""
    return bool(np.abs(a - b).max() <= 1e-9 * max(1.0, float(np.abs(a[:, 3]).max())))


def copies(grid, placements: dict[int, tuple[int, np.ndarray]]) -> dict[int, tuple[int, np.ndarray]]:
    """The ``placements`` (face -> first face, matrix; :func:`cadedge.occt.instances.face_placements`)
    whose edge grids are the first face's moved: as many edges and points, each point of one grid within
    :data:`TOLERANCE` of the shortest segment of a point of the other, both ways. Faces on a degenerate
    edge (a cone's apex, a sphere's pole: a node no edge segment holds) are left out."""
    from scipy.spatial import cKDTree

    edges_of = face_edges(grid)
    by_id = {e.id: e for e in grid.edges}
    on_degenerate = {f for e in grid.edges if e.degenerate for f in e.faces}
    out: dict[int, tuple[int, np.ndarray]] = {}
    for face, (first, matrix) in sorted(placements.items()):
        if face in on_degenerate or first in on_degenerate or len(edges_of.get(face, ())) != \
                len(edges_of.get(first, ())) or not edges_of.get(face):
            continue
        mine = np.vstack([by_id[e].points for e in sorted(edges_of[face])])
        theirs = [by_id[e].points for e in sorted(edges_of[first])]
        if len(mine) != sum(len(p) for p in theirs):
            continue
        shortest = min(float(np.linalg.norm(np.diff(p, axis=0), axis=1).min()) for p in theirs)
        there = moved(np.vstack(theirs), matrix)
        gap = max(cKDTree(mine).query(there)[0].max(), cKDTree(there).query(mine)[0].max())
        if gap <= TOLERANCE * shortest:
            out[face] = (first, matrix)
    return out


def place(result, lines: np.ndarray, line_edges: np.ndarray, grid, placed: dict[int, tuple[int, np.ndarray]],
          seams: dict[int, tuple[int, ...]]) -> set[int]:
    """Add to ``result`` (a joined :class:`~cadedge.mesh.worker.JobResult`; ``lines``, ``line_edges`` its
    edges' segments) the triangles of every copy in ``placed`` (:func:`copies`) whose first face was
    meshed: the first's triangles moved, their boundary nodes the copy's own (each within
    :data:`TOLERANCE` of the shortest segment), their other nodes new. A copy of a face that failed fails
    with its reason. Returns the copies left to mesh on their own: the first face's boundary nodes are
    not the copy's moved (a strategy split the first's curves, or meshed them itself). Copies meshed
    already (in ``result``) are left as they are."""
    from scipy.spatial import cKDTree

    outcomes = {o.face: o for o in result.faces}
    edges_of = face_edges(grid)
    order = np.argsort(line_edges, kind="stable")
    ids, starts = np.unique(line_edges[order], return_index=True)
    stops = np.r_[starts[1:], len(order)]
    edge_nodes = {int(e): np.unique(lines[order[a:b]]) for e, a, b in zip(ids, starts, stops)}
    lengths = np.linalg.norm(result.nodes[lines[order, 0]] - result.nodes[lines[order, 1]], axis=1)
    edge_shortest = dict(zip(ids.tolist(), np.minimum.reduceat(lengths, starts).tolist())) if len(order) else {}
    by_face = np.argsort(result.triangle_faces, kind="stable")
    faces_sorted = result.triangle_faces[by_face]

    def boundary(face: int) -> np.ndarray:
        """The nodes of ``face``'s edges' segments; none when an edge has no segments in ``result``."""
        mine = sorted(edges_of.get(face, ()))
        if not mine or any(e not in edge_nodes for e in mine):
            return np.zeros(0, dtype=np.int64)
        return np.unique(np.concatenate([edge_nodes[e] for e in mine]))

    nodes, tris, tri_faces = [result.nodes], [result.triangles], [result.triangle_faces]
    count = len(result.nodes)
    left, done = set(), []
    for face, (first, matrix) in sorted(placed.items()):
        rep = outcomes.get(first)
        if face in outcomes and outcomes[face].ok:
            continue
        if rep is None or not rep.ok:
            why = rep.reason() if rep is not None else "not meshed"
            outcomes[face] = FaceOutcome(face=face, surface=face,
                                         attempts=[("placed again", f"face {first}, the same face placed "
                                                                    f"elsewhere, failed: {why}")])
            continue
        b_first, b_face = boundary(first), boundary(face)
        if len(b_first) != len(b_face) or not len(b_first):
            left.add(face)
            continue
        gap, at = cKDTree(result.nodes[b_face]).query(moved(result.nodes[b_first], matrix))
        shortest = min(edge_shortest[e] for e in edges_of[first])
        if gap.max() > TOLERANCE * shortest or len(np.unique(at)) != len(at):
            left.add(face)
            continue
        a, b = np.searchsorted(faces_sorted, [first, first + 1])
        rows = result.triangles[by_face[a:b]]
        used = np.unique(rows)
        inner = np.setdiff1d(used, b_first, assume_unique=True)
        src = np.concatenate([b_first, inner])
        dst = np.concatenate([b_face[at], count + np.arange(len(inner))])
        sort = np.argsort(src)
        tris.append(dst[sort][np.searchsorted(src[sort], rows)])
        tri_faces.append(np.full(len(rows), face, dtype=np.int64))
        nodes.append(moved(result.nodes[inner], matrix))
        count += len(inner)
        outcomes[face] = FaceOutcome(face=face, surface=face, strategy=rep.strategy, triangles=len(rows))
        done.append((face, first))
    result.nodes = np.vstack(nodes)
    result.triangles = np.vstack(tris).astype(np.int64)
    result.triangle_faces = np.concatenate(tri_faces).astype(np.int64)
    result.faces = [outcomes.get(f, FaceOutcome(face=f, surface=f)) for f in range(1, grid.faces + 1)]
    meshed = {o.face for o in result.faces if o.ok}
    result.edge_uses = edge_uses(grid, line_edges, meshed, seams)
    _copy_extras(result.extras, done)
    return left


def _copy_extras(extras: dict, done: list[tuple[int, int]]) -> None:
    """Give each placed copy its first face's entries in the fidelity hook's extras (``done``: copy, first)."""
    from .report import AFTER_MESH_HOOK

    hook = extras.get(AFTER_MESH_HOOK)
    if not isinstance(hook, dict) or not done:
        return
    for key in FACE_LISTS:
        if key in hook:
            held = set(hook[key])
            hook[key] = sorted(held | {face for face, first in done if first in held})
    for key in FACE_DICTS:
        if isinstance(hook.get(key), dict):
            hook[key].update({face: hook[key][first] for face, first in done if first in hook[key]})


def placed_note(placed: dict[int, tuple[int, np.ndarray]], left: set[int], outcomes: list) -> str | None:
    """The note on the copies: how many were placed from how many faces, and those meshed on their own;
    None where none was either (every first face failed)."""
    ok = {o.face for o in outcomes if o.ok}
    moved_to = [f for f in placed if f not in left and f in ok]
    firsts = len({placed[f][0] for f in moved_to})
    said = [f"{len(moved_to)} face{'s repeat' if len(moved_to) != 1 else ' repeats'} {firsts} "
            f"other{'s' if firsts != 1 else ''} (an assembly's parts placed again) on the same edge grids: "
            "meshed once, the triangles moved"] if moved_to else []
    if left:
        said.append(f"{faces_text(left)} meshed on their own (the face they repeat was meshed on other boundary "
                    "nodes)")
    return "; ".join(said) or None
