"""Run gmsh's surface meshers face by face, retrying failed faces with other strategies.

Every surface is meshed on its own (``Mesh.MeshOnlyVisible`` with only that surface visible), so one face
that gmsh cannot mesh, or that hangs or crashes it, is known by name. The first attempt meshes faces in
batches of 1, 2, 4, ... up to :data:`BATCH_FACES` faces, fewer where faces take long (one ``generate``
call each: every call re-walks the whole model's mesh, so one call per face grows quadratically with the
model, 15-25% of the time on a 192-face model); a batch that hangs or crashes gmsh is done again face by
face (in the mesh child, :data:`TRACE`, gmsh prints its progress through a batch, so the watchdog knows
the face it was on). A face passes when it carries
triangles whose edges on its boundary curves are exactly the curve segments, each used as often as the
curve bounds the face (seams twice), and whose other edges are shared by two triangles. A face that
fails is cleared and retried through :data:`~cadedge.mesh.strategies.STRATEGIES`: other 2-D algorithms, finer and coarser local
sizes, then its boundary segments split in two (faces sharing those curves are meshed again on the split
curves), then its curves meshed by gmsh itself instead of imposed, at their edge grids' spacings (likewise for
the faces sharing them). Faces that fail every strategy are reported with gmsh's own messages.
"""

from __future__ import annotations

import dataclasses
import re
import time
from typing import Callable

import gmsh
import numpy as np

from .budget import filling_size
from .curve_watch import GMSH_DELETED, MESHED_AGAIN, CurveWatch
from .facemesh import element_corners
from .gmsh_model import surface_curve_uses
from .outcomes import FaceOutcome
from .quality import flat_triangles
from .sizes import curves_from_spacings
from .strategies import STRATEGIES, Strategy, face_order


def surface_ok(surface: int) -> bool:
    """Does the surface carry triangles whose boundary is exactly its (imposed or meshed) curve segments,
    none of them flat (:func:`~cadedge.mesh.quality.flat_triangles`)?

    Edges are compared as integer keys ``a * big + b`` (``a < b`` node tags), with counts from one
    ``np.unique`` each: a dictionary per edge took 3.9 of the 9.5 s its 462 calls cost on a plate with
    225 holes at 1e-3."""
    _, tri_nodes = gmsh.model.mesh.getElementsByType(2, surface)
    if len(tri_nodes) == 0:
        return False
    tri = np.asarray(tri_nodes, dtype=np.int64).reshape(-1, 3)
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    segs, uses = [np.zeros((0, 2), dtype=np.int64)], [np.zeros(0)]
    for curve, n in surface_curve_uses(surface).items():
        _, seg = gmsh.model.mesh.getElementsByType(1, curve)
        segs.append(np.sort(np.asarray(seg, dtype=np.int64).reshape(-1, 2), axis=1))
        uses.append(np.full(len(segs[-1]), float(n)))
    seg = np.vstack(segs)
    big = int(max(edges.max(), seg.max(initial=0))) + 1
    got, counts = np.unique(edges[:, 0] * big + edges[:, 1], return_counts=True)
    wanted, inverse = np.unique(seg[:, 0] * big + seg[:, 1], return_inverse=True)
    expected = np.bincount(inverse.ravel(), weights=np.concatenate(uses), minlength=len(wanted))
    at = np.minimum(np.searchsorted(got, wanted), max(len(got) - 1, 0))
    found = np.where(got[at] == wanted, counts[at], 0)
    if np.any(found != expected) or not np.all(counts[~np.isin(got, wanted)] == 2):
        return False
    corners = element_corners(2, surface)
    return not (len(corners) and flat_triangles(corners.reshape(-1, 3), np.arange(3 * len(corners))).any())


def _reason(surface: int, log: list[str], exc: str | None, *, alone: bool = True) -> str:
    """gmsh's messages about ``surface``; when it was meshed ``alone``, else its last error."""
    pat = re.compile(rf"\b(surface|face)\s+{surface}\b", re.IGNORECASE)
    msgs = [m for m in log if pat.search(m) and ("rror" in m or "arning" in m)]
    if not msgs and alone:
        msgs = [m for m in log if "rror" in m][-1:] or ([exc] if exc else [])
    text = "; ".join(dict.fromkeys(m.strip() for m in msgs))
    return text or "no triangles, or triangles that do not match the face's boundary curves, or flat ones"


