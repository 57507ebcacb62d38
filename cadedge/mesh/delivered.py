"""What a mesh child hands over as it goes, and meshes written without gmsh's writer.

A child appends each face's triangles and each edge's segments to a file as it meshes them
(:func:`cadedge.mesh.worker.run_job`'s ``deliver``), so that the parent of a child it must kill at the
hard timeout still has them (:func:`delivered`), and a child that finished can be joined with faces an
earlier, stopped child meshed (:func:`with_earlier_faces`). Such meshes, and the joined meshes of a split
job (:mod:`cadedge.mesh.shards`), had no gmsh writer: :func:`write_meshio` writes them with meshio.
"""

from __future__ import annotations

import pickle
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from .outcomes import FaceOutcome
from .check import row_keys
from .shards import edge_uses, face_edges, faces_text, pieces, weld
from .strategies import STRATEGIES
from .worker import JobResult, MeshJob, empty_result


@dataclass
class Delivered:
    """A mesh no gmsh writer had (a killed child's, a split job's joined): the result, and its edges'
    segments for the writer (``lines`` (k, 2) node indices, ``line_edges`` (k,) edge ids)."""

    result: JobResult
    lines: np.ndarray
    line_edges: np.ndarray


def read_deliveries(path: str) -> tuple[dict[int, np.ndarray], dict[int, np.ndarray]]:
    """Faces' triangles and edges' segments from the child's delivery file (``worker.run_job``'s
    ``deliver``): the last record of an entity wins, a cleared face is dropped, a record cut off ends it."""
    faces: dict[int, np.ndarray] = {}
    edges: dict[int, np.ndarray] = {}
    try:
        with open(path, "rb") as f:
            while True:
                dim, tag, corners = pickle.load(f)
                into = faces if dim == 2 else edges
                if corners is None:
                    into.pop(tag, None)
                else:
                    into[tag] = corners
    except (OSError, EOFError, pickle.UnpicklingError, ValueError, TypeError):  # the end, or a record cut off
        pass
    return {f: t for f, t in faces.items() if len(t)}, {e: c for e, c in edges.items() if len(c)}


#: Why a delivered face is left out: its boundary is not its edges' last delivered curve meshes.
STALE = ("meshed by a stopped mesh process on curve meshes a later process changed: left out, as it "
         "would not conform to its neighbours")


def stale(faces: dict[int, np.ndarray], edges: dict[int, np.ndarray], grid) -> set[int]:
    """The delivered ``faces`` (id -> triangle corners (m, 3, 3)) meshed on other curve meshes than the
    last delivered ``edges`` (id -> segment corners (k, 2, 3)): a node of one of its edges is not among
    its corners, or (all its edges delivered) a corner on its mesh's boundary is on none of them. A later
    process re-meshes curves (another spacing for a failed face, a strategy's own curve mesh) and
    delivers them at once; faces an earlier, stopped process meshed on the old ones, and the later did
    not mesh again, joined to the rest, made the check fail where each process's own mesh conformed
    (an Inventor worm gear: 9 segments).

    A triangle meshed with a node ``m`` on its first edge, then that edge meshed finer (a node of the
    edge is not in the face) and coarser (a node of the face is on none of its edges):

    >>> from types import SimpleNamespace as E
    >>> grid = E(faces=1, edges=[E(id=i, degenerate=False, faces=[1]) for i in (1, 2, 3)])
    >>> a, b, c = np.eye(3)
    >>> m = (a + b) / 2
    >>> face = {1: np.array([[a, m, c], [m, b, c]])}
    >>> edges = {1: np.array([[a, m], [m, b]]), 2: np.array([[b, c]]), 3: np.array([[c, a]])}
    >>> stale(face, edges, grid)
    set()
    >>> stale(face, {**edges, 1: np.array([[a, (a + m) / 2], [(a + m) / 2, m], [m, b]])}, grid)
    {1}
    >>> stale(face, {**edges, 1: np.array([[a, b]])}, grid)
    {1}
    """
    bounded = face_edges(grid)
    keyed = {e: row_keys(c.reshape(-1, 3)) for e, c in edges.items()}
    out = set()
    for f, corners in faces.items():
        mine = bounded.get(f, set())
        points = row_keys(corners.reshape(-1, 3))
        on_edges = [keyed[e] for e in mine if e in keyed]
        if on_edges and not np.isin(np.concatenate(on_edges), points).all():
            out.add(f)
        elif on_edges and len(on_edges) == len(mine) and \
                not np.isin(points[_boundary_corners(points)], np.concatenate(on_edges)).all():
            out.add(f)
    return out


