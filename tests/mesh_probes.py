"""Measurements taken inside the gmsh child process by the mesh tests (hooks of cadedge.mesh.worker)."""

from __future__ import annotations


def curve_segments(ctx) -> dict:
    """``after_mesh`` hook: line elements on every gmsh curve, the curve of each matched edge, and the
    curves no edge maps to."""
    import gmsh

    return {"segments": {t: len(gmsh.model.mesh.getElementsByType(1, t)[0]) for _, t in gmsh.model.getEntities(1)},
            "curve_of_edge": {eid: m.tag for eid, m in ctx.emap.edges.items()},
            "unmatched_curves": list(ctx.emap.unmatched_curves)}


def smoothed(ctx) -> list[int]:
    """``after_mesh`` hook: the faces the face optimiser changed (``cadedge.mesh.optimize``)."""
    return list(getattr(ctx, "smoothed", []))


def share(ctx) -> list[float]:
    """``after_mesh`` hook: the job's share of the whole job's faces (``MeshJob.share``; under 1 in a shard)."""
    return [ctx.job.share]


def small_budget(ctx) -> None:
    """``before_generate``: a triangle budget of 2 000 a face (:data:`cadedge.mesh.budget.MAX_FACE_TRIANGLES`):
    curved faces come out over their surface target with their budget held, as a long thin fillet does at
    1e-3 with the real budget."""
    import cadedge.mesh.budget

    cadedge.mesh.budget.MAX_FACE_TRIANGLES = 2_000
