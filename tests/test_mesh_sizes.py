"""Sizes mode (``--mode sizes``: gmsh meshes the curves from our sizes) and the ``.geo`` spacing export,
on real shapes through real gmsh."""

from __future__ import annotations

import copy
import dataclasses
import re
import tempfile
from pathlib import Path

import numpy as np
import pytest

gmsh = pytest.importorskip("gmsh")
cq = pytest.importorskip("cadquery")
pytest.importorskip("trimesh")

import cadedge  # noqa: E402
from cadedge.mesh import mesh_shape  # noqa: E402
from cadedge.mesh.spacing_geo import CLASS_RATIO, size_classes  # noqa: E402
from cadedge.mesh.strategies import STRATEGIES  # noqa: E402

ALD = 1e-2
PROBE = {"after_mesh": ["mesh_probes:curve_segments"]}


def _segments_per_edge(result) -> dict[int, tuple[int, int]]:
    """Edge id -> (grid segments, gmsh curve segments) for every matched, non-degenerate edge."""
    probe = result.extras["mesh_probes:curve_segments"]
    return {e.id: (len(e.points) - 1, probe["segments"][probe["curve_of_edge"][e.id]])
            for e in result.grid.edges if not e.degenerate and e.id in probe["curve_of_edge"]}


def test_sizes_mode_meshes_a_cone_apex_with_curves_that_follow_the_grid():
    """gmsh's surface-curvature sizing split the seam running into a cone's apex far below the grid's
    spacing (3 times its segments here; 52 times on the cone of the hard model ``seams_and_poles``, where
    gmsh then failed three strategies on that face, for a minute): curves now follow the grids, and every
    face meshes at the first strategy."""
    cone = cq.Solid.makeCone(1.5, 0.0, 3.0).wrapped
    result = mesh_shape(cone, ald=ALD, mode="sizes", hooks=PROBE, timeout=120)
    assert result.ok, result.problems(verbose=True)
    assert {f.strategy for f in result.faces} == {STRATEGIES[0].name}
    assert not [n for n in result.notes if "hung" in n or "crashed" in n]
    for eid, (grid, ours) in _segments_per_edge(result).items():
        assert 0.5 * grid <= ours <= 2 * grid + 2, (eid, grid, ours)


def test_sizes_mode_sizes_an_unmatched_curve_from_its_neighbours():
    """A curve no edge grid maps to is graded from the size field on gmsh's own curve, not left at the
    largest size."""
    grid = cadedge.refine_shape(cq.Solid.makeCylinder(2.0, 5.0).wrapped, ald=ALD, max_growth=2.0)
    g = copy.copy(grid)
    g.edges = list(grid.edges)
    e = next(e for e in g.edges if e.curve == "Circle" and len(e.faces) == 2)
    g.edges[e.id - 1] = dataclasses.replace(e, points=e.points + np.array([0.0, 0.0, 0.05]), params=e.params + 0.01)
    result = mesh_shape(g, mode="sizes", hooks=PROBE, timeout=120)
    assert result.ok and result.unmatched_edges == [e.id], result.problems(verbose=True)
    probe = result.extras["mesh_probes:curve_segments"]
    segments = [probe["segments"][t] for t in probe["unmatched_curves"] if probe["segments"][t]]
    assert len(segments) == 1 and segments[0] >= 0.5 * (len(e.points) - 1), (segments, len(e.points) - 1)


def test_size_classes_round_down_within_the_class_ratio():
    sizes = {1: 0.1, 2: 0.14, 3: 0.15, 4: 1.0, 5: 7.3}
    classes = size_classes(sizes, 0.1)
    assert sorted(i for ids in classes.values() for i in ids) == list(sizes)
    for h, ids in classes.items():
        assert all(h <= sizes[i] * (1 + 1e-12) and sizes[i] < h * CLASS_RATIO for i in ids)
    assert classes[0.1] == [1, 2]


