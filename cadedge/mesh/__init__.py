"""Surface meshes on cadedge's edge grids, by gmsh, with a watertight/conforming check.

``mesh_shape(source, ald=...)`` refines the edges (or takes a ready :class:`~cadedge.ShapeGrid`), loads the
same B-rep into gmsh, and then either

- ``mode="nodes"`` (default): imposes every edge grid as the mesh of its gmsh curve (shared vertex nodes,
  so faces sharing an edge share its nodes) and lets gmsh mesh only the faces, sized by a field graded
  from our spacings; or
- ``mode="sizes"``: gives gmsh only sizes (at the grid's parametric points on each curve and at each
  vertex) and lets it mesh the curves itself, for meshers that take sizes rather than nodes.

gmsh runs in a child process under a watchdog (:mod:`cadedge.mesh.isolate`, the job itself in
:mod:`cadedge.mesh.worker`): a gmsh crash, hang or exhausted memory costs that run or that face, never
the caller, and ``timeout`` bounds the whole job. Every face is meshed on its own and retried with other
strategies before it is given up. The result carries the triangles, the faces that still failed (with
gmsh's reason; the rest is meshed) and :class:`~cadedge.mesh.check.MeshCheck`; nothing meshed means no
output file. ``output`` may be ``.msh``, ``.stl`` or ``.vtk``
(the mesh) or ``.geo`` (the spacing export, see :func:`~cadedge.mesh.spacing_geo.write_geo`; no meshing).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError, MeshError
from ..shapegrid import ShapeGrid

if TYPE_CHECKING:  # gmsh, trimesh and scipy load only when a mesh is made (``cadedge --help`` stays fast)
    from .check import MeshCheck
    from .instances import SetAside
    from .jobclock import JobClock
    from .outcomes import FaceFailure
    from .sizes import SizeField

MODES = ("nodes", "sizes")
# Interior sizes grow by this much per unit distance from the edges (see sizes.configure_gmsh_sizes).
DEFAULT_GROWTH = 0.25
MESH_SUFFIXES = (".msh", ".stl", ".vtk")
# Edge grids for meshing are graded (neighbouring segments within this ratio, also across vertices): a
# one-segment straight edge next to a finely split arc would otherwise force sliver triangles.
MESH_MAX_GROWTH = 2.0


@dataclass
class MeshResult:
    """A surface mesh: ``nodes`` (n, 3), ``triangles`` (m, 3) 0-based, ``triangle_faces`` (m,) B-rep face ids."""

    source: str
    mode: str
    grid: ShapeGrid
    nodes: np.ndarray
    triangles: np.ndarray
    triangle_faces: np.ndarray
    failures: list[FaceFailure]
    check: MeshCheck | None
    output: Path | None = None
    seconds: float = 0.0
    notes: list[str] = field(default_factory=list)
    #: notes for ``--verbose`` only (how each edge and vertex was matched to gmsh's)
    details: list[str] = field(default_factory=list)
    #: per face: the strategy that meshed it and every failed attempt (``outcomes.FaceOutcome``)
    faces: list[Any] = field(default_factory=list)
    #: edges no gmsh curve carries: gmsh meshed them itself, so their faces lack our grid nodes there
    unmatched_edges: list[int] = field(default_factory=list)
    #: edges whose grid a failing face made the mesher replace by gmsh's own curve mesh (last fallback)
    own_mesh_edges: list[int] = field(default_factory=list)
    #: the reason when gmsh produced nothing at all (import failed, crash, timeout)
    error: str | None = None
    #: what the child's ``after_mesh`` hooks returned (see :mod:`cadedge.mesh.worker`)
    extras: dict[str, Any] = field(default_factory=dict)
    #: per face: surface type, triangles, area deficit, min angle (:class:`~cadedge.mesh.report.MeshReport`)
    report: Any = None
    #: edge id -> its tolerance with the pcurves it was meshed with, where those were rebuilt in step with its
    #: curve (:mod:`cadedge.occt.sameparam`): its tolerance had covered the old pcurves, not its distance
    #: from its faces
    restepped: dict[int, float] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Every face meshed and the check passed."""
        return not self.failures and self.error is None and (self.check is None or self.check.ok)

    def problems(self, *, verbose: bool = False) -> list[str]:
        """The failed faces grouped by reason (one line each, or one per face with every attempt when
        ``verbose``), then the check's problems."""
        from .outcomes import failure_lines

        head = [self.error] if self.error and not self.failures else []
        check = self.check.problems if self.check else []
        return head + failure_lines(self.failures, self.faces, total=self.grid.faces, verbose=verbose) + check

    def lines(self) -> list[str]:
        """The printed report: the check summary and the problems."""
        head = f"{self.source}: {len(self.grid.edges)} edges, {self.grid.segments} segments, mode {self.mode}, " \
               f"{self.seconds:.2f} s"
        check = self.check.lines(missing=len(self.failures)) if self.check else []
        return [head] + check + (self.report.lines() if self.report else []) + self.problems()


