"""The mesh report: per face id, surface type, triangles, area deficit and minimum angle.

Returned by :func:`cadedge.mesh.mesh_shape` as ``result.report``, summarised (worst faces only) in the
printed lines, and written as JSON by ``cadedge mesh --report mesh.json`` (schema ``cadedge.meshreport/1``).
The area deficit of a face is ``1 - mesh area / B-rep area`` (see :mod:`cadedge.mesh.fidelity`).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from .areas import area_deficits, face_mesh_areas
from .budget import MAX_FACE_TRIANGLES
from .interior import SPREAD
from .quality import GOOD_DEG, OFF_REACH, SLIVER_DEG, SmallAngle, min_angles, small_angles, triangle_angles

SCHEMA = "cadedge.meshreport/1"
#: Faces listed in the printed summary.
WORST = 5
#: Where the job's fidelity hook leaves what it did (``MeshResult.extras``).
AFTER_MESH_HOOK = "cadedge.mesh.fidelity:after_mesh"


#: Edges measured this many times farther from a face's boundary than their tolerance lie off the face
#: beyond it (the note says so).
BEYOND = 2.0
#: Why a face is over the target (``FaceReport.reason``): its deficit is within what its edges' tolerances,
#: or their measured distances from its boundary, allow; its sizes were held above a floor on a sharp
#: ridge of its surface; its mesh holds the face's triangle budget (not meshed finer); finer meshes did
#: not reduce it (its meshed and B-rep areas disagree); beside edges whose grids gmsh's own curve mesh
#: replaced; a planar face (its boundary polygon sets its area); still over after it was meshed again
#: finer.
OVER_REASONS = ("tolerances", "size floor", "triangle budget", "gmsh's curves", "not converging", "planar",
                "still over")


@dataclass
class FaceReport:
    """One B-rep face. ``status``: ``ok``, ``over target`` (meshed, area deficit above the target) or
    ``failed`` (not meshed); ``note`` says why when it is not ok, and for a face over target ``reason``
    says it as one of :data:`OVER_REASONS` (else empty). ``folded``: its triangles that face against
    its surface (:mod:`cadedge.mesh.folds`; they overlap their neighbours)."""

    face: int
    surface: str
    triangles: int
    brep_area: float
    mesh_area: float
    area_deficit: float | None
    min_angle: float | None
    below_20: float
    folded: int = 0
    status: str = "ok"
    note: str = ""
    reason: str = ""


@dataclass
class MeshReport:
    """Per-face records plus whole-mesh figures: worst |area deficit|, minimum angle, share under 20 deg,
    and every triangle under 5 deg (forced by the B-rep or not)."""

    surface_ald: float | None
    faces: list[FaceReport]
    triangles: int
    min_angle: float | None
    below_20: float
    worst_deficit: float | None
    small_angles: list[SmallAngle] = field(default_factory=list)

    @property
    def over_target(self) -> list[FaceReport]:
        return [f for f in self.faces if f.status == "over target"]

    @property
    def folded(self) -> int:
        """Triangles that face against their surface, over all faces."""
        return sum(f.folded for f in self.faces)

    @property
    def unforced_slivers(self) -> int:
        return sum(not s.forced for s in self.small_angles)

    def worst_faces(self, n: int = WORST) -> list[FaceReport]:
        """The ``n`` meshed faces with the largest |area deficit|."""
        meshed = [f for f in self.faces if f.area_deficit is not None and f.triangles]
        return sorted(meshed, key=lambda f: -abs(f.area_deficit))[:n]

    def lines(self, n: int = WORST) -> list[str]:
        """The printed summary: whole-mesh figures, the worst faces, faces over target, slivers."""
        target = f" (target {self.surface_ald:g})" if self.surface_ald else ""
        out = [f"faces: worst |area deficit| {_num(self.worst_deficit)}{target}, min angle "
               f"{_num(self.min_angle, '.1f')} deg, {100 * self.below_20:.2f}% of triangles under {GOOD_DEG:g} deg"]
        for f in self.worst_faces(n):
            out.append(f"  face {f.face} ({f.surface}): {f.triangles} triangles, area deficit "
                       f"{f.area_deficit:.3g}, min angle {_num(f.min_angle, '.1f')} deg")
        for f in self.over_target:
            out.append(f"  face {f.face}: area deficit {f.area_deficit:.3g} over the target: {f.note}")
        forced = [s for s in self.small_angles if s.forced]
        if self.small_angles:
            out.append(f"  {len(self.small_angles)} triangles under {SLIVER_DEG:g} deg "
                       f"({len(forced)} forced by the B-rep) on faces "
                       f"{sorted({s.face for s in self.small_angles})[:10]}")
        for s in {s.face: s for s in reversed(forced)}.values():
            out.append(f"  face {s.face}: {s.angle:.2g} deg forced: {s.reason}")
        if self.folded:
            loose = sum(f.folded for f in self.faces if f.reason in ("tolerances", "not converging"))
            out.append(f"  {self.folded} triangles folded against their surface (they overlap their neighbours, "
                       "and their faces' area deficits read smaller by the overlap) on faces "
                       f"{[f.face for f in self.faces if f.folded][:10]}"
                       + (f"; {loose} of them on faces named above for their edges' tolerances or as not "
                          "converging (their boundary or surface is not the B-rep's)" if loose else ""))
        return out

    def to_dict(self) -> dict:
        """Plain JSON-ready data (NaN written as null)."""
        return _clean({"schema": SCHEMA, "surface_ald": self.surface_ald, "triangles": self.triangles,
                       "min_angle": self.min_angle, "below_20": self.below_20,
                       "worst_area_deficit": self.worst_deficit,
                       "faces": [asdict(f) for f in self.faces],
                       "small_angles": [asdict(s) for s in self.small_angles]})

    def write(self, path: str | os.PathLike) -> Path:
        """Write :meth:`to_dict` as JSON, atomically."""
        target = Path(path)
        with atomic_path(target) as tmp:
            tmp.write_text(json.dumps(self.to_dict(), indent=1) + "\n")
        return target


def _num(x: float | None, fmt: str = ".3g") -> str:
    return "n/a" if x is None or not math.isfinite(x) else format(x, fmt)


def _clean(obj):
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


def build_report(nodes: np.ndarray, triangles: np.ndarray, triangle_faces: np.ndarray, *,
                 brep_areas: np.ndarray, surface_types: list[str], surface_ald: float | None = None,
                 failed: dict[int, str] | None = None, vertex_points: np.ndarray | None = None,
                 stuck: list[int] | tuple[int, ...] = (),
                 tolerances: dict[int, tuple[float, ...]] | None = None,
                 planar: set[int] | None = None, floored: dict[int, float] | None = None,
                 budget: set[int] | frozenset[int] = frozenset(), budget_triangles: int | None = None,
                 face_edges: dict[int, list[np.ndarray]] | None = None,
                 folded: dict[int, int] | None = None,
                 offsets: dict[int, list[tuple[np.ndarray, float]]] | None = None,
                 gmsh_curves: dict[int, list[int]] | None = None,
                 tangles: dict[int, list[tuple[tuple[float, float, float], float]]] | None = None) -> MeshReport:
    """The report of a triangle mesh whose triangles carry B-rep face ids (``triangle_faces``, 1-based).

    ``failed`` maps faces that were not meshed to the reason; ``vertex_points`` are the B-rep vertices
    (to tell small angles forced by a sharp face corner from the mesher's own slivers); ``stuck`` the faces
    whose deficit finer meshes did not reduce, or was too large to come from meshing; ``tolerances`` maps
    a face to its edges' largest tolerance and the share of its area they leave open
    (:func:`tolerance_bands`; the largest measured distance instead, then the largest tolerance third):
    a face over target within that share is reported as such; ``planar`` the
    faces meshed as planes (default: those of type ``Plane``); ``floored`` the faces whose sizes were held
    at or above a floor (face -> size, :func:`cadedge.mesh.interior.size_floors`); ``budget`` the faces not
    meshed finer because their mesh holds their triangle budget, ``budget_triangles`` (the job's, default
    :data:`~cadedge.mesh.budget.MAX_FACE_TRIANGLES`); ``face_edges`` the grid
    polylines of each face's edges (:func:`face_edge_grids`: to tell small angles forced by a face
    narrower than its boundary segments); ``folded`` the faces with triangles that face against their
    surface (face -> how many); ``offsets`` the edges that lie off a face's boundary (face -> (grid
    polyline, distance), :func:`edge_polylines_off`: to tell small angles forced by such an edge);
    ``gmsh_curves`` the faces beside edges whose grid a fallback replaced by gmsh's own curve mesh (face ->
    those edges): a face over target there is named for them; ``tangles`` where a face's boundary
    crossed itself (face -> balls, :attr:`~cadedge.mesh.outcomes.FaceOutcome.tangles`): small angles
    there are forced.
    """
    nodes = np.asarray(nodes, dtype=float)
    tris = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    tri_faces = np.asarray(triangle_faces, dtype=np.int64)
    n = len(brep_areas)
    failed = failed or {}
    planar = {i + 1 for i, k in enumerate(surface_types) if k == "Plane"} if planar is None else planar
    mesh_areas = face_mesh_areas(nodes, tris, tri_faces, n)
    deficits = area_deficits(mesh_areas, brep_areas)
    angles = triangle_angles(nodes, tris) if len(tris) else np.zeros((0, 3))
    tri_min = angles.min(axis=1) if len(tris) else np.zeros(0)
    counts = np.bincount(tri_faces - 1, minlength=n)[:n] if len(tris) else np.zeros(n, dtype=int)
    faces = []
    for i in range(n):
        fid = i + 1
        mine = tri_min[tri_faces == fid]
        rec = FaceReport(face=fid, surface=surface_types[i], triangles=int(counts[i]),
                         brep_area=float(brep_areas[i]), mesh_area=float(mesh_areas[i]),
                         area_deficit=float(deficits[i]) if len(mine) and np.isfinite(deficits[i]) else None,
                         min_angle=float(mine.min()) if len(mine) else None,
                         below_20=float(np.mean(mine < GOOD_DEG)) if len(mine) else 0.0,
                         folded=int((folded or {}).get(fid, 0)))
        if fid in failed or not len(mine):
            rec.status, rec.note = "failed", failed.get(fid, "no triangles")
            if (floored or {}).get(fid) is not None:  # the likely cause, in the user's terms
                rec.note += (f"; its surface has a sharp ridge (curvature over {SPREAD:g}x across it), where "
                             f"gmsh's triangles of {floored[fid]:.2g} or more can take longer than the timeout "
                             "(docs/mesh.md, Triangles across a ridge)")
        elif surface_ald and rec.area_deficit is not None and abs(rec.area_deficit) > surface_ald:
            rec.status = "over target"
            rec.reason, rec.note = _over_note(rec, fid in stuck, (tolerances or {}).get(fid), fid in planar,
                                              (floored or {}).get(fid),
                                              (budget_triangles or MAX_FACE_TRIANGLES) if fid in budget else 0,
                                              (gmsh_curves or {}).get(fid, []))
        elif rec.area_deficit is None:
            rec.note = "the B-rep face has no area (degenerate)"
        faces.append(rec)
    measured = [abs(f.area_deficit) for f in faces if f.area_deficit is not None]
    smalls = small_angles(nodes, tris, tri_faces, np.zeros((0, 3)) if vertex_points is None else vertex_points,
                          angles=angles, face_edges=face_edges, offsets=offsets, tangles=tangles) if len(tris) else []
    return MeshReport(surface_ald=surface_ald, faces=faces, triangles=len(tris),
                      min_angle=float(tri_min.min()) if len(tri_min) else None,
                      below_20=float(np.mean(tri_min < GOOD_DEG)) if len(tri_min) else 0.0,
                      worst_deficit=max(measured) if measured else None, small_angles=smalls)


def _percent(share: float) -> str:
    """``share`` as a percentage of two significant digits, without an exponent.

    >>> _percent(0.0014), _percent(0.14), _percent(14.0)
    ('0.14%', '14%', '1400%')
    """
    return f"{100 * share:.2g}%" if 100 * share < 100 else f"{100 * share:.0f}%"


def _over_note(rec: FaceReport, stuck: bool, tolerance: tuple[float, ...] | None, planar: bool,
               floor: float | None, budget: int = 0, gmsh_edges: list[int] | None = None) -> tuple[str, str]:
    """Why a meshed face is over the target: its reason (one of :data:`OVER_REASONS`) and note; ``budget``
    the job's per-face triangle budget where the face holds it (0: it does not); ``gmsh_edges`` its edges
    whose grid gmsh's own curve mesh replaced."""
    if tolerance is not None and abs(rec.area_deficit) <= tolerance[1] and len(tolerance) > 2 and \
            tolerance[0] > BEYOND * tolerance[2]:
        return "tolerances", (f"its edges lie up to {tolerance[0]:.2g} from its boundary (their pcurves on its "
                              f"surface), beyond their tolerance ({tolerance[2]:.2g}), and a boundary moved that far "
                              f"changes its area by up to {_percent(tolerance[1])} (edges off their face; the mesh "
                              "follows the shared edges)")
    if tolerance is not None and abs(rec.area_deficit) <= tolerance[1]:
        return "tolerances", (f"within what its edges' tolerances allow: they may lie up to {tolerance[0]:.2g} "
                              "from its boundary (their pcurves on its surface), and a boundary moved that far "
                              f"changes its area by up to {_percent(tolerance[1])} (loose tolerances; the mesh follows "
                              "the shared edges)")
    if floor is not None:
        return "size floor", (f"its surface has a sharp ridge: its triangles were held at {floor:.2g} or more "
                              "(the face's triangle budget; curvature sizes would go down to a share of the "
                              "finest edge spacing and gmsh run out of time), and some span the ridge")
    if budget:
        return "triangle budget", (f"its {rec.triangles} triangles hold the face's budget (about {budget:,} "
                                   "triangles from curvature sizes): finer, gmsh would take longer than one "
                                   "attempt's time; a longer --timeout raises it")
    if gmsh_edges:
        return "gmsh's curves", (f"beside edge(s) {', '.join(map(str, gmsh_edges))}, whose grids gmsh's own curve "
                                 "mesh replaced (a fallback after a face failed on them): its boundary there is "
                                 "gmsh's polygon, not the grids'")
    if stuck:
        return "not converging", ("not meshed finer, or finer meshes did not reduce it: the meshed face and its "
                                  "B-rep area disagree by more than meshing explains (loose tolerances, or a "
                                  "trimming read differently by gmsh and by OCCT's area integration)")
    if planar:
        return "planar", "a planar face: its area is set by its boundary polygon"
    return "still over", "still over after the face was meshed again finer"


