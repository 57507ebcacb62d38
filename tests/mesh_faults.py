"""Faults injected into the gmsh child process by the robustness tests (hooks of cadedge.mesh.worker).

Each hook acts on the first attempt (strategy 0) at face ``FAULT_FACE`` only, so the restarted child gets
past it with the next strategy.
"""

from __future__ import annotations

import ctypes
import time

FAULT_FACE = 2


def segfault(ctx) -> None:
    """A real segmentation fault: read address 0."""
    if ctx.face == FAULT_FACE and ctx.strategy == 0:
        ctypes.string_at(0)


def hang(ctx) -> None:
    """Never return (as gmsh's 2-D meshers sometimes do)."""
    if ctx.face == FAULT_FACE and ctx.strategy == 0:
        while True:
            time.sleep(1)


def crash_before_meshing(ctx) -> None:
    """Abort the child outside any face attempt: the whole run fails, the caller does not."""
    ctypes.string_at(0)


def spin(ctx) -> None:
    """Compute forever without returning (a busy hang, as gmsh's own are)."""
    if ctx.face == FAULT_FACE and ctx.strategy == 0:
        while True:
            pass


def hang_refining(ctx) -> None:
    """After the faces are meshed, announce meshing face ``FAULT_FACE`` again finer and never return, unless
    an earlier child hung there (the watchdog then lists the face in ``job.no_refine``)."""
    if FAULT_FACE not in ctx.job.no_refine:
        ctx.progress(f"refine {FAULT_FACE}")
        while True:
            time.sleep(1)


def hang_refining_together(ctx) -> None:
    """As :func:`hang_refining`, for faces 1 and 3 meshed again together in one gmsh call (``refine 1 3``)."""
    if not {1, 3} <= ctx.job.no_refine:
        ctx.progress("refine 1 3")
        while True:
            time.sleep(1)


def hang_after_meshing(ctx) -> None:
    """Never return once every face is meshed (only the job's hard timeout ends it)."""
    while True:
        time.sleep(1)


def idle_past_the_kill_point(ctx) -> None:
    """Once the mesh is written, wait to halfway between the job's soft deadline and its ``finish_by`` (72.5%
    of the timeout, past the 70% kill point), unless meshing faces again on an edge another process changed
    (``job.adopt``)."""
    if not ctx.job.adopt:
        time.sleep(max(0.0, (ctx.job.deadline + ctx.job.finish_by) / 2 - time.time()))


def lose_a_face_and_hang(ctx) -> None:
    """Once every face is meshed, clear face ``FAULT_FACE`` (as a re-mesh starts) and never return: the hard
    timeout delivers the other faces only."""
    import gmsh

    gmsh.model.mesh.clear([(2, ctx.emap.faces[FAULT_FACE])])
    if ctx.deliver is not None:
        ctx.deliver(2, FAULT_FACE, None)
    while True:
        time.sleep(1)


def hang_before_writing(ctx) -> None:
    """Never return once the mesh is final (re-meshed finer and optimised), before gmsh writes it."""
    while True:
        time.sleep(1)


def remesh_finer(ctx) -> None:
    """Mesh face ``FAULT_FACE`` again with sizes capped at a twentieth of its size (as the surface target's
    re-mesh does, announced by ``refined F``)."""
    import gmsh

    from cadedge.mesh.generate import mesh_faces

    s = ctx.emap.faces[FAULT_FACE]
    box = gmsh.model.getBoundingBox(2, s)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.05 * max(box[3] - box[0], box[4] - box[1], box[5] - box[2]))
    gmsh.model.mesh.clear([(2, s)])
    ctx.outcomes[s] = mesh_faces([s], ctx.emap.face_of_surface)[s]
    ctx.progress(f"refined {FAULT_FACE}")


def break_a_face(ctx) -> None:
    """After meshing, drop one triangle of face ``FAULT_FACE`` (as a faulty optimiser step would leave a hole)."""
    import gmsh

    s = ctx.emap.faces[FAULT_FACE]
    tags, nodes = gmsh.model.mesh.getElementsByType(2, s)
    inner, coords, params = gmsh.model.mesh.getNodes(2, s, includeBoundary=False, returnParametricCoord=True)
    gmsh.model.mesh.clear([(2, s)])  # drops the face's inner nodes too: put them back
    gmsh.model.mesh.addNodes(2, s, list(inner), list(coords), list(params))
    gmsh.model.mesh.addElementsByType(s, 2, list(tags[1:]), list(nodes[3:]))


def spin_first_face(ctx) -> None:
    """Compute forever on the first attempt at face 1 (the first face of the first batch)."""
    if ctx.face == 1 and ctx.strategy == 0:
        while True:
            pass


def busy_a_while(ctx) -> None:
    """Compute for 3 s of CPU on the first attempt at ``FAULT_FACE``, then let it mesh (a slow face, not a
    hung one)."""
    if ctx.face == FAULT_FACE and ctx.strategy == 0:
        end = time.process_time() + 3.0
        while time.process_time() < end:
            pass


def remesh_split(ctx) -> None:
    """``after_generate``: mesh face ``FAULT_FACE`` again on its own by the first strategy that splits its
    curves; its neighbours, outside that call's faces, are meshed again on the split curves."""
    import gmsh

    from cadedge.mesh.generate import mesh_faces
    from cadedge.mesh.strategies import STRATEGIES

    s = ctx.emap.faces[FAULT_FACE]
    first = next(k for k, strategy in enumerate(STRATEGIES) if strategy.split)
    gmsh.model.mesh.clear([(2, s)])
    ctx.outcomes.update(mesh_faces([s], ctx.emap.face_of_surface,
                                   skip={FAULT_FACE: {k: "barred by the test" for k in range(first)}}))


def break_the_writer(ctx) -> None:
    """gmsh's writer fails as it does on a shape it could not import whole: a bare Exception, no reason."""
    import gmsh

    def fail(path: str) -> None:
        raise Exception("")

    gmsh.write = fail


def add_free_surface(ctx) -> None:
    """A square surface in gmsh's model that no face of the shape matches (as an import splitting a face)."""
    import gmsh

    gmsh.model.occ.addRectangle(100.0, 100.0, 0.0, 1.0, 1.0)
    gmsh.model.occ.synchronize()


def spin_in_gmsh(ctx) -> None:
    """``before_face``: on the first attempt at ``FAULT_FACE``, make gmsh compute forever inside its 2-D
    meshing of that face (a size callback that never returns there), as gmsh's own hangs do: the batch
    that holds the face hangs after gmsh has announced it."""
    import gmsh

    from cadedge.mesh.interior import SIZES

    if ctx.face != FAULT_FACE or ctx.strategy != 0:
        return
    surface = ctx.emap.faces[FAULT_FACE]

    def size(dim, tag, x, y, z, lc):
        while dim == 2 and tag == surface:
            pass
        return SIZES(dim, tag, x, y, z, lc)

    gmsh.model.mesh.setSizeCallback(size)
