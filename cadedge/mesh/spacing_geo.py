"""The ``.geo`` spacing export: the shape as a BREP plus a gmsh script that sizes its mesh from the grids.

``gmsh part.geo -2`` evaluates the background field at every point it places, curves and faces alike, so
the cost of the export is the cost of that field, times the number of evaluations:

- **Few fields.** One Distance/Threshold pair per vertex and per curve made the field a ``Min`` over
  hundreds of fields on large models. Here the spacings are rounded down into size classes (a factor
  :data:`CLASS_RATIO` apart): one Distance field over all the vertices of a class and one over all the
  curves of a class, each with a Threshold growing from the class size by ``growth`` per unit
  distance, and one ``Min`` over those few. Rounding down keeps every size at most the grid's and at
  least ``1 / CLASS_RATIO`` of it.
- **Fewer evaluations.** gmsh integrates the size along each curve to place its nodes, to a relative
  precision of 1e-9 by default (``Mesh.LcIntegrationPrecision``), evaluating the field hundreds of
  thousands of times per curve. At :data:`~cadedge.mesh.sizes.INTEGRATION_PRECISION` the curve meshes are the same (on
  917_fusee one curve of 723 gets one segment more) for a tenth of the time.

- **Curved faces capped by their curvature.** Sizes from the edges alone left a thin tube (the helical
  spring's swept face, radius 1 under sizes of 3-5) with triangles larger than the tube is wide: gmsh's
  mesher then produced invalid elements, split the face's curves and started again, without end (over
  120 s at ALD 1e-1), and at 1e-2 the triangles that did come out had 0.7-degree angles. Each curved face
  gets one size from its curvature, ``2 pi / (n k)`` with ``n`` the surface target's count per circle
  (:func:`~cadedge.mesh.fidelity.per_circle`), at most :data:`GEO_PER_CIRCLE`, and ``k`` a high percentile of its largest principal
  curvature sampled on a grid of its parameters (:func:`face_curvature_sizes`). Faces are grouped into
  the same size classes, one ``Constant`` field per class (cheap: a set lookup per evaluation), with
  their boundary curves included so a curve is never coarser than the faces it bounds.

The sizes stay graded the way :class:`~cadedge.mesh.sizes.SizeField` grades them: near a vertex the
size is its spacing, growing linearly away from it; along and around a curve the size grows from the
curve's median spacing. A long straight edge between two fine vertices is therefore fine at its ends
and coarse in its middle. Point sizes (``MeshSize{}``) are not used: gmsh interpolates them along
curves, which would make such an edge fine all along. The ``.geo`` language has no sizes at
parametric points, so inside a curve the grading of its own grid is approximated by its median.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError
from ..shapegrid import ShapeGrid
from . import DEFAULT_GROWTH
from .coincident import merged_shape, point_tags
from .sizes import INTEGRATION_PRECISION, SizeField, node_spacings, vertex_sizes

#: At most this many triangles per circle of curvature in a face's cap: the caps keep gmsh off faces much
#: wider than they are curved (finer interiors cost gmsh minutes on wing_fuselage's B-spline faces).
GEO_PER_CIRCLE = 6.0
#: Curvature samples per parametric direction of a face (:func:`face_curvature_sizes`).
CURVATURE_SAMPLES = 16
#: Percentile of the sampled curvatures taken as the face's (spikes at poles and near-singular points of
#: spline surfaces are left out).
CURVATURE_PERCENTILE = 95.0

#: Spacings are rounded down to ``base * CLASS_RATIO**k``: a size class per factor of sqrt(2).
CLASS_RATIO = math.sqrt(2.0)
#: Sampling points per curve of a Distance field: enough that the sample gap is at most about twice the
#: class size on the longest curve of the class (the distance is then off by at most one class size,
#: the size by ``growth`` times that), within these bounds.
MIN_SAMPLING, MAX_SAMPLING = 20, 2000

#: gmsh's import of the BREP, as cadedge's own: no healing, sewing or fixing, so the entities (and their
#: tags, which are cadedge's ids) are the B-rep's exactly.
_IMPORT = ("Geometry.OCCAutoFix = 0; Geometry.OCCFixDegenerated = 0; Geometry.OCCFixSmallEdges = 0;",
           "Geometry.OCCFixSmallFaces = 0; Geometry.OCCSewFaces = 0; Geometry.OCCMakeSolids = 0;",
           "Geometry.OCCImportLabels = 0;")


def size_classes(sizes: dict[int, float], base: float) -> dict[float, list[int]]:
    """Group ids by their size rounded down to ``base * CLASS_RATIO**k``: class size -> sorted ids."""
    out: dict[int, list[int]] = {}
    for i, h in sizes.items():
        k = max(int(math.floor(math.log(h / base) / math.log(CLASS_RATIO) + 1e-9)), 0)
        out.setdefault(k, []).append(i)
    return {base * CLASS_RATIO ** k: sorted(ids) for k, ids in sorted(out.items())}


def face_curvature_sizes(shape: object, surface_ald: float) -> dict[int, float]:
    """One size per curved face of ``shape`` (ids in ``TopExp::MapShapes`` order): ``2 pi / (n k)`` with
    ``n = min(per_circle(surface_ald, type), GEO_PER_CIRCLE)`` and ``k`` the :data:`CURVATURE_PERCENTILE` of the largest
    principal curvature on a :data:`CURVATURE_SAMPLES` square grid of the face's parameter bounds, no
    smaller than the size giving about ``MAX_FACE_TRIANGLES`` on the face. Planar faces and faces OCCT
    cannot evaluate get none."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepLProp import BRepLProp_SLProps
    from OCP.BRepTools import BRepTools

    from ..occt.topology import Topology
    from .fidelity import brep_face_areas, per_circle, surface_type_name
    from .budget import filling_size

    faces = Topology(shape).faces
    areas = brep_face_areas(shape)
    t = (np.arange(CURVATURE_SAMPLES) + 0.5) / CURVATURE_SAMPLES
    out: dict[int, float] = {}
    for fid, face in enumerate(faces, start=1):
        surface = BRepAdaptor_Surface(face)
        kind = surface_type_name(surface)
        if kind == "Plane":
            continue
        u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
        if not all(map(math.isfinite, (u0, u1, v0, v1))):
            continue
        props = BRepLProp_SLProps(surface, 2, 1e-9)
        k = []
        for u in (u0 + (u1 - u0) * t).tolist():
            for v in (v0 + (v1 - v0) * t).tolist():
                props.SetParameters(u, v)
                if props.IsCurvatureDefined():
                    k.append(max(abs(props.MaxCurvature()), abs(props.MinCurvature())))
        k95 = float(np.percentile(k, CURVATURE_PERCENTILE)) if k else 0.0
        if not k95 > 0 or not math.isfinite(k95):
            continue
        h = 2.0 * math.pi / (min(per_circle(surface_ald, kind), GEO_PER_CIRCLE) * k95)
        out[fid] = max(h, float(filling_size(areas[fid - 1])))
    return out