def tolerance_bands(grid, brep_areas: np.ndarray, tolerances: dict[int, float] | None = None,
                    measured: dict[int, dict[int, float]] | None = None) -> dict[int, tuple[float, float]]:
    """Per face whose edges carry a tolerance: (their largest tolerance, the share of the face's area a
    boundary moved by each edge's tolerance along its length could add or take away: the sum of
    tolerance x length over its edges, divided by its area). Edges may lie that far from the face's
    boundary (their pcurves on its surface, which bound its B-rep area), and its mesh follows them
    (gapped_sewn: 0.02-0.04 from the fillets, 2-3% of their area). ``tolerances`` (edge id -> tolerance)
    overrides the grid's, for edges meshed with rebuilt pcurves (:attr:`cadedge.mesh.MeshResult.restepped`);
    ``measured`` (face id -> {edge id: distance}, :func:`cadedge.occt.offsets.edge_offsets`) overrides
    both, per face, with how far the edge lies from that face's boundary."""
    reach: dict[int, float] = {}
    worst: dict[int, float] = {}
    for e in grid.edges:
        tolerance = (tolerances or {}).get(e.id, e.tolerance)
        for f in e.faces:
            off = (measured or {}).get(f, {}).get(e.id, tolerance)
            if off <= 0.0:
                continue
            reach[f] = reach.get(f, 0.0) + off * e.length
            worst[f] = max(worst.get(f, 0.0), off)
    return {f: (worst[f], r / brep_areas[f - 1]) for f, r in reach.items()
            if 1 <= f <= len(brep_areas) and brep_areas[f - 1] > 0}