def _attempt(surface: int, strategy: Strategy) -> str | None:
    """Mesh one (empty) surface with ``strategy``; None if it passed, else gmsh's reason (surface cleared)."""
    return _attempt_many([surface], strategy)[surface]


def _clear_log() -> None:
    """Drop gmsh's logged messages (``gmsh.logger.get`` returns every message since the logger started:
    reading it per attempt grew quadratically and mixed other faces' errors into a face's reason)."""
    gmsh.logger.stop()
    gmsh.logger.start()


#: Percentile of a face's sampled curvatures taken as the one curvature of :func:`uniform_curvature_size`
#: (spikes at poles and near-singular points of spline surfaces are left out).
CURVATURE_PERCENTILE = 95.0


def uniform_curvature_size(surface: int, per_circle: float) -> float | None:
    """One size for the whole face: ``2 pi / (per_circle * k)`` with ``k`` a high percentile of the largest
    principal curvature sampled on a grid of the surface's parameters
    (:func:`~cadedge.mesh.interior.face_curvatures`), no smaller than the size giving
    :data:`~cadedge.mesh.budget.MAX_FACE_TRIANGLES` on the face's area. None when the face is flat or gmsh
    cannot sample it."""
    from .interior import face_curvatures

    found = face_curvatures(surface)
    if found is None or per_circle <= 0:
        return None
    k = float(np.percentile(found[0], CURVATURE_PERCENTILE))
    if not k > 0:
        return None
    return max(2.0 * np.pi / (per_circle * k), float(filling_size(np.sum(found[1]))))


#: A face with at least this many boundary nodes gets gmsh's older initial triangulation of them
#: (``Mesh.OldInitialDelaunay2D``, divide and conquer), which all three 2-D algorithms start from: the
#: newer one's time grows with their square. A 9.2 x 400 rectangle, 0.06 apart on its long sides
#: (13 638 nodes), took 24 s in Frontal-Delaunay with the newer, 6.7 s with the older; 6 800 nodes
#: 4.5 s and 2.2 s, 3 400 nodes 1.4 s and 1.1 s. The flat side of a box 1 000 long with 0.4 mm fillets
#: has 33 000 at ALD 1e-3 and took 244 s. Faces on a periodic surface (a cylinder, also a fillet's
#: quarter of one) go another way in gmsh, which this option does not change. Below it faces keep
#: gmsh's default.
OLD_INITIAL_FROM = 2_000


def boundary_nodes(surface: int) -> int:
    """Mesh nodes on gmsh ``surface``'s boundary curves (a curve's end nodes once per curve)."""
    return sum(len(gmsh.model.mesh.getNodes(1, c, includeBoundary=True)[0]) for c in surface_curve_uses(surface))


def old_initial(surfaces: list[int]) -> int:
    """``Mesh.OldInitialDelaunay2D`` for a gmsh call meshing ``surfaces``: 1 when one of them has at least
    :data:`OLD_INITIAL_FROM` boundary nodes."""
    return int(any(boundary_nodes(s) >= OLD_INITIAL_FROM for s in surfaces))