def _mesh_geo(path):
    """Open the ``.geo`` as ``gmsh part.geo -2`` would; (curve segment lengths by curve, meshed surfaces)."""
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        gmsh.model.mesh.generate(2)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        x = dict(zip(np.asarray(tags).tolist(), np.asarray(coords).reshape(-1, 3)))
        lengths = {}
        for _, c in gmsh.model.getEntities(1):
            seg = np.asarray(gmsh.model.mesh.getElementsByType(1, c)[1]).reshape(-1, 2)
            lengths[c] = np.array([np.linalg.norm(x[a] - x[b]) for a, b in seg.tolist()])
        surfaces = [t for _, t in gmsh.model.getEntities(2)]
        meshed = [s for s in surfaces if len(gmsh.model.mesh.getElementsByType(2, s)[0])]
        return lengths, surfaces, meshed
    finally:
        gmsh.finalize()


def test_geo_export_grades_a_long_edge_between_fine_vertices(tmp_path):
    """A 100-long bar with 0.1 chamfers at both ends: its long edges run between fine vertices. The
    ``.geo`` sizes them fine at the ends and coarse in the middle, not fine all along."""
    bar = cq.Workplane().box(100, 10, 10).edges("|Y or |Z").edges("<X or >X").chamfer(0.1).val().wrapped
    out = tmp_path / "bar.geo"
    result = mesh_shape(bar, ald=ALD, output=out)
    text = out.read_text()
    assert "Geometry.OCCAutoFix = 0;" in text
    lengths, surfaces, meshed = _mesh_geo(out)
    assert meshed == surfaces
    long_edges = [e.id for e in result.grid.edges if np.sum(e.segment_lengths) > 90]
    assert long_edges
    for c in long_edges:
        seg = lengths[c]
        assert seg.min() < 0.5 and seg.max() > 10 * seg.min(), (c, seg.min(), seg.max())
        assert len(seg) < 100, (c, len(seg))  # uniformly fine (0.5 or less) would be 200 and more


def test_geo_export_has_a_few_fields_per_size_class_not_per_edge(tmp_path):
    """One Distance field per size class for vertices and for curves (a ``Min`` over a few Thresholds):
    gmsh evaluates the background field at every point it places, and hundreds of fields took minutes."""
    plate = cq.Workplane().box(60, 60, 2).faces(">Z").workplane().rarray(10, 10, 5, 5).hole(2.0).val().wrapped
    out = tmp_path / "plate.geo"
    result = mesh_shape(plate, ald=ALD, output=out)
    text = out.read_text()
    distances = re.findall(r"Field\[\d+\] = Distance", text)
    assert len(result.grid.edges) > 80 and 2 <= len(distances) <= 12, len(distances)
    listed = [int(i) for block in re.findall(r"CurvesList = \{([^}]*)\}", text) for i in block.split(",")]
    assert sorted(listed) == sorted(e.id for e in result.grid.edges if not e.degenerate)
    _, surfaces, meshed = _mesh_geo(out)
    assert meshed == surfaces


def test_curves_from_spacings_sets_and_restores_gmsh_options():
    from cadedge.mesh.gmsh_model import gmsh_session
    from cadedge.mesh.sizes import INTEGRATION_PRECISION, curves_from_spacings

    with gmsh_session():
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 20)
        with curves_from_spacings():
            assert gmsh.option.getNumber("Mesh.MeshSizeFromCurvature") == 0
            assert gmsh.option.getNumber("Mesh.LcIntegrationPrecision") == INTEGRATION_PRECISION
        assert gmsh.option.getNumber("Mesh.MeshSizeFromCurvature") == 20
        assert gmsh.option.getNumber("Mesh.LcIntegrationPrecision") == 1e-9


_GEO_CHILD = """
import json, sys
import gmsh
import numpy as np
from cadedge.mesh.check import check_triangles
from cadedge.mesh.readback import read_mesh

gmsh.initialize(readConfigFiles=False)
gmsh.option.setNumber("General.Terminal", 0)
gmsh.open(sys.argv[1])
gmsh.model.mesh.generate(2)
surfaces = [t for _, t in gmsh.model.getEntities(2)]
raw = read_mesh(surfaces)
check = check_triangles(raw.nodes, raw.triangles)
print(json.dumps({"surfaces": len(surfaces), "meshed": len(np.unique(raw.triangle_surfaces)),
                  "min_angle": check.min_angle_deg}))
"""