def _ids(ids: list[int]) -> str:
    return ", ".join(map(str, ids))


def _threshold(n: int, size: float, max_size: float, growth: float) -> str:
    """Threshold field ``n + 1`` on Distance field ``n``: ``size + growth * d``, up to ``max_size``."""
    return (f"Field[{n + 1}] = Threshold; Field[{n + 1}].InField = {n}; Field[{n + 1}].SizeMin = {size!r}; "
            f"Field[{n + 1}].SizeMax = {max_size!r}; Field[{n + 1}].DistMin = 0; "
            f"Field[{n + 1}].DistMax = {max(max_size - size, 0.0) / growth!r};")


def geo_fields(grid: ShapeGrid, field: SizeField, growth: float,
               face_sizes: dict[int, float] | None = None, points: dict[int, int] | None = None) -> list[str]:
    """The ``.geo`` lines of the size fields: per size class a Distance and a Threshold field, for the
    vertices and for the curves of that class, and a Constant field for the faces of that class in
    ``face_sizes`` (face id -> size; boundaries included), then their ``Min`` as the background field.
    ``points`` maps vertex ids to the BREP's point tags where they differ (vertices merged:
    :func:`cadedge.mesh.coincident.point_tags`)."""
    points = points or {}
    vertex_h = {vid: h for vid, h in vertex_sizes(grid).items() if h > 0}
    edges = [e for e in grid.edges if not e.degenerate and len(e.points) >= 2]
    curve_h = {e.id: float(np.median(node_spacings(e))) for e in edges}
    curve_h = {i: h for i, h in curve_h.items() if h > 0}
    length = {e.id: float(np.sum(e.segment_lengths)) for e in edges}
    sizes = list(vertex_h.values()) + list(curve_h.values())
    if not sizes:
        return []
    base, top = min(sizes), field.max_size
    lines, thresholds, n = [], [], 1
    for size, vids in size_classes(vertex_h, base).items():
        tags = sorted({points.get(v, v) for v in vids})
        lines += [f"Field[{n}] = Distance; Field[{n}].PointsList = {{{_ids(tags)}}};",
                  _threshold(n, size, max(top, size), growth)]
        thresholds.append(n + 1)
        n += 2
    for size, eids in size_classes(curve_h, base).items():
        longest = max(length[i] for i in eids)
        sampling = int(np.clip(math.ceil(longest / (2.0 * size)) + 1, MIN_SAMPLING, MAX_SAMPLING))
        lines += [f"Field[{n}] = Distance; Field[{n}].CurvesList = {{{_ids(eids)}}}; "
                  f"Field[{n}].Sampling = {sampling};",
                  _threshold(n, size, max(top, size), growth)]
        thresholds.append(n + 1)
        n += 2
    capped = {f: h for f, h in (face_sizes or {}).items() if h < top}
    for size, fids in size_classes(capped, base).items():
        lines.append(f"Field[{n}] = Constant; Field[{n}].SurfacesList = {{{_ids(fids)}}}; "
                     f"Field[{n}].VIn = {size!r}; Field[{n}].IncludeBoundary = 1;")
        thresholds.append(n)
        n += 1
    return lines + [f"Field[{n}] = Min; Field[{n}].FieldsList = {{{_ids(thresholds)}}};",
                    f"Background Field = {n};"]