def _attempt_many(surfaces: list[int], strategy: Strategy) -> dict[int, str | None]:
    """Mesh (empty) ``surfaces`` in one gmsh call with ``strategy``; per surface None if it passed, else
    gmsh's reason (the surface is then cleared). A ``uniform`` strategy takes its size from the first
    surface (it is tried on one face at a time). Faces with many boundary nodes start from gmsh's older
    initial triangulation (:data:`OLD_INITIAL_FROM`)."""
    if strategy.unrolled:
        return {s: _unrolled(s, strategy) for s in surfaces}
    gmsh.option.setNumber("Mesh.Algorithm", strategy.algorithm)
    gmsh.option.setNumber("Mesh.OldInitialDelaunay2D", old_initial(surfaces))
    gmsh.option.setNumber("Mesh.MeshSizeFactor", strategy.size_factor)
    restore = {}
    if strategy.uniform:
        per_circle = gmsh.option.getNumber("Mesh.MeshSizeFromCurvature")
        h = uniform_curvature_size(surfaces[0], per_circle) if per_circle > 0 else None
        restore = {o: gmsh.option.getNumber(o) for o in ("Mesh.MeshSizeFromCurvature", "Mesh.MeshSizeMax")}
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        if h is not None:
            gmsh.option.setNumber("Mesh.MeshSizeMax", max(min(h, restore["Mesh.MeshSizeMax"]),
                                                          gmsh.option.getNumber("Mesh.MeshSizeMin")))
    switch = strategy.algorithm in DELAUNAY_BASED and gmsh.option.getNumber("Mesh.AlgorithmSwitchOnFailure") == 1
    if switch:  # gmsh's own switch judges a face by a single fold: judged here instead (keep_or_adapt)
        restore["Mesh.AlgorithmSwitchOnFailure"] = 1
        gmsh.option.setNumber("Mesh.AlgorithmSwitchOnFailure", 0)
    visible = [(2, s) for s in surfaces]
    gmsh.model.setVisibility(visible, 1)
    _clear_log()
    exc = None
    trace = TRACE and len(surfaces) > 1
    try:
        if trace:
            gmsh.option.setNumber("General.Terminal", 1)
        gmsh.model.mesh.generate(2)
    except Exception as err:  # gmsh raises a bare Exception with its last error message
        exc = str(err)
    finally:
        if trace:
            gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.setVisibility(visible, 0)
        gmsh.option.setNumber("Mesh.MeshSizeFactor", 1.0)
        gmsh.option.setNumber("Mesh.OldInitialDelaunay2D", 0)
        for o, value in restore.items():
            gmsh.option.setNumber(o, value)
    log = gmsh.logger.get()
    _clear_log()
    out: dict[int, str | None] = {}
    for s in surfaces:
        if surface_ok(s):
            out[s] = None
        else:
            clear([(2, s)])
            out[s] = _reason(s, log, exc, alone=len(surfaces) == 1)
    if switch:
        out.update(keep_or_adapt([s for s in surfaces if out[s] is None], strategy))
    return out


#: In the mesh child (set by :func:`cadedge.mesh.worker.main`, whose standard output is the job's trace
#: file): gmsh prints its messages there while it meshes a batch of faces ("Meshing surface N ..."), so a
#: batch that hangs or crashes is pinned on the face gmsh was meshing (:mod:`cadedge.mesh.isolate`).
TRACE = False


#: gmsh's Delaunay-based 2-D algorithms (Delaunay, Frontal-Delaunay): with ``Mesh.AlgorithmSwitchOnFailure``
#: gmsh throws such a mesh away when a single triangle of it faces against the surface (``isMeshValid`` in
#: its ``meshGFace.cpp``) and meshes the face again by MeshAdapt.
DELAUNAY_BASED = (5, 6)


#: A Delaunay-based mesh left with folds is meshed again by MeshAdapt only where it holds at most this
#: share of the face's triangle budget (:data:`cadedge.mesh.budget.MAX_FACE_TRIANGLES`: 32 000 triangles
#: at the default bound on an attempt). MeshAdapt remakes a large face far slower than Frontal-Delaunay
#: makes it: a spring's coil face (118 733 triangles in 5.7 s at 1e-3, its folds beside an edge 0.015
#: off the face, 100 times its tolerance) was still in MeshAdapt's passes after 67 s, and every strategy
#: that ended there was stopped as hung. A larger face keeps its Delaunay mesh; the report counts its
#: folded triangles.
ADAPT_SHARE = 0.08


def keep_or_adapt(surfaces: list[int], strategy: Strategy) -> dict[int, str | None]:
    """Delaunay-based meshes of ``surfaces`` (by ``strategy``, made with gmsh's switch off) judged as gmsh's
    switch would judge them, but once their folds are undone (:func:`~cadedge.mesh.optimize.unfolds`): a
    face left with a folded triangle is meshed again by MeshAdapt at the same sizes, as gmsh would, if it
    is small enough for MeshAdapt (:data:`ADAPT_SHARE`). A single fold near a pole (the half ellipsoids
    of gmsh's ellipses.brep: one triangle of 11 621, beside the pole of a rational B-spline surface) sent
    every such face to MeshAdapt, 0.5 -> 13 s a face, and at ALD 1e-3 a chunk of seven of them past the
    60 s of an attempt; its fold is undone in a few moves. Per surface, None if it passed, else the
    reason (the surface is then cleared)."""
    from . import budget
    from .optimize import unfolds

    most = ADAPT_SHARE * budget.MAX_FACE_TRIANGLES
    again = [s for s in surfaces if not unfolds(s)
             and len(gmsh.model.mesh.getElementsByType(2, s)[0]) <= most]
    if not again:
        return {}
    clear([(2, s) for s in again])
    return _attempt_many(again, dataclasses.replace(strategy, algorithm=1))


