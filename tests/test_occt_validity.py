"""OCCT's own check of faces gmsh could not mesh (cadedge.occt.validity): a real broken sweep."""

from __future__ import annotations

import pytest

cq = pytest.importorskip("cadquery")

from cadedge import refine_shape  # noqa: E402
from cadedge.mesh import _with_brep_checks  # noqa: E402
from cadedge.mesh.generate import FaceFailure  # noqa: E402
from cadedge.occt.validity import face_problems  # noqa: E402


def _mitred_tube():
    """An annulus swept along a path with a right-angle corner (cadquery's default 'right' transition):
    four of its eight faces fail BRepCheck (wires not closed or crossing themselves); gmsh cannot mesh
    them either."""
    path = cq.Workplane("XZ").moveTo(0, 0).lineTo(0, 20).radiusArc((15, 35), -15).lineTo(40, 35)
    return cq.Workplane("XY").circle(4).circle(3).sweep(path).val()


def test_broken_faces_are_found_and_said_in_words_and_sound_ones_are_not():
    shape = _mitred_tube().wrapped
    problems = face_problems(shape, list(range(1, 9)))
    assert sorted(problems) == [1, 3, 5, 7]
    assert "a wire not closed" in problems[1] and all(problems.values())
    assert face_problems(cq.Workplane("XY").box(1, 2, 3).val().wrapped, list(range(1, 7))) == {}


def test_a_failed_faces_reason_says_when_the_face_itself_is_invalid():
    grid = refine_shape(_mitred_tube(), ald=1e-2)
    failures = [FaceFailure(face=f, surface=f, reason="gmsh's reason") for f in (1, 2)]
    out = _with_brep_checks(grid, failures)
    assert out[0].reason.startswith("gmsh's reason; the B-rep face itself is invalid (OCCT's BRepCheck: ")
    assert out[1].reason == "gmsh's reason"  # face 2 passes the check
