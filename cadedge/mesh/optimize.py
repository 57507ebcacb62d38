"""Improve every meshed face's triangles, keeping its boundary and its area target.

gmsh's frontal mesher leaves 22-30 degree triangles where its sizes change (from a boundary graded from
the edge grids to the curvature sizes inside); gmsh alone, with nearly uniform sizes, gets 33-40 degrees
on the same cylinders and boxes. Each face gets a few passes of:

- edge swaps (:func:`flip_edges`): the diagonal of two triangles is swapped where that raises their
  smaller angle; curve segments are never swapped;
- a "smart" Laplacian (:func:`smooth_nodes`): every interior node moves to the mean of its neighbours in
  3-D, projected back onto the B-rep surface (:class:`~cadedge.mesh.project.Projector`), where the smallest angle
  of its triangles does not fall and none flips;
- a local search (:func:`climb_nodes`): nodes of triangles under :data:`CLIMB_BELOW` degrees move to the
  best of 24 trial positions around them, the one that raises their worst angle most.

Only nodes within two rings of a triangle under :data:`CLIMB_BELOW` degrees move (and are projected,
the costly part on B-spline faces); the rest of a face is left as gmsh made it. A face still under
:data:`~cadedge.mesh.collapse.COLLAPSE_BELOW` degrees then gets passes with edge collapses
(:mod:`cadedge.mesh.collapse`: one interior node less where triangles crowd around a point, e.g. a
90-degree face corner fanned out in three 30-degree wedges, or beside a curve, merged into the curve's
node) and edge splits (:mod:`cadedge.mesh.corners`:
one interior node more where a triangle has all three nodes on the boundary, e.g. a face corner closed by
one triangle; the stage's last pass only settles them), and then a few more without, each stage kept
only if the face's worst angles rose (compared in order, the smallest first). These later stages are
repeated in rounds, a face's first in a sweep over all faces and the rest in a second sweep, so that one
large face does not take the others' time.

Before all this, triangles gmsh folded against the surface are unfolded (:func:`untangle_nodes`), and
no move may fold one (:mod:`cadedge.mesh.folds`; the nodes' surface normals follow them as they move).
The moves themselves are in :mod:`cadedge.mesh.moves`. Working in 3-D rather than in the surface's
parameters treats nodes beside a seam like any other (gmsh's own ``Laplace2D`` and ``Relocate2D`` left
the worst triangles of a cylinder, beside its seam, in place). Nodes on curves and points (every edge
grid node) never move, so neighbours stay conforming. A face keeps the result only when its smallest
angle does not fall and its area deficit stays within its target (or does not grow; a face not
converging may grow by :data:`STUCK_SLACK` of its target); a pass or stage whose result is not kept
is run once more on the nodes near the face's worst triangles only (:data:`FOCUS`), which changes its
area far less.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .collapse import COLLAPSE_BELOW, collapse_edges
from .corners import split_corner_triangles
from .folds import NodeNormals, _normals, folded, node_params, normals_at, orientation, reference_normals
from .gridded import NAME as GRID
from .moves import (CLIMB_BELOW, _near_bad, around, climb_nodes, flip_edges, flip_folds, smooth_nodes,
                    untangle_nodes)
from .project import Projector
from .quality import SLIVER_DEG, min_angles
from .work import Meter

#: Passes (edge swaps, then smoothing) per face.
PASSES = 3
#: Passes of the stages after the first, each kept only if it improves the face (see :data:`WORST`): with
#: edge collapses and splits (:mod:`cadedge.mesh.collapse`, :mod:`cadedge.mesh.corners`) in all passes but
#: the last, then without. The stages are chaotic (5 passes at once lifted the cylinder fixture at 1e-3
#: from 39.0 to 40.3 degrees but undid red_cube_blue_cylinder's collapses at 1e-2, 39.7 -> 33.7); kept
#: only when better, each can only help. Collapsing in every pass of 3 left the last collapses unsettled
#: and the stage was refused (the cylinder's caps at 1e-3 stayed at 38.7 in 2 of 4 perturbed starts; one
#: collapsing pass and one settling pass: 41.2-42.3 in all 4).
LATER_STAGES = ((2, True), (2, False))
#: The later stages are repeated while a round improves the face (see :data:`WORST`), at most this many
#: rounds: each round starts from the last one's result, whose collapses and
#: moves open new ones (the cylinder fixture's caps at 1e-3: 39.7 after one round, 41.2 after three).
STAGE_ROUNDS = 4
#: The second sweep's rounds go to the faces within this many degrees of the mesh's smallest angle (the
#: faces that set it: the cylinder fixture's 41.5-degree side at 1e-3 spent 40% of the optimiser's time on
#: rounds that did not change the mesh's 38.7) and still under
#: :data:`~cadedge.mesh.collapse.COLLAPSE_BELOW` degrees (about what gmsh alone reaches on such faces).
SWEEP_MARGIN = 2.0
#: A stage is kept when the face's :data:`WORST` smallest angles rise, compared in order (the smallest
#: first): where the worst triangle is stuck the next ones can still rise, and the next round lift it.
WORST = 20
#: A face not converging (its mesh and B-rep areas disagree: see :mod:`cadedge.mesh.fidelity`) is over
#: its target whatever the optimiser does; its deficit may grow by this share of the target (LLNL
#: boxed_sphere's faces over the target kept 20-23 degree triangles when any growth was refused), or by
#: :data:`STUCK_OWN` of its own deficit where that is more (boxed_sphere's small B-spline faces, 30% off:
#: at 1e-3 a tenth of the target refused every move and kept 4-degree triangles).
STUCK_SLACK = 0.1
STUCK_OWN = 0.01
#: After the first round only nodes near triangles within this many degrees of the face's smallest
#: angle move (the same gains on the cylinder's caps in 60% of the time); so do they, and only those
#: triangles' edges collapse, when a pass over the whole face is not kept (``smooth_face``'s retry).
FOCUS = 3.0
#: The optimiser's budget, counted in work (:class:`~cadedge.mesh.work.Meter`, so that a model meshes the
#: same way on every run): each swap, collapse or smoothing step is charged the triangles it visits, and
#: each face :data:`FACE_WORK` for reading and judging it. It gets :data:`WORK_PER_TRIANGLE` times the
#: triangles of the faces it may improve, at least :data:`MIN_WORK` (times ``MeshJob.share`` in a split
#: job's shard, so that the shards together get what one job would). Measured with no bound (13 models,
#: 2 cores): a face's full optimisation took 22-46 units a triangle, done at 37 000-162 000 units per
#: CPU second (about 90 000; B-spline faces and many small faces the slowest), so the budget is about
#: the CPU time the job took before it (1.3e-4 to 1.9e-4 s a triangle: reading, sizes, gmsh's meshing)
#: and at least about 30 s, as the CPU-time budget it replaces. It never runs past the job's
#: ``finish_by`` on the clock (:data:`~cadedge.mesh.isolate.FINISH_SHARE` of the timeout; past the soft
#: deadline too, which only stops meshing: under load mesh_T106_V3's meshing used the soft deadline and
#: every face kept gmsh's 0.1-degree triangles). Each face (worst first) may use :data:`FACE_SHARE` of
#: what is left, or more if its triangles are a larger share of those still to improve; a face out of
#: budget keeps its last stage's result (or gmsh's).
WORK_PER_TRIANGLE = 15
MIN_WORK = 2_500_000
FACE_WORK = 3_000
FACE_SHARE = 0.5
#: Where the faces of one gmsh process (grids aside) hold more triangles than this, a first sweep gives
#: every face rounds on the nodes near its worst triangles only (:data:`FOCUS`; ``smooth_face``'s
#: ``focus_first``) before any pass over a whole face: such a pass over a plane's 80 000 triangles takes
#: about 6 s of CPU, and the budget bound first (the 1 000 mm I-beam at 1e-2, 7 such planes a process:
#: 23.6 degrees on the planes reached last; 35.1 with no budget, in 285 s against 68), where focused
#: rounds lift such a plane from 24 to 31-33 degrees in 2 s (the I-beam: 29.6-30.0 in the same time; 29.8
#: at 1e-3, where it had 20.7). On 11752.stp's 800 small gmsh faces, its optimiser bound by the clock,
#: about even (faces' smallest angles, two runs each: mean 36.5-37.1 -> 36.9-37.6, under 35 degrees
#: 191-287 -> 157, under 30 98 -> 105); a sweep of only its 71 faces of 20 000 triangles or more took
#: the whole window (under 30: 201). Smaller jobs keep the order that reaches higher angles when the
#: budget allows (a pass first, its smoothing spread over the face).
FOCUS_FIRST = 300_000


#: A face with more than this share of its triangles folded as gmsh meshed it is left to the optimiser
#: as if it had no surface normals: its folds are not the mesher's. On LLNL boxed_sphere 5% of the
#: triangles of 40 faces are folded, where their edges lie up to 0.027 off a cylinder or gmsh's surface
#: differs from the B-rep's (30% off in area); guarding against folds and undoing them there only
#: blocked the optimiser (smallest angle 27.7 -> 0.2-3.8 degrees at 1e-3). The blades' folds were
#: 1-3 of a few thousand triangles.
FOLD_TRUST = 0.01


def _area(x: np.ndarray, tri: np.ndarray) -> float:
    return float(0.5 * np.linalg.norm(_normals(x, tri), axis=1).sum())


@dataclass
class _Face:
    """One face's mesh while it is improved: coordinates, triangles (indices into them), which nodes may
    move, the parametric coordinates of the nodes (the curves' nodes' too, where gmsh finds them: they
    start the projections of points placed near them), which of them moved, and the unit surface
    normals at the nodes (zero rows where unknown: a pole) that tell a folded triangle
    (:mod:`cadedge.mesh.folds`; None where folds are not the mesher's, see :data:`FOLD_TRUST`)."""

    x: np.ndarray
    tri: np.ndarray
    movable: np.ndarray
    uv: np.ndarray
    moved: np.ndarray
    up: np.ndarray | None

    def min_angle(self) -> float:
        return float(min_angles(self.x, self.tri).min())

    def worst_angles(self) -> np.ndarray:
        """The :data:`WORST` smallest triangle angles, ascending."""
        ang = min_angles(self.x, self.tri)
        return np.sort(ang)[:WORST]

    def better_than(self, other: _Face) -> bool:
        """Its worst angles are lexicographically larger than ``other``'s (ties within 1e-6 degree): a
        stage that cannot lift a face's worst triangle (three boundary nodes) may still lift the next."""
        a, b = self.worst_angles(), other.worst_angles()
        m = min(len(a), len(b))
        differ = np.flatnonzero(np.abs(a[:m] - b[:m]) > 1e-6)
        return bool(len(differ) and a[differ[0]] > b[differ[0]])


def _improve(face: _Face, fixed: set[tuple[int, int]], project, passes: int, meter: Meter, *,
             collapse: bool = False, below: float = CLIMB_BELOW, collapse_below: float = COLLAPSE_BELOW) -> _Face:
    """``passes`` times: edge swaps, edge collapses and edge splits (with ``collapse``; see
    :mod:`cadedge.mesh.collapse` and :mod:`cadedge.mesh.corners`) and swaps again, then smoothing and the
    local search of the nodes near bad triangles. Returns a new
    :class:`_Face` (``face`` is left as it is); only nodes near triangles under ``below`` degrees move,
    and only edges of triangles under ``collapse_below`` collapse. Each step is charged to ``meter`` (the
    triangles it visits) and none starts once the meter is late."""
    x, tri, movable = face.x, face.tri, face.movable.copy()
    uv, moved = face.uv.copy(), face.moved.copy()
    up = None if face.up is None else face.up.copy()
    sign = 1.0 if up is None else orientation(up, tri, x)
    if isinstance(project, Projector):
        project.uv = uv  # the nodes' current parameters start their projections

    def normals_for(params: np.ndarray) -> np.ndarray:
        return project.normals(params) if isinstance(project, Projector) else np.zeros((len(params), 3))

    def took(params: np.ndarray | None, rows: np.ndarray) -> None:
        if params is None or not params.shape[1]:
            return
        got = ~np.isnan(params[:, 0])
        uv[rows[got]] = params[got]
        moved[rows[got]] = True
        if up is not None:  # a node moved across a ridge turns its normal
            up[rows[got]] = normals_for(params[got])

    def oriented() -> np.ndarray | None:
        return None if up is None else sign * up

    def node_normals(rows: np.ndarray | None = None) -> NodeNormals | None:
        """The oriented normals of the nodes ``rows`` (all if None), for a move to judge folds by."""
        if up is None:
            return None
        return NodeNormals(sign * (up if rows is None else up[rows]), lambda params: sign * normals_for(params))

    for k in range(passes):
        if meter.late():
            break
        meter.charge(len(tri))
        tri = flip_edges(x, tri, fixed, up=oriented())
        if collapse and (k < passes - 1 or passes == 1):  # the last pass settles the last changes
            meter.charge(2 * len(tri))
            x, tri, gone, params = collapse_edges(x, tri, movable, project, below=collapse_below,
                                                  normals=node_normals())
            took(params, np.arange(len(x)))
            if gone.any():
                movable &= ~gone
                tri = flip_edges(x, tri, fixed, up=oriented())
            x, tri, movable, new_uv = split_corner_triangles(x, tri, movable, fixed, project, normals=node_normals())
            if len(new_uv):  # new interior nodes: rows appended
                uv = np.vstack([uv, new_uv])
                moved = np.concatenate([moved, np.ones(len(new_uv), dtype=bool)])
                up = None if up is None else np.vstack([up, normals_for(new_uv)])
                if isinstance(project, Projector):
                    project.uv = uv
                tri = flip_edges(x, tri, fixed, up=oriented())
        active = _near_bad(x, tri, movable, below)
        if not active.any():
            break
        rows = np.flatnonzero(active)
        nodes, part = around(tri, active)  # the moves run on the part of the face they can change

        def project_part(points: np.ndarray, at: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return project(points, nodes[at])

        for mover in (smooth_nodes, climb_nodes):
            if meter.late():
                break
            meter.charge(len(part))
            moved_x, params = mover(x[nodes], part, active[nodes], project_part, normals=node_normals(nodes))
            x = x.copy()
            x[nodes] = moved_x
            took(params, rows)
    return _Face(x, tri, movable, uv, moved, up)


def improve_plane(points: np.ndarray, tri: np.ndarray, movable: np.ndarray, fixed: set[tuple[int, int]], *,
                  below: float = CLIMB_BELOW, passes: int = PASSES) -> tuple[np.ndarray, np.ndarray]:
    """Plane triangles ``tri`` (rows of ``points`` (n, 2)) improved as a face's are: :func:`_improve`, then
    up to :data:`STAGE_ROUNDS` - 1 rounds of it on the nodes near the worst triangles (:data:`FOCUS`)
    while they lift the worst angles (:meth:`_Face.better_than`); only the ``movable`` nodes near
    triangles under ``below`` degrees move, and no segment of ``fixed`` (sorted row pairs) is swapped.
    Returns the points and triangles, as many as given (the same boundary rows). For a grid's bands
    (:mod:`cadedge.mesh.gridded`), plane when unrolled, which the face optimiser leaves alone."""

    def project(p: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        flat = np.column_stack([p[:, :2], np.zeros(len(p))])
        return flat, flat[:, :2].copy()

    x = np.column_stack([points, np.zeros(len(points))])
    best = start = _Face(x, np.asarray(tri, dtype=np.int64), np.asarray(movable, dtype=bool).copy(),
                         x[:, :2].copy(), np.zeros(len(x), dtype=bool), None)
    for round_ in range(STAGE_ROUNDS):
        more = _improve(best, fixed, project, passes if not round_ else LATER_STAGES[-1][0], Meter(),
                        below=below if not round_ else min(below, best.min_angle() + FOCUS))
        if not more.better_than(best):
            break
        best = more
    return (best.x[:, :2], best.tri) if best is not start else (points, tri)


def _start(surface: int, mesh) -> _Face:
    """The :class:`_Face` of gmsh surface ``surface`` as gmsh holds it (``mesh``, its
    :class:`~cadedge.mesh.facemesh.FaceMesh`), no node moved yet; its nodes' surface normals left out
    (no fold guarded against or undone) where more than :data:`FOLD_TRUST` of its triangles are folded."""
    uv = node_params(surface, mesh.x, mesh.uv, mesh.tags)
    up = normals_at(surface, uv)
    up[mesh.pinned] = 0.0  # on a fold (:func:`~cadedge.mesh.facemesh.crease_nodes`): neither flank's normal
    if folded(mesh.x, mesh.tri, reference_normals(up, mesh.tri, orientation(up, mesh.tri, mesh.x))).mean() > FOLD_TRUST:
        up = None
    return _Face(mesh.x, mesh.tri, mesh.movable, uv, np.zeros(len(mesh.tags), dtype=bool), up)


def _unfold(face: _Face, project: Projector, fixed: set[tuple[int, int]]) -> _Face:
    """``face`` with its folded triangles (:mod:`cadedge.mesh.folds`) unfolded where moving its interior
    nodes can (:func:`~cadedge.mesh.moves.untangle_nodes`), then where swapping a fold's edges can
    (:func:`~cadedge.mesh.moves.flip_folds`, never a segment of ``fixed``); ``face`` itself if none is
    folded or nothing could be done."""
    if face.up is None:
        return face
    sign = orientation(face.up, face.tri, face.x)
    if not folded(face.x, face.tri, reference_normals(face.up, face.tri, sign)).any():
        return face
    out = _untangle(face, project, sign)
    if folded(out.x, out.tri, reference_normals(out.up, out.tri, sign)).any():
        tri = flip_folds(out.x, out.tri, fixed, sign * out.up)
        if not np.array_equal(tri, out.tri):
            out = _untangle(dataclasses.replace(out, tri=tri), project, sign)
    return out


def _untangle(face: _Face, project: Projector, sign: float) -> _Face:
    """``face`` after :func:`~cadedge.mesh.moves.untangle_nodes` (orientation ``sign``), or ``face``
    itself if no node moved."""
    project.uv = face.uv.copy()
    x, params = untangle_nodes(face.x, face.tri, face.movable, project,
                               reference_normals(face.up, face.tri, sign))
    if params is None:
        return face
    rows = np.flatnonzero(face.movable)
    got = ~np.isnan(params[:, 0])
    moved, uv, up = face.moved.copy(), face.uv.copy(), face.up.copy()
    uv[rows[got]] = params[got]
    moved[rows[got]] = True
    up[rows[got]] = project.normals(params[got])
    return _Face(x, face.tri, face.movable, uv, moved, up)


def smooth_face(surface: int, *, brep_area: float = 0.0, target: float | None = None, slack: float = 0.0,
                own_slack: float = 0.0, passes: int = PASSES, rounds: int = STAGE_ROUNDS,
                focus_first: bool = False, meter: Meter | None = None) -> bool:
    """Improve one meshed gmsh surface: ``passes`` times edge swaps (:func:`flip_edges`, never a curve
    segment) then smoothing of its interior nodes (:func:`smooth_nodes`, :func:`climb_nodes`); then the
    :data:`LATER_STAGES` (with edge collapses while its smallest angle is under
    :data:`~cadedge.mesh.collapse.COLLAPSE_BELOW`, then without), each kept only if it improves the
    face (:meth:`_Face.better_than`), repeated for up to ``rounds`` rounds while a round improves it
    (``passes=0``: the later stages only). With ``focus_first`` (:data:`FOCUS_FIRST`), up to
    :data:`STAGE_ROUNDS` passes on the nodes near its worst triangles (:data:`FOCUS`) come first, while
    they improve it, and the passes over the whole face are kept after them only if they improve it
    too. A result replaces the face's mesh only if its smallest angle does not fall and its area deficit
    (against ``brep_area``) stays within ``target`` or does not grow (by more than ``slack`` or
    ``own_slack`` times its deficit as gmsh meshed it); a face
    that lost nodes is written again (its interior nodes and triangles; its curves'
    nodes stay). Its work is charged to ``meter`` (:class:`~cadedge.mesh.work.Meter`, none: unbounded): no
    pass or move starts once it is late. Returns whether the face's mesh changed."""
    from .facemesh import read_face

    mesh = read_face(surface)
    if mesh is None:
        return False
    x0, tri0, fixed = mesh.x, mesh.tri, mesh.fixed
    start = _start(surface, mesh)
    project = Projector(surface)
    meter = meter or Meter()
    meter.charge(FACE_WORK)
    late = meter.late

    def fits(face: _Face) -> bool:
        """Its smallest angle is not below gmsh's (once unfolded) and its area deficit within the target
        (or no worse)."""
        if face.min_angle() < base.min_angle():
            return False
        if target is not None and brep_area > 0:
            d0, d1 = abs(1.0 - _area(x0, tri0) / brep_area), abs(1.0 - _area(face.x, face.tri) / brep_area)
            return d1 <= max(target, d0) + max(slack, own_slack * d0)
        return True

    def attempt(face: _Face, n: int, collapse: bool = False, below: float = CLIMB_BELOW) -> _Face:
        """``_improve``; if the result does not fit, again on only the nodes near the face's worst
        triangles (:data:`FOCUS`): the propeller's blade face at 1e-2 sat at 9.6e-3 as meshed, every
        pass over the whole face took it past the target (1.2e-2), and its 3.9-degree triangle stayed,
        where one collapse beside it gives 15.5 degrees."""
        more = _improve(face, fixed, project, n, meter, collapse=collapse, below=below)
        focus = face.min_angle() + FOCUS
        if not fits(more) and below > focus and not late():
            more = _improve(face, fixed, project, n, meter, collapse=collapse, below=focus, collapse_below=focus)
        return more

    base = best = _unfold(start, project, fixed)
    for _ in range(STAGE_ROUNDS if focus_first else 0):  # its worst triangles first, where time is short
        if late():
            break
        more = attempt(best, 1, below=best.min_angle() + FOCUS)
        if not (more.better_than(best) and fits(more)):
            break
        best = more
    if passes:
        more = attempt(best, passes)
        if fits(more) and (best is base or more.better_than(best)):
            best = more
    for round_ in range(rounds):
        before = best
        for n, collapse in LATER_STAGES:
            if late() or best.min_angle() >= (COLLAPSE_BELOW if collapse else CLIMB_BELOW):
                continue
            below = min(CLIMB_BELOW, best.min_angle() + FOCUS) if round_ or not passes else CLIMB_BELOW
            more = attempt(best, n, collapse, below)
            if more.better_than(best) and fits(more):
                best = more
        if best is before:
            break
    return best is not start and _write(surface, mesh, best)


def _write(surface: int, mesh, face: _Face) -> bool:
    """Hand ``face`` (improved from ``mesh``, the surface's :class:`~cadedge.mesh.facemesh.FaceMesh`) back
    to gmsh: the moved nodes, or the whole interior if nodes were removed or added. Returns whether
    anything changed."""
    import gmsh

    from .facemesh import write_interior

    x, tri, movable, uv, moved = face.x, face.tri, face.movable, face.uv, face.moved
    tags = mesh.tags
    if len(tri) != len(mesh.tri) or len(x) != len(tags):  # nodes removed or added: the interior written anew
        write_interior(surface, mesh, x, tri, movable, uv)
        return True
    changed = False
    for i in np.flatnonzero(moved & movable).tolist():
        gmsh.model.mesh.setNode(int(tags[i]), x[i].tolist(), uv[i].tolist())
        changed = True
    if not np.array_equal(tri, mesh.tri):
        gmsh.model.mesh.removeElements(2, surface)
        gmsh.model.mesh.addElementsByType(surface, 2, mesh.el_tags.tolist(), tags[tri].ravel().tolist())
        changed = True
    return changed


def unfold_face(surface: int) -> bool:
    """Unfold the folded triangles of one meshed gmsh surface (:func:`_unfold`), before its area is
    measured (:func:`cadedge.mesh.areas.unfolded_areas`). Returns whether its mesh changed."""
    return _unfold_written(surface)[0]


def unfolds(surface: int) -> bool:
    """Whether one meshed gmsh surface holds no folded triangle once its folds are undone where moving its
    interior nodes or swapping the folds' edges can (:func:`_unfold`, written back): how a Delaunay-based
    mesh is judged (:func:`cadedge.mesh.generate.keep_or_adapt`). False where more than :data:`FOLD_TRUST`
    of its triangles are folded (not the mesher's folds: not undone here)."""
    return _unfold_written(surface)[1]


def _unfold_written(surface: int) -> tuple[bool, bool]:
    """Unfold one meshed gmsh surface (:func:`_unfold`) and hand the result to gmsh: whether its mesh
    changed, and whether it is left with no folded triangle (False where its folds are not the mesher's,
    see :data:`FOLD_TRUST`)."""
    from .facemesh import read_face

    mesh = read_face(surface)
    if mesh is None:
        return False, True
    start = _start(surface, mesh)
    if start.up is None:
        return False, False
    base = _unfold(start, Projector(surface), mesh.fixed)
    changed = base is not start and _write(surface, mesh, base)
    sign = orientation(base.up, base.tri, base.x)
    return changed, not folded(base.x, base.tri, reference_normals(base.up, base.tri, sign)).any()


def _face_min_angle(surface: int) -> float:
    """The smallest triangle angle of one meshed gmsh surface (180 for a face without triangles)."""
    from .facemesh import triangle_min_angles

    angles = triangle_min_angles(surface)
    return 180.0 if angles is None else float(angles.min())


def after_generate(ctx) -> None:
    """Hook (after the area-target pass): improve every meshed face (:func:`smooth_face`), worst smallest
    angle first, within the optimiser's budget (:data:`WORK_PER_TRIANGLE`, :data:`MIN_WORK`, in work
    done, and ``ctx.job.finish_by`` on the clock; a large model may get part of the faces: the worst go
    first). Each face it changed is delivered at once (``ctx.deliver``). A first sweep gives each
    face one round of the later stages, a second the rest of :data:`STAGE_ROUNDS` to the faces it
    changed that set the mesh's smallest angle (within :data:`SWEEP_MARGIN`, under
    :data:`~cadedge.mesh.collapse.COLLAPSE_BELOW`), so one large face does not take the time of the
    others; a face with a sliver (under :data:`~cadedge.mesh.quality.SLIVER_DEG`) gets all its rounds in
    the first sweep, before the budget goes to better faces (Voron 0's Manta DIN mount: the first sweep
    over a shard's 194 faces spent it, and three faces kept 4.5-degree triangles one more round would
    have merged away); where the faces hold over :data:`FOCUS_FIRST` triangles, a sweep of focused rounds on every
    face's worst triangles comes before them. The faces whose mesh changed land in ``ctx.smoothed``."""
    import gmsh

    from .facemesh import element_corners

    opts = ctx.job.options.get("fidelity") or {}
    areas = np.asarray(opts.get("brep_areas", []), dtype=float)
    target = opts.get("surface_ald")
    face_of = ctx.emap.face_of_surface
    stuck = set((getattr(ctx, "fidelity", None) or {}).get("stuck", []))
    kept: list[int] = []
    deliver = ctx.deliver or (lambda dim, tag, corners: None)
    say = ctx.progress or (lambda line: None)
    # a grid's right triangles are as its boundary nodes set them (cadedge.mesh.gridded): nothing to move
    todo = [s for s, outcome in sorted(ctx.outcomes.items()) if outcome.ok and outcome.strategy != GRID]
    # each face's triangles and smallest angle, kept up to date as faces change
    size = {s: len(gmsh.model.mesh.getElementsByType(2, s)[0]) for s in todo}
    worst = {s: _face_min_angle(s) for s in todo}
    many = sum(size.values()) > FOCUS_FIRST
    # on the clock, finish_by; the soft deadline (ctx.job.deadline) bounds meshing, not this
    meter = Meter(max(MIN_WORK * ctx.job.share,  # a shard's share of it (cadedge.mesh.shards)
                      WORK_PER_TRIANGLE * sum(size.values())), ctx.job.finish_by)
    # (passes, rounds, focused rounds first): with many triangles, a sweep of every face's worst ones first
    for passes, rounds, focus_first in [(0, 0, True)] * many + [(PASSES, 1, False), (0, STAGE_ROUNDS - 1, False)]:
        todo = [s for s in sorted(todo, key=lambda s: worst[s]) if worst[s] < CLIMB_BELOW]
        left = sum(size[s] for s in todo)
        tried = []
        for s in todo:  # worst smallest angle first; faces without a triangle worth moving are left alone
            if meter.late():
                break  # out of the optimiser's budget: the faces left keep their triangles
            tried.append(s)
            share = max(FACE_SHARE, size[s] / left if left > 0 else 1.0)
            left -= size[s]
            f = face_of.get(s, s)
            area = float(areas[f - 1]) if 1 <= f <= len(areas) else 0.0
            # a face whose mesh and B-rep areas disagree (not converging) keeps its deficit within a slack
            slack = STUCK_SLACK * target if target is not None and f in stuck else 0.0
            say(f"optimise {f}")
            if smooth_face(s, brep_area=area, target=target, slack=slack, own_slack=STUCK_OWN if slack else 0.0,
                           passes=passes, rounds=STAGE_ROUNDS if passes and worst[s] < SLIVER_DEG else rounds,
                           focus_first=focus_first,
                           meter=(part := meter.part(share))):
                kept.append(f)
                size[s] = ctx.outcomes[s].triangles = len(gmsh.model.mesh.getElementsByType(2, s)[0])
                worst[s] = _face_min_angle(s)
                deliver(2, f, element_corners(2, s))  # a child killed at the hard timeout hands this face over
            meter.settle(part)
        if passes:  # the later rounds go to the faces that set the mesh's smallest angle
            floor = min((_face_min_angle(s) for s, o in ctx.outcomes.items() if o.ok), default=180.0)
            todo = [s for s in tried if worst[s] < min(floor + SWEEP_MARGIN, COLLAPSE_BELOW)]
    ctx.smoothed = sorted(set(kept))