def _mesh_geo_in_child(path, timeout: float) -> dict:
    """``gmsh part.geo -2`` in a child Python (a gmsh that never ends fails the test, not the session)."""
    import json
    import os
    import subprocess
    import sys

    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(cadedge.__file__).parents[1]),
                                                         os.environ.get("PYTHONPATH", "")])}
    try:
        done = subprocess.run([sys.executable, "-c", _GEO_CHILD, str(path)], capture_output=True, text=True,
                              timeout=timeout, env=env, cwd=path.parent)
    except subprocess.TimeoutExpired:
        pytest.fail(f"gmsh did not mesh {path.name} within {timeout} s")
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_geo_export_caps_a_thin_tube_by_its_curvature(tmp_path):
    """The helical spring (a 0.5-radius circle swept along a helix): sized from its edges alone, its tube
    got triangles wider than the tube, and gmsh split its curves and started again without end (over 120 s
    at ALD 1e-1; 0.7-degree triangles at 1e-2). Its face is now capped by its curvature (a Constant
    field) and meshes in about a second with good triangles."""
    path = cq.Wire.makeHelix(pitch=2.0, height=8.0, radius=3.0)
    spring = cq.Workplane("XZ").center(3.0, 0.0).circle(0.5).sweep(cq.Workplane().add(path), isFrenet=True)
    out = tmp_path / "spring.geo"
    mesh_shape(spring.val().wrapped, ald=1e-1, output=out)
    text = out.read_text()
    caps = [float(h) for h in re.findall(r"= Constant; Field\[\d+\]\.SurfacesList = \{[^}]*\}; Field\[\d+\]\.VIn = "
                                          r"([0-9.e+-]+);", text)]
    assert caps and max(caps) < 2 * np.pi * 0.5, caps  # finer than the tube's circumference
    got = _mesh_geo_in_child(out, timeout=60)
    assert got["meshed"] == got["surfaces"] and got["min_angle"] > 20, got


def test_a_face_that_failed_every_strategy_gets_its_curves_meshed_again_at_other_sizes():
    """``sizes.retry_failed_faces`` (the sizes mode's ``after_generate`` hook): a face whose curve mesh
    no strategy could use (on mesh_T106_V3 gmsh could not recover the loose B-spline edges of the thin
    face 5 in its parameter plane; here the cap's circle simply loses its mesh) has its curves meshed
    again at other sizes and is meshed again with the faces sharing them, every face conforming."""
    from cadedge.mesh.generate import mesh_faces, surface_ok
    from cadedge.mesh.gmsh_model import gmsh_session, import_brep, map_entities, shape_to_brep, surface_curve_uses
    from cadedge.mesh.outcomes import FaceOutcome
    from cadedge.mesh.sizes import SizeField, apply_spacing_sizes, configure_gmsh_sizes, retry_failed_faces
    from cadedge.mesh.worker import JobContext, MeshJob

    grid = cadedge.refine_shape(cq.Solid.makeCylinder(1.0, 2.0).wrapped, ald=ALD, max_growth=2.0)
    field = SizeField(grid)
    job = MeshJob(source="cylinder", brep=b"", grid=grid, field=field, mode="sizes")
    with gmsh_session():
        path = Path(tempfile.mkdtemp()) / "cyl.brep"
        path.write_bytes(shape_to_brep(grid.shape))
        import_brep(str(path))
        ctx = JobContext(job=job, emap=map_entities(grid))
        apply_spacing_sizes(grid, ctx.emap, field)
        configure_gmsh_sizes(field)
        gmsh.model.mesh.generate(1)
        surfaces = [t for _, t in gmsh.model.getEntities(2)]
        ctx.outcomes = mesh_faces(surfaces, ctx.emap.face_of_surface)
        assert all(o.ok for o in ctx.outcomes.values())
        cap = ctx.emap.faces[2]
        gmsh.model.mesh.clear([(2, cap)] + [(1, c) for c in surface_curve_uses(cap)])
        ctx.outcomes[cap] = FaceOutcome(face=2, surface=cap, attempts=[("Frontal-Delaunay", "0 nodes")])
        retry_failed_faces(ctx)
        assert all(o.ok for o in ctx.outcomes.values()), ctx.outcomes
        assert "spacing sizes" in ctx.outcomes[cap].strategy
        assert ctx.outcomes[cap].attempts == [("Frontal-Delaunay", "0 nodes")]
        assert all(surface_ok(s) for s in surfaces)