def _boundary_corners(keys: np.ndarray) -> np.ndarray:
    """Indices into a face's corner ``keys`` (3 a triangle) of the ends of the segments only one of its
    triangles has."""
    _, node = np.unique(keys, return_inverse=True)
    tri = node.reshape(-1, 3)
    at = np.arange(len(keys)).reshape(-1, 3)
    sides = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    ends = np.concatenate([at[:, [0, 1]], at[:, [1, 2]], at[:, [2, 0]]])
    _, which, count = np.unique(np.sort(sides, axis=1), axis=0, return_inverse=True, return_counts=True)
    return ends[count[which.ravel()] == 1].ravel()


def delivered(path: str, job: MeshJob, known_ok: dict[int, int], reason: str,
               events: list[str]) -> Delivered | None:
    """The faces the killed children delivered, as a result whose other faces fail with ``reason``; None
    when no face was delivered. Nodes are merged by exact coordinates within each connected piece of the
    shape (:func:`~cadedge.mesh.shards.pieces`): faces share their boundary nodes, and the delivered edge
    segments are the faces' boundary segments, so each edge's multiplicity for the check is known (how
    many delivered faces it bounds; 1-or-2 for a single-face edge, a possible seam)."""
    faces, edges = read_deliveries(path)
    dropped = stale(faces, edges, job.grid)
    faces = {f: t for f, t in faces.items() if f not in dropped}
    if not faces:
        return None
    order = sorted(faces)
    result = empty_result("")
    result.error = None
    piece, edge_piece = pieces(job.grid)
    result.nodes, index, lines, line_edges = weld([faces[f] for f in order], edges,
                                                  groups=([piece.get(f, -1) for f in order], edge_piece))
    result.triangles = index.reshape(-1, 3)
    result.triangle_faces = np.repeat(np.array(order, dtype=np.int64), [len(faces[f]) for f in order])
    result.edge_pairs = np.sort(lines, axis=1)
    result.edge_uses = edge_uses(job.grid, line_edges, set(faces), job.seams)
    names = {f: STRATEGIES[k].name for f, k in known_ok.items()}
    mine = sorted(job.faces) if job.faces is not None else range(1, job.grid.faces + 1)
    result.faces = [FaceOutcome(face=f, surface=f, strategy=names.get(f, STRATEGIES[0].name), triangles=len(faces[f]))
                    if f in faces else
                    FaceOutcome(face=f, surface=f, attempts=[("joining what was delivered", STALE)]) if f in dropped else
                    FaceOutcome(face=f, surface=f, attempts=[("meshing", f"not finished: {reason}")])
                    for f in mine]
    missing = len(mine) - len(faces)
    which = "the mesh process" if job.faces is None else f"the mesh process of {faces_text(set(job.faces))}"
    result.notes = events + [f"{which} was stopped ({reason}); the {len(faces)} faces it had meshed are "
                             "delivered as last meshed (re-meshed finer where that had finished), without the "
                             "face optimiser's last pass or gmsh's writer"
                             + (f"; {missing} faces are missing" if missing else "")] \
        + ([f"{faces_text(dropped)}: {STALE}"] if dropped else []) \
        + (_regridded(edges, job.grid) if job.mode == "nodes" else [])
    return Delivered(result, lines, line_edges)