def _grid_of(source: Any, ald: float, min_length: float | None, max_length: float | None,
             max_growth: float | None, allow_partial: bool, say: Callable[[str], None]) -> ShapeGrid:
    if isinstance(source, ShapeGrid):
        if source.shape is None:
            raise InputError(f"{source.source}: the shape grid carries no OCCT shape to mesh")
        return source
    from .. import refine_shape
    return refine_shape(source, ald=ald, min_length=min_length, max_length=max_length, max_growth=max_growth,
                        allow_partial=allow_partial,
                        progress=lambda done, total: say(f"refining edges: {done}/{total}"))


def mesh_shape(source: Any, *, ald: float = 1e-3, output: str | os.PathLike | None = None,
               mode: str = "nodes", min_length: float | None = None, max_length: float | None = None,
               max_growth: float | None = MESH_MAX_GROWTH, growth: float = DEFAULT_GROWTH,
               max_size: float | None = None, timeout: float | None = None,
               face_timeout: float | None = None, hooks: dict[str, list[str]] | None = None,
               job_options: dict[str, Any] | None = None, surface_ald: float | None = None,
               allow_partial: bool = False, progress: Callable[[str], None] | None = None,
               workers: int | None = None) -> MeshResult:
    """Mesh every face of ``source`` (STEP path, cadquery/build123d/OCP shape, or a ``ShapeGrid``).

    ``ald``, ``min_length``, ``max_length``, ``max_growth`` go to :func:`cadedge.refine_shape` (ignored for
    a ready ShapeGrid); ``max_growth`` defaults to :data:`MESH_MAX_GROWTH` here (``None`` for pure ALD
    grids). Interior sizes grow from the edge spacings by ``growth`` per unit distance, capped
    at ``max_size`` (default: ``max_length``, else the largest edge spacing). ``mode`` is ``"nodes"`` or
    ``"sizes"`` (see the module doc). The whole job is bounded by ``timeout`` seconds from this call on
    (default :data:`~cadedge.mesh.isolate.DEFAULT_TIMEOUT`; reading and refining included, the stages
    fitting the grids to the faces left out past a share of it: :mod:`cadedge.mesh.jobclock`), one face
    attempt by ``face_timeout`` (default a fifth of it); ``hooks`` are run inside the gmsh job with
    ``job_options`` (picklable) as ``job.options`` (see :mod:`cadedge.mesh.worker`). Every face's area
    deficit ``1 - mesh area / B-rep area`` is aimed at ``|deficit| <= surface_ald`` (default ``ald``; see
    :mod:`cadedge.mesh.fidelity`) and measured in ``result.report``. ``allow_partial`` goes to
    :func:`cadedge.refine_shape` (a file OCCT transfers only in part is an InputError without it). ``progress(text)``, if given, is called with what the job is doing
    at each step (refining edges, each face meshed, ...; the CLI's status line), from this process. A large
    job (at least :data:`~cadedge.mesh.shards.MIN_SEGMENTS` boundary segments, ``nodes`` mode) is meshed
    in up to ``workers`` gmsh processes at once (default: the CPUs this process may use; 1 meshes in one),
    each face in one of them (see :mod:`cadedge.mesh.shards`). A face that is an earlier face placed again
    (an assembly's repeated part, on the same edge grids moved) is not meshed in gmsh: it gets that face's
    triangles, moved (see :mod:`cadedge.mesh.instances`; ``hooks`` see only the faces gmsh meshes). Raises
    :class:`InputError` on bad arguments or input; faces gmsh fails on, crashes and timeouts are returned
    in ``failures`` / ``error``, never raised.
    """
    if mode not in MODES:
        raise InputError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    for name, value in (("timeout", timeout), ("face_timeout", face_timeout)):
        if value is not None and not value > 0:
            raise InputError(f"{name} must be a positive number of seconds, got {value!r}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise InputError(f"workers must be a whole number of processes, 1 or more, got {workers!r}")
    out = Path(output) if output is not None else None
    if out is not None and out.suffix.lower() not in MESH_SUFFIXES + (".geo",):
        raise InputError(f"{out}: unsupported mesh output suffix {out.suffix!r} "
                         f"(use {', '.join(MESH_SUFFIXES)} or .geo)")
    if out is not None and not (out.parent if str(out.parent) else Path(".")).is_dir():
        raise InputError(f"{out}: output folder does not exist")
    from .isolate import DEFAULT_TIMEOUT
    from .jobclock import JobClock
    from .sizes import SizeField
    from .spacing_geo import write_geo

    t0 = time.perf_counter()
    clock = JobClock(timeout or DEFAULT_TIMEOUT)
    say = progress or (lambda text: None)
    grid = _grid_of(source, ald, min_length, max_length, max_growth, allow_partial, say)
    if not grid.faces:
        raise InputError(f"{grid.source}: the shape has no faces to mesh (only loose edges)")

    def make_field(g: ShapeGrid) -> SizeField:
        return SizeField(g, growth=growth, min_size=min_length, max_size=max_size or max_length)

    if out is not None and out.suffix.lower() == ".geo":
        write_geo(grid, out, growth=growth, max_size=max_size or max_length, surface_ald=surface_ald)
        return MeshResult(source=grid.source, mode="sizes", grid=grid, nodes=np.zeros((0, 3)),
                          triangles=np.zeros((0, 3), dtype=np.int64), triangle_faces=np.zeros(0, dtype=np.int64),
                          failures=[], check=None, output=out, seconds=time.perf_counter() - t0,
                          notes=[f"wrote {out} and {out.with_suffix('.brep')} (spacing export, not meshed)"])
    from .fidelity import HOOKS, prepare
    from .gridded import grid_face_ids

    if surface_ald is not None and not surface_ald > 0:
        raise InputError(f"surface_ald must be a positive number, got {surface_ald!r}")
    if surface_ald is None:  # one knob: the edges' ALD (a ready grid's own) is the faces' area target too
        surface_ald = float(grid.options.get("ald") or ald) if isinstance(source, ShapeGrid) else ald
    say("area target: measuring the B-rep faces and fitting their boundaries")
    refined = grid
    aside = _set_aside(grid) if mode == "nodes" else None  # an assembly's copies: fitted as their firsts
    grid, fidelity = prepare(grid, surface_ald,  # faces' area target: boundary fit, curvature sizes
                             fit=clock.allows("the boundary fit for the area target"), aside=aside)
    hooks = {stage: HOOKS.get(stage, []) + (hooks or {}).get(stage, []) for stage in {*HOOKS, *(hooks or {})}}
    if mode == "sizes":  # failed faces get their curves meshed at other sizes before the surface target
        hooks["after_generate"] = ["cadedge.mesh.sizes:retry_failed_faces"] + hooks.get("after_generate", [])
    job_options = {**(job_options or {}), "fidelity": fidelity}
    notes = []
    if mode == "nodes":  # imposed boundary nodes must be fine where the face around them is
        from .node_grids import fit_node_grids

        say("fitting the edge grids to the face sizes")
        grid, max_size, fit_notes = fit_node_grids(grid, refined, fidelity, surface_ald, growth=growth,
                                                   make_field=make_field, cap=max_size or max_length,
                                                   clock=clock, aside=aside)
        notes += fit_notes
        if aside is not None:
            grid = aside.back(grid)
    if (left_out := clock.note()) is not None:
        notes.append(left_out)
    fidelity["grid_faces"] = grid_face_ids(grid, fidelity["meshed_kinds"], surface_ald,  # the boundary's
                                           fidelity["brep_areas"])  # last word: which faces are grids
    field_ = make_field(grid)
    result = _run_gmsh(grid, field_, mode, out, t0, clock, face_timeout=face_timeout, hooks=hooks,
                       job_options=job_options, say=say, workers=workers)
    result.notes[:0] = notes
    from .report import report_of

    say("measuring the mesh's faces")
    result.report = report_of(result, fidelity)
    return result


def _set_aside(grid: ShapeGrid) -> SetAside | None:
    """The copies of an assembly's repeated parts in ``grid`` (:func:`cadedge.mesh.instances.set_aside`),
    fitted as their first faces and given their grids after; None without an OCCT shape."""
    from ..occt.instances import edge_placements, face_placements
    from .instances import set_aside

    if grid.shape is None:
        return None
    return set_aside(grid, face_placements(grid.shape), edge_placements(grid.shape))


def _run_gmsh(grid: ShapeGrid, field_: SizeField, mode: str, out: Path | None, t0: float, clock: JobClock, *,
              face_timeout: float | None, hooks: dict[str, list[str]] | None,
              job_options: dict[str, Any] | None, say: Callable[[str], None],
              workers: int | None = None) -> MeshResult:
    """Mesh in a child process (:func:`~cadedge.mesh.isolate.run_isolated`, within what is left of the
    job's time, ``clock``), then check in this one."""
    import dataclasses

    from ..occt.empty import without_empty
    from ..occt.instances import face_placements
    from ..occt.sameparam import in_step
    from ..occt.topology import Topology
    from .check import check_triangles, segment_uses, twin_points
    from .coincident import meshed_as, merged_shape
    from .gmsh_model import shape_to_brep
    from .instances import copies
    from .isolate import run_isolated
    from .outcomes import FaceFailure
    from .shards import coincident as shards_coincident
    from .shards import default_workers
    from .status import MeshStatus
    from .strategies import invalid_face_skips
    from .worker import MeshJob

    shape, coincident = merged_shape(grid)  # one gmsh point where a face has two vertices
    shape, left_out = without_empty(shape)  # gmsh's import and writer fail on a solid with no face
    shape, restepped = in_step(shape, _shortest_segments(grid))  # gmsh places edge nodes by the pcurves
    meshed = meshed_as(dataclasses.replace(grid, shape=None, curves=None), coincident)
    tolerance = {r.edge: r.tolerance for r in restepped}
    if tolerance:  # the job judges what the edges' tolerances excuse by the tolerances they now need
        meshed = dataclasses.replace(meshed, edges=[dataclasses.replace(e, tolerance=tolerance[e.id])
                                                    if e.id in tolerance else e for e in meshed.edges])
    invalid = _invalid_faces(grid, (job_options or {}).get("fidelity", {}).get("brep_areas"))
    placed = {} if mode != "nodes" or coincident or shards_coincident(meshed) else \
        copies(meshed, face_placements(grid.shape))
    job = MeshJob(source=grid.source, brep=shape_to_brep(shape), grid=meshed, field=field_, mode=mode,
                  hooks=dict(hooks or {}), options=dict(job_options or {}), coincident=coincident,
                  skip=invalid_face_skips(invalid), as_gmsh_alone=frozenset(invalid),
                  seams=Topology(grid.shape).shared_seams(), copies=placed)
    res = run_isolated(job, output=out, timeout=clock.timeout, face_timeout=face_timeout,
                       progress=MeshStatus(say, faces=set(range(1, grid.faces + 1)) - set(placed)),
                       workers=workers or default_workers(), started=clock.started)
    faces = list(res.faces)
    if res.error is not None:
        failures = [FaceFailure(face=f, surface=f, reason=res.error) for f in range(1, grid.faces + 1)]
    else:
        failures = _with_brep_checks([FaceFailure(face=o.face, surface=o.surface, reason=o.reason())
                                      for o in faces if not o.ok], invalid)
    check = None
    twins, twin_edges = twin_points(meshed.edges)
    if len(res.triangles):
        say("checking the mesh")
        failed = {f.face for f in failures}
        grid_points = None
        if mode == "nodes":  # imposed grids whose faces all meshed must be there, node for node
            imposed = set(res.imposed_edges)
            pts = [e.points for e in meshed.edges
                   if e.id in imposed and e.faces and not failed.intersection(e.faces) and len(e.points)]
            grid_points = np.vstack(pts) if pts else np.zeros((0, 3))
        multiplicity = segment_uses(res.edge_pairs, res.edge_uses)
        check = check_triangles(res.nodes, res.triangles, triangle_faces=res.triangle_faces,
                                grid_points=grid_points, edge_multiplicity=multiplicity, twins=twins)
    notes = list(res.notes)
    if twin_edges:  # named where both lie in one shell (shells may touch)
        shell = {f: k for k, sh in enumerate(check.shells) for f in sh.faces} if check is not None else {}
        shells = {e.id: {shell[f] for f in e.faces if f in shell} for e in meshed.edges}
        twin_edges = [(a, b) for a, b in twin_edges if shells[a] & shells[b]]
    if twin_edges:
        pairs = ", ".join(f"{a} with {b}" for a, b in twin_edges[:10])
        more = f" ({len(twin_edges)} pairs in all)" if len(twin_edges) > 10 else ""
        notes.append(f"edges that lie one on the other (the B-rep touches itself there; their nodes coincide, "
                     f"not joined): {pairs}{more}")
    if coincident:
        pairs = ", ".join(f"{v} with {k}" for v, k in sorted(coincident.items()))
        notes.append(f"vertices of one face at one point, meshed as one node: {pairs}")
    if left_out:
        notes.append(f"{' and '.join(left_out)} (holding no face) left out of the shape gmsh meshes")
    if restepped:
        worst = max(restepped, key=lambda r: r.before)
        if len(restepped) == 1:
            notes.append(f"edge {worst.edge}: its curves on its faces ran out of step with its own curve (by up to "
                         f"{worst.before:.2g}): rebuilt in step for meshing")
        else:
            notes.append(f"edges {_ids([r.edge for r in restepped])}: their curves on their faces ran out of step "
                         f"with their own curves (by up to {worst.before:.2g}, edge {worst.edge}): rebuilt in step "
                         "for meshing")
    if res.unmatched_edges:
        notes.append(f"edges {_ids(res.unmatched_edges)} match no gmsh curve: gmsh meshed those curves itself")
    if res.own_mesh_edges:
        notes.append(f"edges {_ids(res.own_mesh_edges)}: a face failed on their grids; gmsh's own curve mesh "
                     "replaced them")
    return MeshResult(source=grid.source, mode=mode, grid=grid, nodes=res.nodes, triangles=res.triangles,
                      triangle_faces=res.triangle_faces, failures=failures, check=check,
                      output=out if res.written else None, seconds=time.perf_counter() - t0, notes=notes,
                      faces=faces, unmatched_edges=list(res.unmatched_edges), own_mesh_edges=list(res.own_mesh_edges),
                      error=res.error, extras=res.extras,
                      details=list(res.details), restepped=tolerance)


def _shortest_segments(grid: ShapeGrid) -> dict[int, float]:
    """Edge id -> the length of its grid's shortest segment (edges with a segment only)."""
    return {e.id: float(e.segment_lengths.min()) for e in grid.edges if not e.degenerate and len(e.points) >= 2}


def _invalid_faces(grid: ShapeGrid, areas: np.ndarray | None = None) -> dict[int, str]:
    """Face id -> what is wrong with it, for every face OCCT's own check fails
    (:func:`cadedge.occt.validity.face_problems`) or, given the faces' B-rep ``areas`` (by id - 1, 0 for a
    face of no area: :func:`cadedge.mesh.fidelity.without_degenerate`), that has no area: such a face gets
    only the strategies gmsh alone would use (:data:`~cadedge.mesh.strategies.INVALID_FACE_STRATEGIES`),
    and if it fails the fault is said to be the model's. SparkFun's FlexyPin STEP file has three cylinder
    faces of no area between coinciding curves: one hung gmsh for 60 s twice among its 12 strategies, and
    the job ran out of time before a real face was tried again. Up front OCCT's check costs milliseconds
    (0.16 s for 917_fusee's 249 faces)."""
    if grid.shape is None or not grid.faces:
        return {}
    from ..occt.validity import face_problems

    checked = face_problems(grid.shape, list(range(1, grid.faces + 1)))
    arealess = {} if areas is None else {i: "it has no area" for i, a in enumerate(areas, start=1) if a == 0}
    return {**arealess, **{face: f"OCCT's BRepCheck: {why}" for face, why in checked.items()}}


def _with_brep_checks(failures: list[FaceFailure], problems: dict[int, str]) -> list[FaceFailure]:
    """``failures`` with the reason of each face in ``problems`` (see :func:`_invalid_faces`) extended by
    what OCCT's check finds: the fault is then the model's."""
    import dataclasses

    return [dataclasses.replace(f, reason=f"{f.reason}; the B-rep face itself is invalid ({problems[f.face]})")
            if f.face in problems else f for f in failures]


def _ids(ids: list[int], limit: int = 10) -> str:
    """``1, 2, 5`` or ``1, 2, ... (12 in all)``."""
    shown = ", ".join(str(i) for i in ids[:limit])
    return shown + (f", ... ({len(ids)} in all)" if len(ids) > limit else "")


def check_mesh(result_or_nodes: MeshResult | np.ndarray, triangles: np.ndarray | None = None, *,
               grid: ShapeGrid | None = None) -> MeshCheck:
    """Watertight/conforming check of a :class:`MeshResult` or of raw ``nodes`` and ``triangles``.

    For raw arrays, ``grid`` (optional) adds the every-edge-grid-node-is-a-mesh-node test; boundary edges
    are then only expected where a grid edge bounds a single face.
    """
    from .check import check_triangles, twin_points

    if isinstance(result_or_nodes, MeshResult):
        if result_or_nodes.check is None:
            raise MeshError(f"{result_or_nodes.source}: no mesh to check (spacing export only)")
        return result_or_nodes.check
    if triangles is None:
        raise InputError("check_mesh needs triangles with raw nodes")
    nodes = np.asarray(result_or_nodes, dtype=float)
    grid_points = None
    multiplicity = None
    twins = None
    if grid is not None:
        grid_points = _face_grid_points(grid)
        multiplicity = _multiplicity_from_grid(nodes, grid)
        twins = twin_points(grid.edges)[0]
    return check_triangles(nodes, triangles, grid_points=grid_points, edge_multiplicity=multiplicity,
                           twins=twins)


def _face_grid_points(grid: ShapeGrid) -> np.ndarray:
    """Grid points of every edge that bounds a face (loose edges carry no triangles)."""
    pts = [e.points for e in grid.edges if e.faces and len(e.points)]
    return np.vstack(pts) if pts else np.zeros((0, 3))


def _multiplicity_from_grid(nodes: np.ndarray, grid: ShapeGrid) -> dict[tuple[int, int], int]:
    """Expected triangle counts of grid segments found in a raw mesh (by exact coordinates; where several
    nodes share a point, as on two B-rep edges lying on each other, every pair of them; where one node
    is at each end and two edges have that segment, both edges' counts, as
    :func:`~cadedge.mesh.check.segment_uses`)."""
    from .check import row_keys

    keys = row_keys(nodes)
    order = np.argsort(keys)
    ordered = keys[order]
    out: dict[tuple[int, int], int] = {}
    for e in grid.edges:
        if e.degenerate:
            continue
        k = row_keys(e.points)
        lo, hi = np.searchsorted(ordered, k, side="left"), np.searchsorted(ordered, k, side="right")
        n = len(e.faces) if len(e.faces) > 1 else 0  # one face: free boundary or seam, both fine
        for i in range(len(k) - 1):
            single = hi[i] - lo[i] == 1 and hi[i + 1] - lo[i + 1] == 1
            for a in order[lo[i]:hi[i]]:
                for b in order[lo[i + 1]:hi[i + 1]]:
                    pair = (int(min(a, b)), int(max(a, b)))
                    out[pair] = out[pair] + n if single and pair in out else n
    return out


__all__ = ["mesh_shape", "check_mesh", "MeshResult", "MODES", "MESH_SUFFIXES", "MESH_MAX_GROWTH",
           "DEFAULT_GROWTH"]
