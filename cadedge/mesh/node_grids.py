"""The edge grids imposed as boundary nodes (``mode="nodes"``): the grids as the boundary fit left them,
split and graded for the faces they bound, in a fixed order.

Each pass only adds points, except the narrow corners' first grading, which may drop points the
boundary fits added to lengthen a corner's tips (:func:`cadedge.mesh.wedges.grade_wedges`). The later
area fits split the segments that still cost a face too much, and one of those may be a narrow corner's
tip: KiCad's USB-C receptacle has a planar strip 0.0004-0.0007 wide between a line and an arc that end
0.00036 apart (a vertex tolerance closes the gap); its tips, graded to 0.01, were cut on the arc alone
by the planar fit (the gap's sliver), and every triangle on the 0.01 line tip spanned the strip: two of
4.6 degrees that the B-rep did not force. The build123d M6 screw's cone face had its circle cut in
thirds by the curved faces' second fit, its tips left at 0.059 and 0.019. So the narrow corners are
graded once more at the end, the longer tip cut at the shorter one's length and the sides graded by the
wedge's width again. Cutting only shortens chords, so no sliver grows; a credited face's slivers cancel,
and a cut can unbalance them, but on every file that changed (the screw, the USB-C receptacle, faceted,
917_fusee) no face's deficit moved past its target.
"""

from __future__ import annotations

from collections.abc import Callable

from ..occt.cones import apex_cones
from ..shapegrid import ShapeGrid
from .apex import grade_to_apexes
from .boundary_fit import fit_curved, fit_grids, fit_planes, plane_room
from .grading import grade_faces
from .instances import SetAside
from .jobclock import JobClock
from .proximity import fit_to_sizes
from .shards import faces_text
from .turnbacks import drop_turn_backs
from .wedges import grade_wedges
from .widths import fit_to_widths


def fit_node_grids(grid: ShapeGrid, refined: ShapeGrid, fidelity: dict, surface_ald: float, *, growth: float,
                   make_field: Callable[[ShapeGrid], object], cap: float | None,
                   clock: JobClock, aside: SetAside | None = None) -> tuple[ShapeGrid, float, list[str]]:
    """``grid`` (the boundary-fitted grid of :func:`cadedge.mesh.fidelity.prepare`, whose ``fidelity``
    settings it updates) with its segments fitted to the face sizes, for imposing as boundary nodes:
    split near small features, across thin faces, graded face by face (``growth``) and into narrow
    corners and cone tips, the planar, credited curved and gridded faces' polygons fitted again to the
    area target ``surface_ald``, then the narrow corners' tips matched again (module doc). ``refined`` is
    the grid as the edges were refined (the points a corner's tips keep). Each pass runs only while
    ``clock`` allows it. ``aside``: an assembly's copies, left out as by
    :func:`~cadedge.mesh.fidelity.prepare` (``grid`` is ``aside.apart`` already). Returns the grid, the
    size cap (``cap``, or the size field's largest size before the thin faces' splits: they must not
    shrink it) and notes for the user."""
    notes = []
    if aside is not None:  # the proximity split's size field feels the copies as fitted
        grid = aside.follow(grid)
    try:
        if clock.allows("the splits near small features"):
            grid = fit_to_sizes(grid, make_field)
    except Exception as exc:  # OCCT failing on one edge's curve: mesh the grids as refined, and say so
        notes.append(f"long boundary segments near small features were not split: OCCT failed ({exc})")
    cap = cap or make_field(grid).max_size
    areas, kinds, credits = fidelity["brep_areas"], fidelity["meshed_kinds"], fidelity["curved_credits"]
    if aside is not None:
        areas, refined = aside.hide(areas), aside.apart(refined)
    if clock.allows("the thin faces' splits"):
        grid = fit_to_widths(grid, keep=refined)  # segments of thin faces no longer than the face is wide
    if clock.allows("the face-wise grading"):
        grid = grade_faces(grid, growth=growth)  # each face's boundary graded from its own spacings
    if clock.allows("the grading into narrow corners"):  # segments shrink into a face's narrow corners
        grid = grade_wedges(grid, keep=refined, areas=areas, target=surface_ald,
                            spare=lambda: plane_room(grid, surface_ald, brep_areas=areas, kinds=kinds))
    cones = [i for i, kind in enumerate(fidelity["surface_types"], start=1)
             if kind == "Cone" and (aside is None or i not in aside.faces)]
    if cones and clock.allows("the grading into cone tips"):
        grid = grade_to_apexes(grid, apex_cones(grid.shape, cones))  # segments shrink into a narrow cone's tip
    if clock.allows("the planar faces' second fit"):  # the splits moved planar faces' polygons
        grid = fit_planes(grid, surface_ald, brep_areas=areas, kinds=kinds, credit=credits)
    if credits and clock.allows("the curved faces' second fit"):  # the splits may have left a credited
        grid, credits = fit_curved(grid, surface_ald, brep_areas=areas, kinds=kinds, credit=credits)
        fidelity["curved_credits"] = credits  # face's slivers uncancelled: checked again
    if clock.allows("the gridded faces' fit"):  # polygons checked again, and the grids' rows
        grid = fit_grids(grid, surface_ald, brep_areas=areas, kinds=kinds, credit=credits)
    if clock.allows("the narrow corners' tips matched again"):
        grid = grade_wedges(grid)  # a fit above may have cut one tip of a corner
    grid, hooked = drop_turn_backs(grid)  # last: a split inside a hook puts its tip back
    if hooked:
        notes.append(f"{faces_text(set(hooked), noun='edge')}: the curve turns back on itself; the grid "
                     "imposed on the faces crosses the hook's base (both faces would fill the hook, back to back)")
    return grid, cap, notes
