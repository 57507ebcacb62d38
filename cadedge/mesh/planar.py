"""The exact area a planar face's triangles will have: the area of its boundary polygon.

Triangles filling a planar face without folding cover exactly the polygon of its boundary nodes (outer
wire minus holes), so the face's area deficit is known before meshing. Summed with signs: a thin curved
strip (periodic_u_cst face 2, 1 mm wide between two 210 mm B-spline edges) loses along its outer edge
what it gains along its inner one, while the unsigned estimate of :func:`cadedge.mesh.boundary_fit.fit_boundaries`
split both edges 14-fold for the strip's budget (13 -> 185 segments, deficit 2.5e-5 against 7e-3 allowed),
and the fine boundary was carried into the two large faces beside it.
"""

from __future__ import annotations

import numpy as np

from ..grid import polygon_area


def planar_polygon_areas(shape: object, grid, faces: list[int]) -> dict[int, float]:
    """Area enclosed by the grid nodes of each planar face in ``faces`` (ids; planar whatever the surface
    type, :mod:`cadedge.occt.planes`), holes subtracted.

    Each wire is walked in order (``BRepTools_WireExplorer``), each edge's grid points taken in the
    direction the wire uses it, projected on the face's plane; the signed areas of the wires are summed
    (outer wire and holes run opposite ways) and the absolute value taken, so the face's orientation does
    not matter. A face with an edge that has no usable grid, or a wire the walk cannot follow, is left out."""
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_FORWARD, TopAbs_REVERSED
    from OCP.TopExp import TopExp

    from ..occt.compat import TopoDS, TopTools_IndexedMapOfShape
    from ..occt.planes import plane_of
    from ..occt.topology import walked_wires

    edge_map, face_map = TopTools_IndexedMapOfShape(), TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_EDGE, edge_map)
    TopExp.MapShapes_s(shape, TopAbs_FACE, face_map)
    by_id = {e.id: e for e in grid.edges}
    out: dict[int, float] = {}
    for fid in faces:
        face = TopoDS.Face_s(face_map.FindKey(fid).Oriented(TopAbs_FORWARD))
        plane = plane_of(face)
        wires = walked_wires(face)
        if plane is None or wires is None:  # not planar after all, or a wire the walk cannot follow
            continue
        origin, axes = plane[0], np.array(plane[1:])
        total, usable = 0.0, True
        for edges in wires:
            loop = []
            for edge in edges:
                e = by_id.get(edge_map.FindIndex(edge))
                if e is None or (len(e.points) < 2 and not e.degenerate):
                    usable = False
                    break
                if not e.degenerate:
                    loop.append(e.points[::-1] if edge.Orientation() == TopAbs_REVERSED else e.points)
            if not usable:
                break
            if loop:
                total += polygon_area((np.vstack(loop) - origin) @ axes.T)
        if usable:
            out[fid] = abs(total)
    return out