def _unrolled(surface: int, strategy: Strategy) -> str | None:
    """Mesh (empty) ``surface`` laid flat: a cone with its apex on its boundary or a face of linear
    extrusion, as ``strategy.unrolled`` says; None if it passed, else why not (the surface is then
    cleared)."""
    if strategy.unrolled == "grid":
        from .gridded import mesh_grid

        reason = mesh_grid(surface)
    elif strategy.unrolled == "parameters":
        from .parametric import mesh_parametric

        reason = mesh_parametric(surface, strategy.algorithm)
    elif strategy.unrolled == "cone":
        from .developed import cone_of, mesh_unrolled

        cone = cone_of(surface)
        reason = "not a cone with its apex on its boundary" if cone is None else mesh_unrolled(
            surface, cone, strategy.algorithm)
    else:
        from .extruded import mesh_unrolled

        reason = mesh_unrolled(surface, strategy.algorithm)
    if reason is None and not surface_ok(surface):
        reason = "unrolled: triangles that do not match the face's boundary curves"
    if reason is not None:
        clear([(2, surface)])
    return reason


def clear(dim_tags: list[tuple[int, int]]) -> None:
    """Delete the mesh of ``dim_tags``; nothing for an empty list (``gmsh.model.mesh.clear([])`` deletes the
    whole model's mesh, imposed curve grids included: on mesh_T106_V3 a face retried on curves gmsh had
    already meshed once cleared every curve, and every face then failed with no boundary nodes)."""
    if dim_tags:
        gmsh.model.mesh.clear(dim_tags)


def curve_chain(curve: int) -> tuple[np.ndarray, np.ndarray]:
    """Node tags of a curve's 1-D mesh from its first to its last node, and their gmsh parameters."""
    _, seg = gmsh.model.mesh.getElementsByType(1, curve)
    seg = np.asarray(seg, dtype=np.int64).reshape(-1, 2)
    nxt = dict(zip(seg[:, 0].tolist(), seg[:, 1].tolist()))
    start = (set(nxt) - set(seg[:, 1].tolist()) or {int(seg[0, 0])}).pop()  # a closed curve: any start
    chain = [start]
    while len(chain) <= len(seg):
        chain.append(nxt[chain[-1]])
    tags, _, params = gmsh.model.mesh.getNodes(1, curve, includeBoundary=False, returnParametricCoord=True)
    param_of = dict(zip(np.asarray(tags, dtype=np.int64).tolist(), np.asarray(params, dtype=float).tolist()))
    lo, hi = (float(b[0]) for b in gmsh.model.getParametrizationBounds(1, curve))
    u = np.array([param_of.get(t, np.nan) for t in chain])
    u[0], u[-1] = lo, hi  # end nodes sit on point entities; chains run in gmsh's increasing parameter
    return np.asarray(chain, dtype=np.int64), u


