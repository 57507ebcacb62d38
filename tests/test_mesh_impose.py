"""The edge grids imposed on gmsh's curves (cadedge/mesh/impose.py): one merged MSH file, node for node."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gmsh")

import cadedge  # noqa: E402

from conftest import FIXTURES  # noqa: E402


@pytest.fixture(scope="module")
def bracket() -> cadedge.ShapeGrid:
    return cadedge.refine_shape(FIXTURES / "bracket.step", ald=1e-3, max_growth=2.0)


def test_every_grid_point_is_a_node_of_its_curve_bit_for_bit(bracket, tmp_path):
    """Each edge's interior points become its gmsh curve's nodes with the exact coordinates and gmsh
    parameters (in gmsh's direction of the curve, reversed where it runs the other way), each vertex one
    node on its point, and the line elements chain them from vertex to vertex; an adopted 1-D mesh
    replaces its edge's grid."""
    import gmsh

    from cadedge.mesh.gmsh_model import gmsh_session, import_brep, map_entities, shape_to_brep
    from cadedge.mesh.impose import impose_edge_grids

    path = tmp_path / "b.brep"
    path.write_bytes(shape_to_brep(bracket.shape))
    with gmsh_session():
        import_brep(str(path))
        emap = map_entities(bracket)
        edge = next(e for e in bracket.edges if not e.degenerate and e.id in emap.edges and len(e.points) > 3)
        match = emap.edges[edge.id]
        t = np.linspace(match.params[0], match.params[-1], 7)  # another process's mesh of that curve
        adopted = np.asarray(gmsh.model.getValue(1, match.tag, t.tolist())).reshape(-1, 3)
        adopted[[0, -1]] = edge.points[[0, -1]]
        imposed = impose_edge_grids(bracket, emap, {edge.id: (adopted, t)})
        assert not imposed.skipped and len(imposed.edge_nodes) == sum(not e.degenerate for e in bracket.edges)
        for e in bracket.edges:
            if e.degenerate:
                continue
            m = emap.edges[e.id]
            points, params = (adopted, t) if e.id == edge.id else (e.points, m.params)
            chain = imposed.edge_nodes[e.id]
            tags, xyz, par = gmsh.model.mesh.getNodes(1, m.tag, includeBoundary=False, returnParametricCoord=True)
            order = slice(None) if params[-1] > params[0] else slice(None, None, -1)
            assert np.array_equal(np.asarray(tags), chain[1:-1][order])
            assert np.array_equal(np.reshape(xyz, (-1, 3)), points[1:-1][order])  # bit for bit
            assert np.array_equal(np.asarray(par), params[1:-1][order])
            _, lines = gmsh.model.mesh.getElementsByType(1, m.tag)
            along = chain[order]
            assert np.array_equal(np.reshape(lines, (-1, 2)), np.column_stack([along[:-1], along[1:]]))
            for vid, end in zip(e.vertices, (chain[0], chain[-1])):
                coord, _, dim, _ = gmsh.model.mesh.getNode(int(end))
                assert dim == 0 and np.array_equal(coord, bracket.vertices[vid - 1].point)