def report_of(result, opts: dict) -> MeshReport | None:
    """The report of a :class:`~cadedge.mesh.MeshResult` meshed with the fidelity settings ``opts``
    (:func:`cadedge.mesh.fidelity.prepare`); None when nothing was meshed."""
    if result.check is None and not len(result.triangles):
        return None
    extras = result.extras.get(AFTER_MESH_HOOK, {}) or {}
    failed = {f.face: f.reason for f in result.failures}
    vertex_points = np.array([np.asarray(v.point, dtype=float) for v in result.grid.vertices]).reshape(-1, 3)
    bands = tolerance_bands(result.grid, opts["brep_areas"], result.restepped)
    over = _over_target(result, opts, failed)
    slivered = _slivered_near_loose(result, bands)
    measured: dict[int, dict[int, float]] = {}
    if (over or slivered) and result.grid.shape is not None:  # the edges' real distances, not the bound
        from ..occt.offsets import edge_offsets

        measured = edge_offsets(result.grid.shape, result.grid.edges, sorted(set(over) | set(slivered)))
        stated = bands
        bands = tolerance_bands(result.grid, opts["brep_areas"], result.restepped,
                                {f: d for f, d in measured.items() if f in over})
        bands = {f: band + (stated[f][0],) if f in over and f in stated else band for f, band in bands.items()}
    return build_report(result.nodes, result.triangles, result.triangle_faces, brep_areas=opts["brep_areas"],
                        surface_types=opts["surface_types"], surface_ald=opts["surface_ald"], failed=failed,
                        vertex_points=vertex_points, stuck=extras.get("stuck", ()),
                        tolerances=bands,
                        planar=set(range(1, len(opts["brep_areas"]) + 1)) - set(opts["curved_faces"]),
                        floored=extras.get("floored"), budget=set(extras.get("budget", ())),
                        budget_triangles=extras.get("budget_triangles"),
                        face_edges=face_edge_grids(result.grid),
                        folded=extras.get("folded"), offsets=edge_polylines_off(result.grid, measured),
                        gmsh_curves=faces_beside(result.grid, result.own_mesh_edges),
                        tangles={o.face: o.tangles for o in result.faces if o.tangles})