def write_geo(grid: ShapeGrid, path: str | os.PathLike, *, growth: float = DEFAULT_GROWTH,
              max_size: float | None = None, surface_ald: float | None = None) -> Path:
    """Write a gmsh ``.geo`` carrying our spacings, plus the shape as ``<stem>.brep`` beside it (vertices
    of one face at one point merged into one: :mod:`cadedge.mesh.coincident`).

    The ``.geo`` merges the BREP (gmsh's tags are then cadedge's ids: MapShapes order) without any of
    gmsh's healing, and sizes the mesh with the size-class fields of :func:`geo_fields` (see the module
    doc), curved faces capped by :func:`face_curvature_sizes` for ``surface_ald`` (default: the grid's
    ALD). :func:`~cadedge.mesh.sizes.apply_spacing_sizes` gives gmsh the exact per-point sizes through
    the API instead (``cadedge mesh --mode sizes``).
    """
    from OCP.BRepTools import BRepTools

    target = Path(path)
    if grid.shape is None:
        raise InputError(f"{grid.source}: the shape grid carries no OCCT shape to export")
    if not growth > 0:
        raise InputError(f"growth must be positive, got {growth}")
    field = SizeField(grid, growth=growth, max_size=max_size)
    surface_ald = surface_ald or grid.options.get("ald")
    face_sizes = face_curvature_sizes(grid.shape, float(surface_ald)) if surface_ald else {}
    shape, into = merged_shape(grid)  # one gmsh point where a face has two vertices
    brep = target.with_suffix(".brep")
    with atomic_path(brep) as tmp:
        if not BRepTools.Write_s(shape, str(tmp)):
            raise InputError(f"{brep}: OCCT could not write the BREP")
    lines = [f"// cadedge spacing export of {grid.source} (options {grid.options})",
             'SetFactory("OpenCASCADE");', *_IMPORT,
             f'Merge "{brep.name}";',
             "Mesh.MeshSizeFromCurvature = 0; Mesh.MeshSizeFromPoints = 0; Mesh.MeshSizeExtendFromBoundary = 0;",
             f"Mesh.MeshSizeMax = {field.max_size!r}; Mesh.LcIntegrationPrecision = {INTEGRATION_PRECISION!r};",
             *geo_fields(grid, field, growth, face_sizes, point_tags(grid, into) if into else None)]
    with atomic_path(target) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    return target