def split_curves(curves: list[int]) -> list[int]:
    """Split every segment of ``curves`` in two at its parameter midpoint (on gmsh's curve).

    The faces using these curves are cleared first (their triangles reference the old segments); returns
    those faces so they can be meshed again. Curves without a 1-D mesh, or with a chain that is not
    monotonic in gmsh's parameter, are left alone.
    """
    touched: set[int] = set()
    for c in curves:
        _, seg = gmsh.model.mesh.getElementsByType(1, c)
        if len(seg) == 0:
            continue
        chain, u = curve_chain(c)
        if not np.all(np.isfinite(u)) or not np.all(np.diff(u) > 0):
            continue
        users = [int(s) for s in gmsh.model.getAdjacencies(1, c)[0]]
        clear([(2, s) for s in users])
        touched.update(users)
        mid_u = 0.5 * (u[:-1] + u[1:])
        mid_x = np.asarray(gmsh.model.getValue(1, c, mid_u.tolist()), dtype=float).reshape(-1, 3)
        inner_tags = chain[1:-1]
        tags, coords, _ = gmsh.model.mesh.getNodes(1, c, includeBoundary=False)
        x_of = dict(zip(np.asarray(tags, dtype=np.int64).tolist(), np.asarray(coords).reshape(-1, 3)))
        inner_x = np.array([x_of[t] for t in inner_tags.tolist()]).reshape(-1, 3)
        clear([(1, c)])
        first = int(gmsh.model.mesh.getMaxNodeTag()) + 1
        new_tags = np.arange(first, first + len(mid_u), dtype=np.int64)
        n_in = len(inner_tags)
        all_tags = np.empty(n_in + len(new_tags), dtype=np.int64)
        all_tags[1::2], all_tags[0::2] = inner_tags, new_tags
        all_x = np.empty((len(all_tags), 3))
        all_x[1::2], all_x[0::2] = inner_x, mid_x
        all_u = np.empty(len(all_tags))
        all_u[1::2], all_u[0::2] = u[1:-1], mid_u
        gmsh.model.mesh.addNodes(1, c, all_tags.tolist(), all_x.ravel().tolist(), all_u.tolist())
        full = np.concatenate([[chain[0]], all_tags, [chain[-1]]])
        first_el = int(gmsh.model.mesh.getMaxElementTag()) + 1
        conn = np.column_stack([full[:-1], full[1:]]).ravel()
        gmsh.model.mesh.addElementsByType(c, 1, list(range(first_el, first_el + len(full) - 1)), conn.tolist())
    return sorted(touched)


def curve_surfaces(curves: list[int]) -> set[int]:
    """The gmsh surfaces that use any of ``curves``."""
    return {int(s) for c in curves for s in gmsh.model.getAdjacencies(1, c)[0]}


def remesh_curves(curves: list[int]) -> list[int]:
    """Replace the 1-D mesh of ``curves`` by gmsh's own, from the sizes set on them alone
    (:func:`~cadedge.mesh.sizes.curves_from_spacings`; the worker sets their edge grids' spacings: by the
    boundary size field alone, the cylinder fixture's circle edge of 41 segments at ALD 1e-3 got 10, and
    its disk face missed its area by 6.3% instead of 0.17%). The faces using them are cleared first and
    returned, to be meshed again, with every other face whose mesh gmsh's 1-D step wiped (``generate(1)``
    clears all 2-D meshes, visible or not)."""
    if not curves:  # all of them replaced already (generate(1) would still wipe every face's mesh)
        return []
    touched = curve_surfaces(curves)
    meshed = {t for _, t in gmsh.model.getEntities(2) if len(gmsh.model.mesh.getElementsByType(2, t)[0])}
    clear([(2, s) for s in sorted(touched)])
    clear([(1, c) for c in curves])
    visible = [(1, c) for c in curves]
    gmsh.model.setVisibility(visible, 1)
    try:
        with curves_from_spacings():
            gmsh.model.mesh.generate(1)
    except Exception:  # gmsh's bare Exception: the faces' own checks will tell
        pass
    finally:
        gmsh.model.setVisibility(visible, 0)
    wiped = {t for t in meshed if not len(gmsh.model.mesh.getElementsByType(2, t)[0])}
    return sorted(touched | wiped)


#: Faces meshed in one gmsh call on the first attempt (see the module doc); a chunk must finish within the
#: watchdog's time for one attempt.
BATCH_FACES = 24
#: A chunk is planned to take at most this share of the watchdog's bound on one attempt, at the CPU time
#: per face the chunk before it took: sphere_grooves at ALD 1e-3 (tori of 190k-240k triangles each,
#: 17 s of CPU a face) had 4 of them in one chunk, stopped as hung at 60 s and meshed again one by one.
BATCH_SHARE = 0.25
#: gmsh options a ``prepare`` hook may set per face: faces share a gmsh call only when these agree.
FACE_OPTIONS = ("Mesh.MeshSizeFromCurvature", "Mesh.MeshSizeMin", "Mesh.MeshSizeMax", "Mesh.MeshSizeFactor",
                "Mesh.AlgorithmSwitchOnFailure")