def faces_beside(grid, edges: list[int]) -> dict[int, list[int]]:
    """Face id -> the ``edges`` (ids) on its boundary, for the faces with any."""
    from .shards import face_edges

    wanted = set(edges)
    return {f: sorted(mine & wanted) for f, mine in face_edges(grid).items() if mine & wanted}


def _slivered_near_loose(result, bands: dict[int, tuple[float, float]]) -> list[int]:
    """The faces with a triangle under :data:`~cadedge.mesh.quality.SLIVER_DEG` no longer than
    :data:`~cadedge.mesh.quality.OFF_REACH` times their edges' largest tolerance (``bands``): those an
    edge off the face's boundary may force (:func:`~cadedge.mesh.quality.small_angles`)."""
    if not len(result.triangles) or not bands:
        return []
    tris = np.asarray(result.triangles, dtype=np.int64)
    low = np.flatnonzero(min_angles(result.nodes, tris) < SLIVER_DEG)
    if not len(low):
        return []
    p = np.asarray(result.nodes, dtype=float)[tris[low]]
    longest = np.linalg.norm(p - np.roll(p, -1, axis=1), axis=2).max(axis=1)
    faces = np.asarray(result.triangle_faces, dtype=np.int64)[low]
    reach = np.array([OFF_REACH * bands.get(int(f), (0.0, 0.0))[0] for f in faces])
    return sorted(set(faces[longest <= reach].tolist()))


