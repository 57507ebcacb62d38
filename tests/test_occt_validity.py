"""OCCT's own check of faces gmsh could not mesh (cadedge.occt.validity): a real broken sweep, built with
build123d so the check runs on both OCP lines (OCP 8 cannot read BRepCheck's lists of statuses)."""

from __future__ import annotations

import numpy as np
import pytest

b3d = pytest.importorskip("build123d")

from cadedge import refine_shape  # noqa: E402
from cadedge.mesh import _invalid_faces, _with_brep_checks  # noqa: E402
from cadedge.mesh.outcomes import FaceFailure, FaceOutcome  # noqa: E402
from cadedge.mesh.strategies import (EXTRUSION_ORDER, INVALID_FACE_STRATEGIES, STRATEGIES,  # noqa: E402
                                     invalid_face_skips)
from cadedge.occt.validity import face_problems  # noqa: E402


def _mitred_tube():
    """A ring swept along a path with a right-angle corner ('right' transition): four of its eight faces
    fail BRepCheck (their wires are not closed); gmsh cannot mesh them either."""
    with b3d.BuildLine(b3d.Plane.XZ) as path:
        b3d.Line((0, 0), (0, 20))
        b3d.RadiusArc((0, 20), (15, 35), -15)
        b3d.Line((15, 35), (40, 35))
    with b3d.BuildSketch() as ring:
        b3d.Circle(4)
        b3d.Circle(3, mode=b3d.Mode.SUBTRACT)
    return b3d.sweep(ring.sketch, path.line, transition=b3d.Transition.RIGHT)


def test_broken_faces_are_found_and_said_in_words_and_sound_ones_are_not():
    tube = _mitred_tube()
    problems = face_problems(tube.wrapped, list(range(1, len(tube.faces()) + 1)))
    assert sorted(problems) == [1, 3, 5, 7]
    assert all("a wire not closed" in p for p in problems.values())
    assert face_problems(b3d.Box(1, 2, 3).wrapped, list(range(1, 7))) == {}


def test_a_failed_faces_reason_says_when_the_face_itself_is_invalid():
    grid = refine_shape(_mitred_tube(), ald=1e-2)
    problems = _invalid_faces(grid)
    assert sorted(problems) == [1, 3, 5, 7]
    failures = [FaceFailure(face=f, surface=f, reason="gmsh's reason") for f in (1, 2)]
    out = _with_brep_checks(failures, problems)
    assert out[0].reason == ("gmsh's reason; the B-rep face itself is invalid (OCCT's BRepCheck: "
                             "a wire not closed)")
    assert out[1].reason == "gmsh's reason"  # face 2 passes the check


def test_a_face_of_no_area_is_tried_only_as_gmsh_alone_would_mesh_it():
    """A face whose B-rep area is 0 (:func:`~cadedge.mesh.fidelity.without_degenerate`) is barred from the
    other strategies as an invalid one is: SparkFun's FlexyPin STEP file has cylinder faces of no area
    between coinciding curves, and one of them hung gmsh for 60 s twice among the 12 strategies."""
    grid = refine_shape(b3d.Box(1, 2, 3), ald=1e-2)
    areas = np.array([6.0, 0.0, 6.0, 3.0, 3.0, 2.0])
    problems = _invalid_faces(grid, areas)
    assert problems == {2: "it has no area"}
    assert _invalid_faces(grid) == {}
    failures = _with_brep_checks([FaceFailure(face=2, surface=2, reason="gmsh's reason")], problems)
    assert failures[0].reason == "gmsh's reason; the B-rep face itself is invalid (it has no area)"
    assert set(range(len(STRATEGIES))) - set(invalid_face_skips(problems)[2]) == set(INVALID_FACE_STRATEGIES)


def test_an_invalid_face_is_tried_only_as_gmsh_alone_would_mesh_it():
    """Every strategy but the first and gmsh's own curve mesh is barred, with the check's words; the
    failed face's reason counts the two tried apart from those not tried."""
    skips = invalid_face_skips({3: "OCCT's BRepCheck: a wire not closed"})
    barred = skips[3]
    assert set(range(len(STRATEGIES))) - set(barred) == set(INVALID_FACE_STRATEGIES)
    assert [STRATEGIES[k].name for k in INVALID_FACE_STRATEGIES] == [
        "Frontal-Delaunay", "gmsh's own curve mesh, Frontal-Delaunay"]
    assert barred[1] == "not tried: the B-rep face is invalid (OCCT's BRepCheck: a wire not closed)"
    outcome = FaceOutcome(face=3, surface=3, attempts=[
        (STRATEGIES[k].name, barred.get(k, "gmsh's reason")) for k in EXTRUSION_ORDER])
    assert outcome.reason() == f"Frontal-Delaunay: gmsh's reason (1 other strategies failed, " \
                               f"{len(EXTRUSION_ORDER) - 2} not tried)"
