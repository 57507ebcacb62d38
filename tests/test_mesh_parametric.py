"""A face meshed in its own parameters laid flat (cadedge.mesh.parametric): the last strategy of every face,
for faces gmsh's periodic mesher gives up on."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

gmsh = pytest.importorskip("gmsh")
pytest.importorskip("OCP")

RADIUS, HEIGHT = 12.0, 3.0


def _bspline_tube():
    """A cylinder of :data:`RADIUS` and :data:`HEIGHT` with every face turned into a B-spline (its side a
    periodic B-spline surface with a seam, bounded by two closed curves), as a TopoDS shape."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_NurbsConvert
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt

    cylinder = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), RADIUS, HEIGHT).Shape()
    return BRepBuilderAPI_NurbsConvert(cylinder, True).Shape()


def _angles_and_area(xyz: np.ndarray, tri: np.ndarray) -> tuple[float, float]:
    from cadedge.mesh.quality import triangle_angles

    t = xyz[tri]
    area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum()
    return float(triangle_angles(xyz, tri).min()), float(area)


def test_a_periodic_face_is_meshed_in_its_parameters_on_its_curves_as_they_are(tmp_path):
    """The tube's side, its rims split into 53 and 23 segments and its seam into 4: laid flat it meshes on
    exactly those nodes (each rim's closing node and the seam's on both sides of the seam), every new node
    on the surface at its parameters, its triangles over 20 degrees, its area between the prism's on its
    finer rim's chords and the cylinder's."""
    from OCP.BRepTools import BRepTools

    from cadedge.mesh.generate import surface_ok
    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.parametric import mesh_parametric

    path = tmp_path / "tube.brep"
    BRepTools.Write_s(_bspline_tube(), str(path))
    with gmsh_session():
        gmsh.open(str(path))
        side = min((s for _, s in gmsh.model.getEntities(2)), key=lambda s: gmsh.model.occ.getMass(2, s))
        curves = [abs(c) for _, c in gmsh.model.getBoundary([(2, side)], combined=False, oriented=False)]
        rims = sorted({c for c in curves if curves.count(c) == 1})
        (seam,) = {c for c in curves if curves.count(c) == 2}
        for curve, n in zip(rims + [seam], (54, 24, 5)):
            gmsh.model.mesh.setTransfiniteCurve(curve, n)
        gmsh.model.mesh.generate(1)
        boundary = {int(t) for c in curves for t in gmsh.model.mesh.getNodes(1, c, includeBoundary=True)[0]}
        assert mesh_parametric(side, 6) is None
        assert surface_ok(side)
        _, tri = gmsh.model.mesh.getElementsByType(2, side)
        used = set(np.asarray(tri, dtype=np.int64).tolist())
        tags, coords, params = gmsh.model.mesh.getNodes(2, side)
        assert len(tags) and boundary <= used and used - boundary == set(np.asarray(tags).tolist())
        on = np.reshape(gmsh.model.getValue(2, side, list(params)), (-1, 3))
        assert np.abs(on - np.reshape(coords, (-1, 3))).max() < 1e-9
        nodes, xyz, _ = gmsh.model.mesh.getNodes()
        row = {int(t): i for i, t in enumerate(nodes)}
        angle, area = _angles_and_area(np.reshape(xyz, (-1, 3)),
                                       np.array([row[int(t)] for t in tri]).reshape(-1, 3))
        assert angle > 20.0
        chords = 53 * 2 * RADIUS * math.sin(math.pi / 53)
        assert chords * HEIGHT < area < 2 * math.pi * RADIUS * HEIGHT


def test_faces_whose_parameters_stretch_are_not_laid_flat():
    """A sphere's parameters degenerate at its poles; a cone's stretch along it (its circles shrink to the
    apex): neither is laid flat, and the face is left empty with the reason."""
    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.parametric import mesh_parametric, scales

    with gmsh_session():
        gmsh.model.occ.addSphere(0, 0, 0, 1.0)
        gmsh.model.occ.addCone(5, 0, 0, 0, 0, 4, 2.0, 0.5)
        gmsh.model.occ.synchronize()
        gmsh.model.mesh.generate(1)
        sphere = next(s for _, s in gmsh.model.getEntities(2) if gmsh.model.getType(2, s) == "Sphere")
        cone = next(s for _, s in gmsh.model.getEntities(2) if gmsh.model.getType(2, s) == "Cone")
        for surface in (sphere, cone):
            why = mesh_parametric(surface, 6)
            assert isinstance(why, str) and isinstance(scales(surface), str)
            assert "uneven" in why or "degenerate" in why
            assert not len(gmsh.model.mesh.getElementsByType(2, surface)[0])


def test_a_face_every_gmsh_strategy_fails_on_is_meshed_laid_flat_on_its_grids():
    """Every gmsh strategy barred on the tube's side (as gmsh's periodic mesher bars them all on some
    B-spline faces: "Impossible to mesh periodic surface"): it is meshed laid flat, on the edge grids as
    refined (every grid node a mesh node, no segment added), watertight with its caps, within the target."""
    import cadedge
    from cadedge.mesh.check import check_triangles
    from cadedge.mesh.gmsh_model import shape_to_brep
    from cadedge.mesh.sizes import SizeField
    from cadedge.mesh.strategies import STRATEGIES
    from cadedge.mesh.worker import MeshJob, run_job
    from cadedge.occt.areas import face_area
    from cadedge.occt.topology import Topology

    ald = 1e-2
    shape = _bspline_tube()
    grid = cadedge.refine_shape(shape, ald=ald)
    faces = Topology(shape).faces
    areas = [face_area(f) for f in faces]
    side = 1 + int(np.argmin(areas))  # the caps are larger
    last = next(k for k, s in enumerate(STRATEGIES) if s.unrolled == "parameters")
    job = MeshJob(source="tube", brep=shape_to_brep(shape), grid=dataclasses.replace(grid, shape=None),
                  field=SizeField(grid), mode="nodes", skip={side: {k: "barred by the test" for k in range(last)}})
    res = run_job(job)
    outcome = next(o for o in res.faces if o.face == side)
    assert outcome.ok and outcome.strategy == STRATEGIES[last].name
    assert all(o.ok for o in res.faces)
    multiplicity = {(int(a), int(b)): int(n) for (a, b), n in zip(res.edge_pairs, res.edge_uses)}
    check = check_triangles(res.nodes, res.triangles, triangle_faces=res.triangle_faces,
                            grid_points=np.vstack([e.points for e in grid.edges]), edge_multiplicity=multiplicity)
    assert check.ok and check.missing_grid_nodes == 0 and all(s.watertight for s in check.shells)
    assert len(res.edge_pairs) == sum(e.segments for e in grid.edges)
    angle, area = _angles_and_area(res.nodes, res.triangles[res.triangle_faces == side])
    assert angle > 20.0
    assert abs(1 - area / areas[side - 1]) < ald  # triangles across a band can be larger than it
