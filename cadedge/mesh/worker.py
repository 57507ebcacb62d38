"""The gmsh side of ``mesh_shape``: one picklable :class:`MeshJob` in, one :class:`JobResult` out.

:func:`run_job` is the only place where gmsh meshes a model. It runs in a child process started by
:mod:`cadedge.mesh.isolate` (``python -m cadedge.mesh.worker JOB RESULT PROGRESS``), so a gmsh crash,
hang or exhausted memory costs that child, never the caller. Steps, in order:

1. import the BREP text (no healing; gmsh's wire fixing as a second try, see ``IMPORT_ATTEMPTS``);
2. map gmsh's entities onto cadedge's ids (:func:`~cadedge.mesh.gmsh_model.map_entities`, never raises);
3. ``nodes`` mode: impose the edge grids (or, for edges in ``job.adopt``, the 1-D mesh another process
   made of them); ``sizes`` mode: sizes at the grids' parameters; gmsh's size
   field; **hooks "before_generate"**; curves gmsh still has to mesh (degenerate, unmatched, or all of
   them in ``sizes`` mode);
4. every face of the job (``job.faces``, all by default; a shard's in a split job, see
   :mod:`cadedge.mesh.shards`, which also gets the edges a strategy changed, :func:`changed_edges`) on its
   own through the retry strategies (:func:`~cadedge.mesh.generate.mesh_faces`), with
   a progress line (``face F K``, or ``batch F1 F2 ...`` before a batch of first attempts) and **hooks
   "before_face"** (``context.face``, ``context.strategy`` set) before each attempt (the parent's
   watchdog reads the line); **hooks "after_generate"** (a hook may clear faces and mesh them again with
   ``mesh_faces``, updating ``context.outcomes``, after a ``refine F1 F2 ...`` line through
   ``context.progress`` for each face or group of faces meshed together; faces in ``job.no_refine`` are
   not meshed again); the re-check of every face (:func:`_recheck`, whose re-meshes are announced the
   same way);
5. read the mesh back; **hooks "before_write"**; write ``job.output`` if asked; **hooks "after_mesh"**.

Hooks are ``"module:function"`` names in ``job.hooks[stage]``, imported in the child and called as
``function(context)`` with a :class:`JobContext` (the job, the entity map, the gmsh surfaces, the face
outcomes and the raw mesh once they exist; gmsh's current model is the one being meshed). What an
``after_mesh`` hook returns (numpy arrays, plain data) lands in ``JobResult.extras[name]``. This is where
size fields, physical groups and per-face measurements plug in without touching the isolation.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import pickle
import re
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..childproc import die_with_parent
from ..shapegrid import ShapeGrid
from .facemesh import element_corners

#: Address space a mesh child may use, as a share of physical memory: beyond it allocations fail inside
#: the child (gmsh reports or crashes there) before the system's out-of-memory killer picks a process.
MEMORY_SHARE = 0.8
HOOK_STAGES = ("before_generate", "before_face", "after_generate", "before_write", "after_mesh")


@dataclass
class MeshJob:
    """Everything the child needs, picklable: the shape as BREP text and the grid without its OCCT shape."""

    source: str
    brep: bytes
    grid: ShapeGrid
    field: Any  # cadedge.mesh.sizes.SizeField (kept untyped: sizes imports gmsh)
    mode: str
    output: str | None = None  # where the child writes the mesh (gmsh picks the format from the suffix)
    skip: dict[int, dict[int, str]] = field(default_factory=dict)  # face -> {strategy index: reason}
    # faces whose curves gmsh meshes as alone, from its boundary field, when it meshes them itself (OCCT
    # finds them invalid, or of no area: see cadedge.mesh.strategies.INVALID_FACE_STRATEGIES)
    as_gmsh_alone: frozenset[int] = frozenset()
    known_ok: dict[int, int] = field(default_factory=dict)  # face -> strategy that meshed it in an earlier run
    deadline: float | None = None  # time.time() after which only known_ok attempts start
    finish_by: float | None = None  # time.time() after which no optional step (the optimiser) goes on
    no_batch: set[int] = field(default_factory=set)  # faces meshed one by one (their batch hung or crashed)
    no_refine: set[int] = field(default_factory=set)  # faces not to mesh again finer (that hung or crashed)
    attempt_bound: float | None = None  # the watchdog's bound on one face attempt, CPU seconds (sizes batches)
    hooks: dict[str, list[str]] = field(default_factory=dict)
    options: dict[str, Any] = field(default_factory=dict)  # free-form settings for hooks
    # the faces this job meshes (None: all); the other faces are imported but left alone, for another
    # process to mesh (see cadedge.mesh.shards)
    faces: frozenset[int] | None = None
    # edge -> (points, gmsh parameters): a 1-D mesh another process made of its curve, imposed instead of
    # the edge's grid (see changed_edges)
    adopt: dict[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    # this job's share of the whole job's faces (by boundary segments; a shard's is under 1): the steps'
    # minimum budgets (the optimiser's work, MeshAdapt's triangles), meant for the whole job, are scaled by it
    share: float = 1.0
    # vertex -> the vertex it is meshed as: vertices of one face at one point, merged in ``brep`` (see
    # cadedge.mesh.coincident)
    coincident: dict[int, int] = field(default_factory=dict)
    # edge -> the faces whose seam it is, for seams more than one face holds (a face repeated on the same
    # edges): each such face puts two triangles on each of its segments (see cadedge.mesh.shards.edge_uses)
    seams: dict[int, tuple[int, ...]] = field(default_factory=dict)
    # face -> (first face, (3, 4) matrix): faces that are another face placed again, with its edge grids
    # moved; the parent meshes only the first and moves its triangles (see cadedge.mesh.instances)
    copies: dict[int, tuple[int, np.ndarray]] = field(default_factory=dict)


@dataclass
class JobContext:
    """What a hook sees. Fields fill in as the job advances (``None`` before their step)."""

    job: MeshJob
    emap: Any = None  # cadedge.mesh.gmsh_model.EntityMap
    surfaces: list[int] = field(default_factory=list)
    outcomes: dict[int, Any] = field(default_factory=dict)  # gmsh surface -> outcomes.FaceOutcome
    raw: Any = None  # cadedge.mesh.readback.RawMesh
    face: int = 0  # the face attempt under way (for "before_face" hooks)
    strategy: int = -1  # its index in cadedge.mesh.strategies.STRATEGIES
    progress: Any = None  # progress(line): a line for the parent's watchdog (see cadedge.mesh.isolate)
    deliver: Any = None  # deliver(dim, id, corners): hand mesh to the parent as it is made (see run_job)
    # faces meshed one by one after the batches: hooks name those that may take gmsh long, so that a hang
    # costs only that face, not the batch it would have joined
    alone: set[int] = field(default_factory=set)
    started: float = field(default_factory=time.time)  # time.time() when the child took the job


@dataclass
class JobResult:
    """The child's answer: plain arrays and records only.

    ``nodes`` (n, 3); ``triangles`` (m, 3) 0-based; ``triangle_faces`` (m,) cadedge face ids; ``faces``
    one :class:`~cadedge.mesh.outcomes.FaceOutcome` per face; ``edge_pairs`` (k, 2) node-index pairs of the
    curve segments and ``edge_uses`` (k,) how many triangles each should have; ``imposed_edges`` the edges
    whose grid was imposed; ``unmatched_edges`` the edges gmsh meshed itself; ``error`` a reason when the
    job failed as a whole (gmsh could not import the shape, an internal error).
    """

    nodes: np.ndarray
    triangles: np.ndarray
    triangle_faces: np.ndarray
    faces: list[Any]
    edge_pairs: np.ndarray
    edge_uses: np.ndarray
    imposed_edges: list[int] = field(default_factory=list)
    unmatched_edges: list[int] = field(default_factory=list)
    own_mesh_edges: list[int] = field(default_factory=list)  # imposed grids a fallback replaced by gmsh's mesh
    notes: list[str] = field(default_factory=list)
    details: list[str] = field(default_factory=list)  # for --verbose: how each entity was matched
    extras: dict[str, Any] = field(default_factory=dict)
    error: str | None = None
    written: bool = False
    # for a job of some faces only (job.faces): the edges whose imposed 1-D mesh a strategy replaced,
    # as changed_edges gives them
    changed_edges: dict[int, tuple[np.ndarray, np.ndarray] | None] = field(default_factory=dict)


def empty_result(error: str) -> JobResult:
    """A result with no mesh and ``error`` as the reason."""
    return JobResult(nodes=np.zeros((0, 3)), triangles=np.zeros((0, 3), dtype=np.int64),
                     triangle_faces=np.zeros(0, dtype=np.int64), faces=[], edge_pairs=np.zeros((0, 2), np.int64),
                     edge_uses=np.zeros(0, dtype=np.int64), error=error)


def _hooks(ctx: JobContext, stage: str) -> dict[str, Any]:
    out = {}
    for name in ctx.job.hooks.get(stage, []):
        module, _, func = name.partition(":")
        out[name] = getattr(importlib.import_module(module), func)(ctx)
    return out


def _import(brep: bytes, notes: list[str]) -> tuple[str | None, str | None]:
    """Import the BREP into the current gmsh model: ``(error, partial)``. ``error`` is the reason when
    nothing could be imported; ``partial`` gmsh's reason when only part of the shape was (every attempt
    failed, and what the first one bound is kept)."""
    import gmsh

    from ..errors import GeometryError
    from .gmsh_model import IMPORT_ATTEMPTS, import_brep

    errors = []
    with tempfile.TemporaryDirectory(prefix="cadedge-brep-") as tmp:
        path = os.path.join(tmp, "shape.brep")
        with open(path, "wb") as f:
            f.write(brep)
        for attempt in range(len(IMPORT_ATTEMPTS)):
            try:
                import_brep(path, attempt=attempt)
            except GeometryError as exc:
                errors.append(str(exc))
                gmsh.clear()
                continue
            if attempt:
                notes.append(f"gmsh imported the shape only with its wire fixing ({errors[0]})")
            return None, None
        try:
            partial = import_brep(path, attempt=0, partial=True)
        except GeometryError:
            return errors[-1], None
    notes.append(f"gmsh imported the shape only in part ({partial or 'giving no reason'}): the faces it left out "
                 "are named")
    return None, partial


def _overlapping_faces(surfaces: list[int]) -> dict[int, float]:
    """Meshed surfaces whose inner triangle edges (not curve segments) are also edges of another surface's
    triangles: two faces with the same boundary loop (a lens) triangulated from their boundary nodes alone
    give the same triangles twice. Returns each one with the shortest such edge's length."""
    import gmsh

    from .readback import node_lookup

    tags, coords, _ = gmsh.model.mesh.getNodes()
    if not len(tags):
        return {}
    lookup = node_lookup(tags)
    x = np.asarray(coords, dtype=float).reshape(-1, 3)
    big = int(np.max(tags)) + 1
    _, seg = gmsh.model.mesh.getElementsByType(1)
    seg = np.sort(np.asarray(seg, dtype=np.int64).reshape(-1, 2), axis=1)
    on_curves = seg[:, 0] * big + seg[:, 1]
    keys, owners = [], []
    for s in surfaces:  # each surface's edges once, as integer keys
        tri = np.asarray(gmsh.model.mesh.getElementsByType(2, s)[1], dtype=np.int64).reshape(-1, 3)
        e = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
        keys.append(np.unique(e[:, 0] * big + e[:, 1]))
        owners.append(np.full(len(keys[-1]), s, dtype=np.int64))
    if not keys:
        return {}
    k, own = np.concatenate(keys), np.concatenate(owners)
    inner = ~np.isin(k, on_curves)  # one test for all surfaces: one per surface took 26 s on 227 faces
    k, own = k[inner], own[inner]
    pr = np.column_stack([k // big, k % big])
    _, inverse, counts = np.unique(k, return_inverse=True, return_counts=True)
    shared = counts[inverse.ravel()] > 1
    out: dict[int, float] = {}
    lengths = np.linalg.norm(x[lookup[pr[shared, 0]]] - x[lookup[pr[shared, 1]]], axis=1)
    for s, length in zip(own[shared].tolist(), lengths.tolist()):
        out[s] = min(out.get(s, np.inf), length)
    return out


def _recheck(ctx: JobContext, notes: list[str]) -> None:
    """Check every meshed face again after the ``after_generate`` hooks (a re-mesh, the optimiser's moves
    and flips): a face whose triangles no longer match its boundary curves exactly, or whose inner edges are
    not each shared by two triangles, is meshed again from scratch; faces whose inner edges coincide with
    another face's (the same triangles twice) are meshed again with sizes under a quarter of those edges,
    so they get interior nodes, but not under :func:`~cadedge.mesh.budget.filling_size` of the face's area
    (a Fusion caster part's face shared a 1.1e-13 inner edge, and gmsh meshing it at 3e-14 ran until the
    job's timeout). Boundaries are unchanged, so neighbours stay conforming; a note names them.

    Each re-mesh is announced ``refine F`` (``refined F`` after), so the parent's watchdog bounds it; a
    face whose re-mesh hung or crashed an earlier child (``job.no_refine``) is left as it was, and named."""
    import gmsh

    from .areas import gmsh_surface_areas
    from .budget import filling_size
    from .generate import mesh_faces, surface_ok

    face_of = ctx.emap.face_of_surface
    say = ctx.progress or (lambda line: None)
    held: list[int] = []  # faces the re-check would mesh again, but a re-mesh hung or crashed before

    def again(s: int) -> Any:
        """Face ``s`` meshed again from scratch, announced to the watchdog; its outcome."""
        say(f"refine {face_of.get(s, s)}")
        gmsh.model.mesh.clear([(2, s)])
        outcome = mesh_faces([s], face_of)[s]
        say(f"refined {face_of.get(s, s)}")
        return outcome

    def allowed(faces: list[int]) -> list[int]:
        held.extend(s for s in faces if face_of.get(s, s) in ctx.job.no_refine)
        return [s for s in faces if face_of.get(s, s) not in ctx.job.no_refine]

    meshed = [s for s, o in sorted(ctx.outcomes.items()) if o.ok and s > 0]
    broken = allowed([s for s in meshed if not surface_ok(s)])
    for s in broken:
        ctx.outcomes[s] = again(s)
    if broken:
        notes.append(f"faces {', '.join(str(face_of.get(s, s)) for s in broken)}: the steps after meshing (re-mesh "
                     "finer, optimiser) left triangles that do not match the face's boundary; meshed again")
    overlap = _overlapping_faces([s for s, o in sorted(ctx.outcomes.items()) if o.ok and s > 0])
    remesh = allowed(sorted(overlap))
    if remesh:
        cap = gmsh.option.getNumber("Mesh.MeshSizeMax")
        areas = gmsh_surface_areas(remesh)
        try:
            for s in remesh:
                gmsh.option.setNumber("Mesh.MeshSizeMax", min(cap, max(0.25 * overlap[s], filling_size(areas[s]))))
                ctx.outcomes[s] = again(s)
                if not ctx.outcomes[s].ok:  # keep a face meshed as before rather than none
                    gmsh.option.setNumber("Mesh.MeshSizeMax", cap)
                    ctx.outcomes[s] = again(s)
        finally:
            gmsh.option.setNumber("Mesh.MeshSizeMax", cap)
        notes.append(f"faces {', '.join(str(face_of.get(s, s)) for s in remesh)}: triangulated from their "
                     "boundary nodes alone they repeated another face's triangles; meshed again with interior nodes")
    if held:
        names = ", ".join(str(face_of.get(s, s)) for s in sorted(set(held)))
        notes.append(f"faces {names}: the re-check would have meshed "
                     "them again, but an earlier re-mesh hung or crashed gmsh; kept as they were")


def run_job(job: MeshJob, progress: Any = None, deliver: Any = None) -> JobResult:
    """Mesh ``job`` in this process (see the module doc); ``progress(line)`` gets one line per step.

    ``deliver(dim, id, corners)`` gets the mesh as it is made, so a parent that must kill this process at
    its hard timeout still has it: ``(2, face, triangles (m, 3, 3))`` as soon as a face is meshed, again
    when it is meshed finer (``refined F1 F2 ...``) and once more after the ``after_generate`` hooks (the final
    mesh), ``(2, face, None)`` when a meshed face is cleared, and ``(1, edge, segments (k, 2, 3))`` for
    every matched edge once its curve is meshed and again after the faces (strategies may split a curve
    or replace its mesh). Later records of the same entity replace earlier ones."""
    import gmsh

    from . import generate
    from .budget import held, job_budget
    from .curve_watch import CurveWatch
    from .generate import mesh_faces
    from .gmsh_model import gmsh_session, map_entities
    from .impose import impose_edge_grids
    from .readback import boundary_multiplicity, read_mesh
    from .shards import faces_text
    from .sizes import apply_spacing_sizes, configure_gmsh_sizes, curves_from_spacings

    notes: list[str] = []

    def say(line: str) -> None:
        if progress is not None:
            progress(line)
        words = line.split()
        if deliver is not None and words[:1] == ["refined"]:
            for f in (int(w) for w in words[1:]):
                if f in emap.faces:
                    deliver(2, f, element_corners(2, emap.faces[f]))  # the finer mesh

    def deliver_edges() -> None:
        if deliver is not None:
            for eid, m in sorted(emap.edges.items()):
                deliver(1, eid, element_corners(1, m.tag))

    with gmsh_session(), held(job_budget(job.attempt_bound)):  # a longer bound on an attempt buys finer faces
        say("import")
        error, partial = _import(job.brep, notes)
        if error is not None:
            return empty_result(error)
        ctx = JobContext(job=job)
        say("map")
        emap = ctx.emap = map_entities(job.grid, coincident=job.coincident)
        unmatched = list(emap.unmatched_edges)
        imposed_edges: list[int] = []
        if job.mode == "nodes":
            imposed = impose_edge_grids(job.grid, emap, job.adopt)
            imposed_edges = sorted(imposed.edge_nodes)
            unmatched = sorted(set(unmatched) | set(imposed.skipped))
            # sizes for gmsh's own mesh of these curves, should a failing face have it replace their grids
            apply_spacing_sizes(job.grid, emap, job.field, curves={emap.edges[e].tag for e in imposed_edges})
            gmsh.option.setNumber("Mesh.MeshOnlyEmpty", 1)
        else:
            apply_spacing_sizes(job.grid, emap, job.field)
            gmsh.option.setNumber("Mesh.MeshOnlyEmpty", 0)
        say("sizes")
        configure_gmsh_sizes(job.field)
        _hooks(ctx, "before_generate")
        say("curves")
        try:
            with curves_from_spacings() if job.mode == "sizes" else contextlib.nullcontext():
                gmsh.model.mesh.generate(1)
        except Exception as exc:  # gmsh's bare Exception: the faces on the curves it missed fail below
            notes.append(f"gmsh's curve meshing reported: {exc}")
        deliver_edges()
        # the imposed curve meshes as gmsh holds them, to tell later which a strategy changed
        imposed_points = curve_points(imposed_edges, emap) if job.faces is not None and job.mode == "nodes" else {}
        ctx.surfaces = sorted(emap.faces.values()) if job.faces is None else \
            [emap.faces[f] for f in sorted(job.faces) if f in emap.faces]  # the others: another process's
        extra = [] if job.faces is not None else sorted({t for _, t in gmsh.model.getEntities(2)} - set(ctx.surfaces))
        if extra:  # their triangles could only be labelled with some other face's id
            notes.append(f"gmsh surface(s) {', '.join(map(str, extra))} match no face of the shape: not meshed")
        face_of = emap.face_of_surface
        ctx.progress, ctx.deliver = say, deliver

        def prepare(face: int, k: int) -> None:
            ctx.face, ctx.strategy = face, k
            _hooks(ctx, "before_face")

        def started(face: int, k: int) -> None:
            say(f"face {face} {k}")
            prepare(face, k)

        def finished(face: int, k: int, reason: str | None) -> None:
            say(f"result {face} {k} ok" if reason is None else f"result {face} {k} fail {' '.join(reason.split())}")
            if reason is None and deliver is not None and face in emap.faces:
                deliver(2, face, element_corners(2, emap.faces[face]))

        def batch_started(faces: list[int]) -> None:
            say("batch " + " ".join(map(str, faces)))
            if generate.TRACE:  # which gmsh surface is which face, for the watchdog (see trace_culprit)
                sys.stdout.write(f"{BATCH_MARK} " + " ".join(f"{f}:{emap.faces[f]}" for f in faces if f in emap.faces)
                                 + "\n")
                sys.stdout.flush()

        def cleared(faces: list[int]) -> None:  # curves changed: as they are now, and faces cleared for it
            if deliver is not None:
                deliver_edges()
                for f in faces:
                    deliver(2, f, None)

        own_curves: set[int] = set()
        watch = CurveWatch(per_curve=True)
        # faces of one curvature count (by surface type, cadedge.mesh.fidelity) side by side in the batches:
        # a gmsh call costs about as much for one face as for 24 (it rebuilds every element of the model)
        per_circle = (job.options.get("fidelity") or {}).get("face_per_circle", {})
        ctx.outcomes = mesh_faces(ctx.surfaces, face_of, skip=job.skip, started=started, finished=finished,
                                  deadline=job.deadline, known_ok=job.known_ok, own_curves=own_curves,
                                  batch_started=batch_started, as_gmsh_alone=job.as_gmsh_alone,
                                  prepare=prepare, no_batch=job.no_batch | ctx.alone, batch_bound=job.attempt_bound,
                                  batch_order=lambda face: per_circle.get(face, 0.0), cleared=cleared, watch=watch)
        deliver_edges()
        if partial is not None:  # faces gmsh did not import: named with its reason, keyed apart from surfaces
            from .outcomes import FaceOutcome

            missing = sorted(set(job.faces or range(1, job.grid.faces + 1)) - set(emap.faces))
            ctx.outcomes.update({-f: FaceOutcome(face=f, surface=0, attempts=[("gmsh import", partial)])
                                 for f in missing})
        edge_of = {m.tag: eid for eid, m in emap.edges.items()}
        if watch.split:  # gmsh split them for a face whose boundary crossed itself (curve_watch.CurveWatch)
            meshes = "grids" if job.mode == "nodes" else "curve meshes"  # sizes mode: gmsh's own
            notes.append(f"{faces_text({edge_of[c] for c in watch.split if c in edge_of}, noun='edge')}: gmsh "
                         f"added nodes to their {meshes} where a face's boundary segments crossed in its "
                         "parameters; the faces on them were meshed again on those nodes")
        own_edges = sorted(edge_of[c] for c in own_curves if c in edge_of and edge_of[c] in imposed_edges)
        imposed_edges = [e for e in imposed_edges if e not in set(own_edges)]
        _hooks(ctx, "after_generate")
        _recheck(ctx, notes)
        changed = changed_edges(imposed_points, emap)
        if deliver is not None:  # the hooks may have meshed faces again or moved their nodes
            for s, o in sorted(ctx.outcomes.items()):
                if o.ok and s in face_of:
                    deliver(2, face_of[s], element_corners(2, s))
        say("read")
        raw = ctx.raw = read_mesh(ctx.surfaces)
        meshed = [s for s, o in ctx.outcomes.items() if o.ok]
        pairs, uses = boundary_multiplicity(raw, meshed)
        _hooks(ctx, "before_write")
        written = False
        if job.output and len(raw.triangles):
            say("write")
            try:
                gmsh.write(job.output)
                written = True
            except Exception as exc:  # the faces are meshed: the parent writes what they delivered
                notes.append(f"gmsh's writer failed ({str(exc) or 'giving no reason'}); the mesh was written by meshio")
        extras = _hooks(ctx, "after_mesh")
    from .parametric import TANGLED
    from .strategies import STRATEGIES

    flat = {st.name for st in STRATEGIES if st.unrolled == "parameters"}
    for s, o in ctx.outcomes.items():  # where a face laid flat had its boundary cross itself
        if o.strategy in flat and s in TANGLED:
            o.tangles = TANGLED[s]
    tri_faces = np.array([face_of[int(s)] for s in raw.triangle_surfaces], dtype=np.int64)
    return JobResult(nodes=raw.nodes, triangles=raw.triangles, triangle_faces=tri_faces,
                     faces=sorted(ctx.outcomes.values(), key=lambda o: o.face), edge_pairs=pairs, edge_uses=uses,
                     imposed_edges=imposed_edges, unmatched_edges=unmatched, own_mesh_edges=own_edges, notes=notes,
                     details=list(emap.notes),
                     extras=extras, written=written, changed_edges=changed)


def curve_points(edges: list[int], emap: Any) -> dict[int, np.ndarray]:
    """The nodes along each of ``edges``' gmsh curves (edge id -> points from the edge's first vertex),
    for those with a 1-D mesh: what :func:`changed_edges` compares with later. Points, not node tags:
    gmsh renumbers every node in its entity order after each meshing call, so a curve's tags change when
    its own order is not cadedge's (gmsh's benchmark simple_plane.brep: a job in two processes dropped
    all 108 faces as meshed on edges their neighbours had changed) and when a curve bound before it
    gains nodes (ellipses.brep at 1e-3: one split curve made 36 edges look changed)."""
    return {eid: got[0] for eid in edges if (got := _chain_of(emap.edges[eid])) is not None}


def _chain_of(match: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """The points along a matched edge's gmsh curve from the edge's first vertex, and their gmsh
    parameters; None where the curve has no 1-D mesh."""
    import gmsh

    from .generate import curve_chain

    if not len(gmsh.model.mesh.getElementsByType(1, match.tag)[1]):
        return None
    chain, u = curve_chain(match.tag)
    if match.params[-1] < match.params[0]:  # the edge's direction, as imposed
        chain, u = chain[::-1], u[::-1]
    tags, coords, _ = gmsh.model.mesh.getNodes(1, match.tag, includeBoundary=False)
    x_of = dict(zip(np.asarray(tags, dtype=np.int64).tolist(), np.asarray(coords, dtype=float).reshape(-1, 3)))
    for end in {int(chain[0]), int(chain[-1])} - set(x_of):  # the vertex nodes: on points, maybe another curve's
        x_of[end] = np.asarray(gmsh.model.mesh.getNode(end)[0], dtype=float)
    return np.array([x_of[t] for t in chain.tolist()]), u


def changed_edges(imposed: dict[int, np.ndarray], emap: Any) -> dict[int, tuple[np.ndarray, np.ndarray] | None]:
    """Edges whose curve no longer carries the nodes ``imposed`` on it (edge -> points from its first
    vertex, as :func:`curve_points` read them): a strategy split it or meshed it itself. Each with its
    nodes' points (from the edge's first vertex to its last) and gmsh parameters, for
    :func:`~cadedge.mesh.impose.impose_edge_grids` in the processes that mesh the edge's other faces; None
    where the new chain does not run from vertex to vertex (it cannot be imposed there)."""
    out: dict[int, tuple[np.ndarray, np.ndarray] | None] = {}
    for eid, was in imposed.items():
        got = _chain_of(emap.edges[eid])
        if got is None or (got[0].shape == was.shape and np.array_equal(got[0], was)):
            continue  # no mesh (its faces failed), or the imposed one
        points, u = got
        ends = np.array_equal(points[[0, -1]], was[[0, -1]])
        out[eid] = (points, u) if ends and np.all(np.isfinite(u)) else None
    return out


def _limit_memory() -> None:
    try:
        import resource

        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
        limit = int(MEMORY_SHARE * total)
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    except (ImportError, ValueError, OSError):  # not on this platform: the parent's timeout still bounds it
        pass


#: The trace line that starts each batch of faces: ``BATCH_MARK F:S ...``, face id and gmsh surface.
BATCH_MARK = "cadedge-batch"
_SURFACE_LINE = re.compile(r"Meshing surface (\d+)")


def trace_culprit(trace: str, faces: list[int]) -> int | None:
    """The face of ``faces`` that gmsh was meshing when the batch the ``trace`` text (a mesh child's
    standard output) ends in was stopped: the surface of its last "Meshing surface N" line after the last
    :data:`BATCH_MARK`, unless gmsh finished the batch ("Done meshing 2D") or named no surface of it."""
    _, mark, tail = trace.rpartition(BATCH_MARK + " ")
    if not mark:
        return None
    pairs, _, log = tail.partition("\n")
    face_of = {int(s): int(f) for f, s in (p.split(":") for p in pairs.split() if p.count(":") == 1)}
    lines = log.splitlines()
    at = [i for i, line in enumerate(lines) if _SURFACE_LINE.search(line)]
    if not at or any("Done meshing 2D" in line for line in lines[at[-1]:]):
        return None
    face = face_of.get(int(_SURFACE_LINE.search(lines[at[-1]]).group(1)))
    return face if face in faces else None


def main(argv: list[str]) -> int:
    """``python -m cadedge.mesh.worker JOB RESULT PROGRESS [FACES]``: unpickle the job, run it, pickle the
    result; each meshed face's triangles and each edge's segments are appended to FACES as they come (see
    :func:`run_job`). Its standard output is the job's trace: gmsh's progress through each batch of
    faces (:data:`cadedge.mesh.generate.TRACE`)."""
    from . import generate

    job_path, result_path, progress_path = argv[:3]
    faces_path = argv[3] if len(argv) > 3 else os.devnull
    generate.TRACE = True
    die_with_parent()
    _limit_memory()
    with open(job_path, "rb") as f:
        job = pickle.load(f)
    with open(progress_path, "a", buffering=1) as prog, open(faces_path, "ab") as faces:
        def deliver(dim: int, tag: int, corners: np.ndarray | None) -> None:
            pickle.dump((dim, tag, corners), faces, protocol=pickle.HIGHEST_PROTOCOL)
            faces.flush()

        def say(line: str) -> None:
            prog.write(line + "\n")
            prog.flush()

        try:
            result = run_job(job, say, deliver)
        except Exception as exc:  # reported to the parent as the job's failure, with where it happened
            where = traceback.extract_tb(exc.__traceback__)[-1]
            result = empty_result(f"internal error: {type(exc).__name__}: {exc} "
                                  f"({os.path.basename(where.filename)}:{where.lineno})")
        say("done")
    tmp = result_path + ".part"
    with open(tmp, "wb") as f:
        pickle.dump(result, f, protocol=pickle.HIGHEST_PROTOCOL)
    os.replace(tmp, result_path)
    return 0


if __name__ == "__main__":  # run through the importable module, so results pickle under its real name
    from cadedge.mesh.worker import main as _main

    sys.exit(_main(sys.argv[1:]))