def _chunk_size(last: int, per_face: float, bound: float | None) -> int:
    """The next chunk's size after one of ``last`` faces (0: none yet) that took ``per_face`` seconds of CPU
    a face: 1, 2, 4, ... then :data:`BATCH_FACES` (a chunk stopped as hung loses the time of all its faces,
    so the first chunks are small: on mesh_T106_V3 in sizes mode at ALD 1e-3, face 1 alone takes about 50 s
    of CPU; the 8 faces in one chunk were stopped at the bound of one attempt, and meshed one by one after
    it only 1 face was done by the soft deadline), and no more than take :data:`BATCH_SHARE` of ``bound``
    (the watchdog's bound on one attempt) at that rate."""
    size = min(2 * last, BATCH_FACES) if last else 1
    if bound and per_face > 0:
        size = max(1, min(size, int(BATCH_SHARE * bound / per_face)))
    return size


def _mesh_batches(out: dict[int, FaceOutcome], surfaces: list[int], *,
                  batch_started: Callable[[list[int]], None], prepare: Callable[[int, int], None],
                  finished: Callable[[int, int, str | None], None], bound: float | None = None,
                  deleted: Callable[[], list[int]] = lambda: [],
                  order: Callable[[int], float] | None = None) -> set[int]:
    """The first strategy on ``surfaces`` in chunks (:func:`_chunk_size`, with the watchdog's ``bound`` on
    one attempt), one gmsh call per group of faces whose ``prepare`` leaves the same :data:`FACE_OPTIONS`;
    outcomes go into ``out``. With ``order`` (face -> a number), the faces are taken in its order (ties
    as given), so that faces likely to get the same options share chunks and calls. Returns the surfaces
    meshed in an earlier chunk whose meshes gmsh deleted (``deleted()`` after each call, which resets them
    in ``out``; see :class:`CurveWatch`)."""
    first = STRATEGIES[0]
    again: set[int] = set()
    if order is not None:
        surfaces = sorted(surfaces, key=lambda s: order(out[s].face))
    done, size, per_face = 0, 0, 0.0
    while done < len(surfaces):
        size = _chunk_size(size, per_face, bound)
        chunk = surfaces[done:done + size]
        done += len(chunk)
        cpu = time.process_time()
        batch_started([out[s].face for s in chunk])
        groups: dict[tuple[float, ...], list[int]] = {}
        for s in chunk:  # a face with many boundary nodes apart: its initial triangulation differs
            prepare(out[s].face, 0)
            key = tuple(gmsh.option.getNumber(o) for o in FACE_OPTIONS) + (old_initial([s]),)
            groups.setdefault(key, []).append(s)
        for n, group in enumerate(groups.values()):
            if n:  # the watchdog bounds each gmsh call: after a group's results it would bound nothing
                batch_started([out[s].face for s in group])
            prepare(out[group[0]].face, 0)
            for s, reason in _attempt_many(group, first).items():
                finished(out[s].face, 0, reason)
                if reason is None:
                    out[s].strategy = first.name
                else:
                    out[s].attempts.append((first.name, reason))
            again.update(deleted())
        per_face = (time.process_time() - cpu) / len(chunk)
    return again


