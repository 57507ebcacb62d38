"""Inside the gmsh job: the curves gmsh splits as it meshes a face, and the meshed faces it deletes for that.

A face whose boundary segments cross in its parameters (two nearby curves' chords on a plane) has gmsh
split them at their midpoints and mesh it again (``remeshUnrecoveredEdges`` in gmsh's ``meshGFace.cpp``,
always on); the other faces on those curves lose their meshes, for gmsh to mesh them again in the same
call, but :func:`cadedge.mesh.generate.mesh_faces` meshes with only the faces of the call visible, so
they stay empty. :class:`CurveWatch` tells ``mesh_faces`` which faces to mesh again, and the job which
edges' grids gained nodes.
"""

from __future__ import annotations

import gmsh

#: Times a face is meshed again after gmsh deleted its mesh splitting a curve for a neighbour
#: (:class:`CurveWatch`); deleted once more, it is left failed with :data:`GMSH_DELETED`.
MESHED_AGAIN = 2
#: The reason for such a face.
GMSH_DELETED = (f"meshed, then its mesh deleted by gmsh, which split a curve it shares with a face meshed after "
                f"it; meshed again {MESHED_AGAIN} times already")


def curve_counts() -> dict[int, int]:
    """Segments on each gmsh curve."""
    return {c: len(gmsh.model.mesh.getElementsByType(1, c)[0]) for _, c in gmsh.model.getEntities(1)}


class CurveWatch:
    """The curve meshes followed across gmsh calls (see the module doc): an Inventor worm gear's helical
    flanks (31 000 triangles each) were deleted so as their side planes were meshed, counted as meshed,
    and came out missing.
    :meth:`deleted`, after every gmsh call, counts all segments in one call and looks further only when
    the count moved; :meth:`reset` follows a strategy that changes curves itself. With ``per_curve`` the
    curves split are collected in :attr:`split` (from a count per curve, taken again at each change)."""

    def __init__(self, *, per_curve: bool = False) -> None:
        self.per_curve = per_curve
        self.split: set[int] = set()
        self.reset()

    def reset(self) -> None:
        self.counts = curve_counts() if self.per_curve else {}
        self.total = len(gmsh.model.mesh.getElementsByType(1)[0])

    def deleted(self, meshed: list[int]) -> list[int] | None:
        """The surfaces of ``meshed`` (meshed before the last gmsh call) left empty by it when it split
        curves (maybe none); None when no curve changed since the last look."""
        if len(gmsh.model.mesh.getElementsByType(1)[0]) == self.total:
            return None
        before = self.counts
        self.reset()
        self.split.update(c for c, n in self.counts.items() if n != before.get(c))
        return [s for s in meshed if not len(gmsh.model.mesh.getElementTypes(2, s))]
