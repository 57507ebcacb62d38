"""B-rep ids in the mesh file: physical groups named after cadedge's faces and edges.

Every B-rep face becomes a physical group of dimension 2 whose tag is its face id (``TopExp::MapShapes``
order, 1-based) and whose name is ``face <id>``; every edge a physical group of dimension 1 tagged with its
edge id and named ``edge <id>``. Users put boundary conditions on CAD faces and edges through them. gmsh
then writes the elements of physical groups only: every triangle belongs to its face's group, so nothing
of the surface mesh is lost.
"""

from __future__ import annotations

import gmsh


def add_physical_groups(emap) -> tuple[int, int]:
    """Add the groups for the entity map ``emap`` to the current gmsh model; returns (faces, edges) added."""
    existing = {(d, t) for d, t in gmsh.model.getPhysicalGroups()}
    surfaces = {t for _, t in gmsh.model.getEntities(2)}
    curves = {t for _, t in gmsh.model.getEntities(1)}
    n_faces = n_edges = 0
    for face, surface in sorted(emap.faces.items()):
        if surface in surfaces and (2, face) not in existing:
            gmsh.model.addPhysicalGroup(2, [surface], tag=face, name=f"face {face}")
            n_faces += 1
    edge_curves = {eid: m.tag for eid, m in emap.edges.items()}
    edge_curves.update(emap.degenerate_curves)
    for eid, curve in sorted(edge_curves.items()):
        if int(curve) in curves and (1, eid) not in existing:
            gmsh.model.addPhysicalGroup(1, [int(curve)], tag=eid, name=f"edge {eid}")
            n_edges += 1
    return n_faces, n_edges


def before_write(ctx) -> None:
    """Hook (``cadedge.mesh.worker``): the groups go in just before the mesh file is written."""
    add_physical_groups(ctx.emap)