def edge_polylines_off(grid, measured: dict[int, dict[int, float]]) -> dict[int, list[tuple[np.ndarray, float]]]:
    """Face id -> (grid polyline, distance) of its edges that lie off its boundary, from the distances
    ``measured`` (face id -> {edge id: distance}, :func:`cadedge.occt.offsets.edge_offsets`)."""
    lines = {e.id: np.asarray(e.points, dtype=float) for e in grid.edges}
    return {f: [(lines[e], d) for e, d in sorted(per_edge.items()) if d > 0.0 and e in lines]
            for f, per_edge in measured.items()}


def _over_target(result, opts: dict, failed: dict[int, str]) -> list[int]:
    """The meshed faces over the surface target: their edges are measured against their boundaries
    (:func:`cadedge.occt.offsets.edge_offsets`), which may excuse them. Measured only where the edges'
    tolerances would, a Seeed camera module's near-planar face (sk_himax, 1.29 times the target at
    1e-3) was said to be set by its boundary polygon: two of its edges lie 0.044 and 0.13 off its
    boundary, with tolerances of 8e-7."""
    areas = np.asarray(opts["brep_areas"], dtype=float)
    target = opts["surface_ald"]
    if not target or not len(result.triangles):
        return []
    deficits = area_deficits(face_mesh_areas(result.nodes, result.triangles, result.triangle_faces, len(areas)),
                             areas)
    return [f for f in range(1, len(areas) + 1)
            if f not in failed and np.isfinite(deficits[f - 1]) and abs(deficits[f - 1]) > target]


def face_edge_grids(grid) -> dict[int, list[np.ndarray]]:
    """Face id -> the grid polylines of its edges (for :func:`~cadedge.mesh.quality.small_angles`)."""
    out: dict[int, list[np.ndarray]] = {}
    for e in grid.edges:
        for f in set(e.faces):
            out.setdefault(f, []).append(np.asarray(e.points, dtype=float))
    return out