def _regridded(edges: dict[int, np.ndarray], grid) -> list[str]:
    """A note naming the edges delivered with other segments than their grids (split by a fallback
    strategy or by gmsh, or meshed by gmsh itself; ``nodes`` mode): the stopped process's own notes on
    them are lost."""
    count = {e.id: len(e.points) - 1 for e in grid.edges if not e.degenerate}
    other = {e for e, c in edges.items() if e in count and len(c) != count[e]}
    return [f"{faces_text(other, noun='edge')}: meshed on other nodes than their grids (split by a fallback "
            "strategy or by gmsh, or meshed by gmsh itself)"] if other else []


def with_earlier_faces(result: JobResult, path: str, job: MeshJob, known_ok: dict[int, int], *,
                       rewrite: bool = False) -> Delivered | None:
    """``result``, from a child that finished, with the faces an earlier, stopped child delivered and this
    one did not mesh (its replay of them was stopped in turn, or came after the soft deadline with their
    strategy barred): the union of both, nodes merged by exact coordinates as for the hard timeout; None
    when there is no such face (unless ``rewrite``: gmsh's writer failed, so the result is wanted as
    delivered, for meshio). A restarted job that ran out of time used to end with the last child's faces
    only, down to none."""
    if result.error is not None:
        return None
    faces, _ = read_deliveries(path)
    meshed = {o.face for o in result.faces if o.ok}
    if not set(faces) - meshed and not (rewrite and faces):
        return None
    union = delivered(path, job, known_ok, "", [])
    if union is None:
        return None
    extra = sorted({o.face for o in union.result.faces if o.ok} - meshed)
    if not extra and not rewrite:
        return None
    mine = {o.face: o for o in result.faces}
    outcomes = [o if o.face in extra or o.face not in mine else mine[o.face] for o in union.result.faces]
    merged = replace(result, nodes=union.result.nodes, triangles=union.result.triangles,
                                 triangle_faces=union.result.triangle_faces, edge_pairs=union.result.edge_pairs,
                                 edge_uses=union.result.edge_uses, faces=outcomes, written=False)
    dropped = {o.face for o in union.result.faces if o.attempts and o.attempts[0][1] == STALE} - meshed
    merged.notes = result.notes + ([
        f"{faces_text(set(extra))}: meshed by an earlier mesh process that was stopped; the last one "
        "did not mesh them again, so they are delivered as that process meshed them (the mesh written by "
        "meshio, not gmsh's writer)"] if extra else []) \
        + ([f"{faces_text(dropped)}: {STALE}"] if dropped else [])
    return Delivered(merged, union.lines, union.line_edges)


def write_meshio(delivered: Delivered, output: Path) -> None:
    """Write a delivered or joined result with meshio (no gmsh writer had the whole mesh): in a ``.msh`` (format 2.2) the triangles
    and edge segments carry the physical groups gmsh's writer would give (``face <id>``, ``edge <id>``,
    tagged with the B-rep ids, see :mod:`cadedge.mesh.groups`); ``.stl`` and ``.vtk`` get the triangles."""
    import meshio

    result = delivered.result
    faces = result.triangle_faces.astype(np.int64)
    cells = [("triangle", result.triangles)]
    tags = [faces]
    field_data = {}
    # MSH 2.2: elements carry their physical and entity tags themselves (meshio's MSH 4.1 writer wants one
    # cell block and one node per entity)
    fmt = {".msh": "gmsh22", ".stl": "stl", ".vtk": "vtk"}[output.suffix.lower()]
    if fmt == "gmsh22":
        if len(delivered.lines):
            cells.insert(0, ("line", delivered.lines))
            tags.insert(0, delivered.line_edges)
        field_data = {**{f"edge {e}": np.array([e, 1]) for e in np.unique(delivered.line_edges).tolist()},
                      **{f"face {f}": np.array([f, 2]) for f in np.unique(faces).tolist()}}
    mesh = meshio.Mesh(result.nodes, cells, cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                       field_data=field_data)
    with atomic_path(output) as dst:
        meshio.write(str(dst), mesh, file_format=fmt)
    result.written = True
