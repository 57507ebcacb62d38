"""cadedge mesh on kinds of input the corpus lacks: IGES files of unsewn trimmed surfaces (real OCCT, real gmsh)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gmsh")
pytest.importorskip("trimesh")
cq = pytest.importorskip("cadquery")

from cadedge.mesh import mesh_shape  # noqa: E402


def _iges_cylinder(path) -> None:
    """A cylinder written as IGES trimmed surfaces (faces mode, no shared topology): its seam comes back
    as two distinct edges of the one face, lying on each other."""
    from OCP.IGESControl import IGESControl_Writer

    writer = IGESControl_Writer("MM", 0)
    writer.AddShape(cq.Workplane().cylinder(2, 1).val().wrapped)
    writer.ComputeModel()
    assert writer.Write(str(path))


def test_an_iges_face_whose_seam_is_two_edges_is_not_a_crack(tmp_path):
    """The two seam edges of the IGES cylinder carry grid nodes at the same coordinates (max_length splits
    both alike); they bound the face once each, so the face is open there in the B-rep itself. The check
    called those nodes a crack and a valid file ended with exit 1."""
    path = tmp_path / "cylinder.igs"
    _iges_cylinder(path)
    result = mesh_shape(path, ald=1e-1, max_length=0.5, timeout=120)
    seam = [e for e in result.grid.edges if len(e.faces) == 1 and not e.degenerate
            and not np.allclose(e.points[0], e.points[-1])]
    assert len(seam) == 2  # the seam, as two open edges of the lateral face
    assert result.ok, result.problems(verbose=True)
    assert set(np.unique(result.triangle_faces)) == set(range(1, result.grid.faces + 1))
    assert result.check.duplicate_nodes == 0


def test_an_empty_solid_does_not_cost_the_mesh(tmp_path):
    """A compound holding a solid with no shell (as OCCT's own sample Axis_of_bearing.brep does) stopped
    gmsh's import and then its ``.msh`` writer, giving no reason: every face was meshed, all were
    reported failed and nothing was written. The empty solid is left out of the shape gmsh meshes."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepTools import BRepTools
    from OCP.TopoDS import TopoDS_Compound, TopoDS_Solid

    from cadedge.occt.empty import without_empty
    from cadedge.occt.topology import indexed
    from OCP.TopAbs import TopAbs_FACE

    builder, compound, empty = BRep_Builder(), TopoDS_Compound(), TopoDS_Solid()
    builder.MakeCompound(compound)
    builder.MakeSolid(empty)
    builder.Add(compound, cq.Workplane().box(2, 1, 1).val().wrapped)
    builder.Add(compound, empty)
    builder.Add(compound, cq.Workplane().cylinder(2, 1).translate((3, 0, 0)).val().wrapped)
    pruned, left_out = without_empty(compound)
    assert left_out == ["1 empty solid"]
    before, after = indexed(compound, TopAbs_FACE), indexed(pruned, TopAbs_FACE)
    assert [after.FindKey(i).IsSame(before.FindKey(i)) for i in range(1, 10)] == [True] * 9
    assert without_empty(pruned) == (pruned, [])
    path, out = tmp_path / "with_empty.brep", tmp_path / "with_empty.msh"
    assert BRepTools.Write_s(compound, str(path))
    result = mesh_shape(path, ald=1e-2, output=out, timeout=120)
    assert result.ok and not result.failures, result.problems(verbose=True)
    assert set(np.unique(result.triangle_faces)) == set(range(1, 10)) and out.exists()
    assert "1 empty solid (holding no face) left out of the shape gmsh meshes" in result.notes