def mesh_faces(surfaces: list[int], face_of: dict[int, int], *,
               skip: dict[int, dict[int, str]] | None = None,
               started: Callable[[int, int], None] = lambda face, strategy: None,
               finished: Callable[[int, int, str | None], None] = lambda face, strategy, reason: None,
               deadline: float | None = None, known_ok: dict[int, int] | None = None,
               own_curves: set[int] | None = None,
               batch_started: Callable[[list[int]], None] | None = None,
               prepare: Callable[[int, int], None] = lambda face, strategy: None,
               no_batch: set[int] | frozenset[int] = frozenset(),
               cleared: Callable[[list[int]], None] = lambda faces: None,
               as_gmsh_alone: frozenset[int] | set[int] = frozenset(),
               batch_bound: float | None = None,
               batch_order: Callable[[int], float] | None = None,
               watch: CurveWatch | None = None) -> dict[int, FaceOutcome]:
    """Mesh every surface on its own through :data:`~cadedge.mesh.strategies.STRATEGIES`; returns each surface's outcome.

    ``skip[face][k]`` marks strategy ``k`` as not to be tried on ``face`` (it failed, hung or crashed gmsh
    in an earlier run) with the reason to record. ``started(face, k)`` is called before each attempt and
    ``finished(face, k, reason or None)`` after it, so a watchdog outside the process knows which attempt
    was running when gmsh hung or crashed, and what an earlier run achieved. After ``deadline``
    (``time.time()``) no attempt starts, except ``known_ok[face]``, the strategy that meshed that face in
    an earlier run, and, while no face at all is meshed, the first strategy of faces never tried alone
    (so that a job whose first batch hung still delivers a mesh). ``own_curves`` collects the curves whose imposed mesh was replaced by gmsh's own.

    With ``batch_started``, the first strategy meshes faces in batches (faces in ``no_batch`` excepted):
    ``batch_started(faces)`` is called before each chunk, ``prepare(face, k)`` sets a face's options (it is
    also what ``started`` should call), ``finished`` follows each face of the batch. ``cleared(faces)`` is
    called whenever curves changed (a strategy's splits or own curve mesh, once it has meshed its face;
    gmsh's own splits, after the call), with the meshed faces cleared for it (maybe none; they are meshed
    again): until a strategy has meshed the face, its neighbours' last meshes, on the curves as they were,
    are the ones a process stopped during the attempt can hand over.
    ``batch_bound``: the watchdog's bound on one attempt (CPU seconds), which sizes the batches;
    ``batch_order(face)``: a number by which the batches take their faces, those likely to get the same
    options side by side (a face's options are known only once ``prepare`` has run, inside its batch).
    ``watch`` (a :class:`CurveWatch`, made here if not given) follows the curves gmsh splits itself; the
    faces whose meshes it deleted for that are meshed again (at most :data:`MESHED_AGAIN` times each; past
    ``deadline`` too, by the strategy that meshed them), once ``cleared`` has named them.
    Faces (ids) in ``as_gmsh_alone`` have gmsh mesh their curves as alone, from its boundary size field,
    when a strategy drops their imposed meshes; the others' follow the sizes set on the curves (their
    grids' spacings: :func:`remesh_curves`).
    """
    skip = skip or {}
    known_ok = known_ok or {}
    own_curves = set() if own_curves is None else own_curves
    gmsh.option.setNumber("Mesh.MeshOnlyEmpty", 1)
    gmsh.option.setNumber("Mesh.MeshOnlyVisible", 1)
    gmsh.model.setVisibility(gmsh.model.getEntities(), 0)
    out = {s: FaceOutcome(face=face_of.get(s, s), surface=s) for s in surfaces}
    watch = CurveWatch() if watch is None else watch
    again: dict[int, int] = {}  # surface -> times its mesh was deleted by gmsh
    replay: dict[int, int] = {}  # surface -> the strategy that meshed it before gmsh deleted its mesh
    index = {st.name: k for k, st in enumerate(STRATEGIES)}

    def deleted() -> list[int]:
        """Faces whose meshes gmsh deleted in the last call: cleared, and (but a face deleted too often)
        reset in ``out``, to be meshed again, first (and past ``deadline`` too) by the strategy that
        meshed it."""
        lost = watch.deleted([n for n, o in out.items() if o.ok])
        if lost is None:
            return []
        cleared([out[n].face for n in lost])
        for n in lost:
            again[n] = again.get(n, 0) + 1
            k = replay[n] = index.get(out[n].strategy, 0)
            order[n] = [k] + [j for j in order[n] if j != k]
            out[n] = FaceOutcome(face=out[n].face, surface=n)
            if again[n] > MESHED_AGAIN:
                out[n].attempts.append(("meshing", GMSH_DELETED))
        return [n for n in lost if again[n] <= MESHED_AGAIN]

    order = {s: face_order(s) for s in surfaces}
    split_done: set[int] = set()
    # faces meshed as grids go first (a second for a million triangles: cadedge.mesh.gridded; after the
    # batches, the I-beam's twelve fillets were left out of time); faces with attempts barred (they hung,
    # crashed or failed in an earlier run) go last: the others are meshed before the time runs out
    quick = {s for s in surfaces if STRATEGIES[order[s][0]].unrolled == "grid"}
    queue = sorted(surfaces, key=lambda s: (face_of.get(s, s) in skip and face_of.get(s, s) not in known_ok,
                                            s not in quick))
    late = deadline is not None and time.time() > deadline
    batched = [s for s in queue if batch_started is not None and out[s].face not in no_batch
               and order[s][0] == 0
               and 0 not in skip.get(out[s].face, {}) and known_ok.get(out[s].face, 0) == 0
               and (not late or out[s].face in known_ok)]
    try:
        tried_first: set[int] = set()
        while queue:
            s = queue.pop(0)
            if batched and s not in quick:  # the grids are done: the first strategy's batches
                redo = _mesh_batches(out, batched, batch_started=batch_started, prepare=prepare,
                                     finished=finished, bound=batch_bound, deleted=deleted, order=batch_order)
                tried_first, batched = set(batched) - redo, []
                queue += sorted(n for n in redo if n not in queue)
            rec = out[s]
            if rec.ok:
                continue
            for k in order[s]:
                strategy = STRATEGIES[k]
                if k == 0 and s in tried_first:
                    continue  # failed in its batch: recorded there
                if k in skip.get(rec.face, {}):
                    rec.attempts.append((strategy.name, skip[rec.face][k]))
                    continue
                rescue = k == 0 and rec.face not in skip and not known_ok and not any(o.ok for o in out.values())
                if deadline is not None and time.time() > deadline and known_ok.get(rec.face) != k \
                        and replay.get(s) != k and not rescue:
                    rec.attempts.append((strategy.name, "not tried: out of time (timeout)"))
                    break
                started(rec.face, k)
                touched: list[int] = []
                users: set[int] = set()  # the faces on the curves this attempt changes
                meshed: set[int] = set()  # faces outside ``surfaces`` meshed so far
                if strategy.split or strategy.own_curves:
                    meshed = {t for _, t in gmsh.model.getEntities(2) if t not in out
                              and len(gmsh.model.mesh.getElementsByType(2, t)[0])}
                if strategy.split:
                    curves = [c for c in surface_curve_uses(s) if c not in split_done]  # split once
                    split_done.update(curves)
                    touched = split_curves(curves)
                    users = set(touched)
                elif strategy.own_curves:
                    curves = [c for c in surface_curve_uses(s) if c not in own_curves]
                    own_curves.update(curves)
                    if rec.face in as_gmsh_alone:  # an invalid face: fewer nodes on its broken wires
                        for c in curves:
                            gmsh.model.mesh.setSizeAtParametricPoints(1, c, [], [])
                    users = curve_surfaces(curves)
                    touched = remesh_curves(curves)
                if touched:
                    watch.reset()
                # the neighbours' last meshes stand for them until this attempt meshes the face: a process
                # stopped during it (a hang, the timeout) delivers them as they were, on the curves as they
                # were; faces gmsh's 1-D step wiped whose curves did not change keep theirs until meshed
                # again (the same boundary): a file's 46 meshed faces were otherwise cleared, and 1 delivered
                lost = [out[n].face for n in touched if n in out and out[n].ok and n in users]
                for n in touched:  # their boundary changed: mesh them again
                    tried_first.discard(n)  # a face whose batch attempt failed starts again on the new boundary
                    if n == s or (n in out and not out[n].ok) or (n not in out and n not in meshed):
                        continue  # this face, or a failed or not yet tried one: its own turn comes; or
                        # a face outside ``surfaces`` with no mesh to redo (failed, or another process's)
                    out[n] = FaceOutcome(face=face_of.get(n, n), surface=n)
                    order.setdefault(n, face_order(n))  # a neighbour outside ``surfaces``
                    tried_first.discard(n)
                    queue.append(n)
                reason = _attempt(s, strategy)
                if reason is None and touched:
                    cleared(lost)
                for n in deleted():
                    tried_first.discard(n)
                    if n not in queue:
                        queue.append(n)
                finished(rec.face, k, reason)
                if reason is None:
                    rec.strategy = strategy.name
                    break
                rec.attempts.append((strategy.name, reason))
    finally:
        gmsh.model.setVisibility(gmsh.model.getEntities(), 1)
        gmsh.option.setNumber("Mesh.MeshOnlyVisible", 0)
    for s, rec in out.items():
        rec.triangles = len(gmsh.model.mesh.getElementsByType(2, s)[0]) if rec.ok else 0
    return out
