"""cadedge.occt.reader: STEP files and in-memory shapes in, one-line InputErrors for bad input."""

from __future__ import annotations

import math
import shutil

import pytest

pytest.importorskip("OCP")

from OCP.Bnd import Bnd_Box  # noqa: E402
from OCP.BRepBndLib import BRepBndLib  # noqa: E402
from OCP.TopAbs import TopAbs_COMPOUND, TopAbs_SOLID  # noqa: E402
from OCP.TopoDS import TopoDS_Shape  # noqa: E402

from cadedge.errors import InputError  # noqa: E402
from cadedge.occt import shapedump  # noqa: E402
from cadedge.occt.reader import (LoadedShape, _diagonal_at_least, _diagonal_from_dump, load_shape,  # noqa: E402
                                 tolerance_warnings)
from conftest import CORPUS, FIXTURE_FILES, FIXTURES, corpus_params  # noqa: E402

EMPTY_STEP = """ISO-10303-21;
HEADER;
FILE_DESCRIPTION(('empty'),'2;1');
FILE_NAME('empty.step','2026-01-01T00:00:00',(''),(''),'','','');
FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));
ENDSEC;
DATA;
ENDSEC;
END-ISO-10303-21;
"""


def _diag(shape: TopoDS_Shape) -> float:
    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box, False)
    return box.SquareExtent() ** 0.5


@pytest.mark.parametrize("path", FIXTURE_FILES + corpus_params(), ids=lambda p: p.name)
def test_every_file_loads_in_millimetres(path):
    loaded = load_shape(path)
    assert isinstance(loaded, LoadedShape)
    assert not loaded.shape.IsNull()
    assert loaded.source == path.name
    assert loaded.units == "mm"
    assert all(isinstance(w, str) and "\n" not in w for w in loaded.warnings)


def test_str_path_and_upper_case_suffixes(tmp_path):
    src = FIXTURES / "cylinder.step"
    for name in ("CYL.STEP", "cyl.Stp"):
        shutil.copy(src, tmp_path / name)
        assert load_shape(str(tmp_path / name)).source == name


@pytest.mark.corpus
def test_metre_file_is_converted_to_millimetres():
    # wing_fuselage declares METRE; SOURCES.tsv gives its diagonal as 918.8 after OCCT's transfer to mm
    loaded = load_shape(CORPUS / "live-clones__gmsh__wing_fuselage.step")
    assert loaded.units == "mm"
    assert _diag(loaded.shape) == pytest.approx(918.8, rel=1e-3)


@pytest.mark.corpus
def test_reader_check_messages_become_warnings():
    loaded = load_shape(CORPUS / "live-clones__gmsh__wing_fuselage.step")
    assert any("Poor result from projection vertex / curve 3d" in w for w in loaded.warnings)
    clean = load_shape(CORPUS / "live-clones__gmsh__Kurbelwelle.stp")
    assert clean.warnings == []


@pytest.mark.parametrize("name", ["live-clones__gmsh__mesh_T106_V3.step", "LLNL__axom_data__boxed_sphere.step"])
@pytest.mark.corpus
def test_loose_tolerance_is_a_warning_naming_edge_and_model_size(name):
    loaded = load_shape(CORPUS / name)
    loose = [w for w in loaded.warnings if w.startswith("loose tolerance")]
    assert len(loose) == 1
    assert "edge " in loose[0] and "model size" in loose[0] and "mm" in loose[0]


@pytest.mark.parametrize("name", ["live-clones__gmsh__Kurbelwelle.stp", "live-clones__gmsh__917_fusee.stp",
                                  "live-clones__gmsh__wing_fuselage.step"])
@pytest.mark.corpus
def test_tolerances_within_declared_precision_do_not_warn(name):
    assert not any(w.startswith("loose tolerance") for w in load_shape(CORPUS / name).warnings)


def _one_line_error(source, *needles):
    with pytest.raises(InputError) as info:
        load_shape(source)
    msg = str(info.value)
    assert "\n" not in msg
    for needle in needles:
        assert needle in msg, msg
    return msg


def test_missing_file(tmp_path):
    _one_line_error(tmp_path / "nothere.step", "nothere.step", "no such file")


def test_text_file_named_step(tmp_path):
    path = tmp_path / "notes.step"
    path.write_text("these are not the shapes you are looking for\n")
    _one_line_error(path, "notes.step", "not a STEP file")


def test_a_step_file_opening_with_a_comment_is_read(tmp_path):
    """Part 21 allows comments where white space may be, and OCCT reads a file that opens with one; the
    sniff took it for "not a STEP file" (22 files of the public dodgy-STEP catalogue open so)."""
    from cadedge import refine_shape

    path = tmp_path / "commented.step"
    path.write_bytes(b"/* written by hand,\n   over two lines */\n\n" + (FIXTURES / "bracket.step").read_bytes())
    got, want = refine_shape(path, ald=1e-2), refine_shape(FIXTURES / "bracket.step", ald=1e-2)
    assert [e.segments for e in got.edges] == [e.segments for e in want.edges] and got.faces == want.faces
    path.write_bytes(b"/* a comment, and then no STEP */\nsolid x\n")
    _one_line_error(path, "commented.step", "not a STEP file")


def test_truncated_copy_of_a_fixture(tmp_path):
    data = (FIXTURES / "bracket.step").read_bytes()
    cut = tmp_path / "cut.step"
    cut.write_bytes(data[: len(data) // 2])
    _one_line_error(cut, "cut.step", "truncated")
    # a cut that still ends with a trailer: OCCT's parser rejects it, still one clean line
    patched = tmp_path / "patched.step"
    patched.write_bytes(data[: len(data) // 2] + b"\nEND-ISO-10303-21;\n")
    _one_line_error(patched, "patched.step", "corrupt")


def test_empty_step_and_empty_file(tmp_path):
    empty = tmp_path / "empty.step"
    empty.write_text(EMPTY_STEP)
    _one_line_error(empty, "empty.step", "empty")
    zero = tmp_path / "zero.stp"
    zero.write_bytes(b"")
    _one_line_error(zero, "zero.stp", "empty")


def test_wrong_suffix_and_wrong_object(tmp_path):
    other = tmp_path / "part.iges"
    shutil.copy(FIXTURES / "cylinder.step", other)
    _one_line_error(other, "part.iges", "not an IGES file", "STEP")
    other = tmp_path / "part.obj"
    shutil.copy(FIXTURES / "cylinder.step", other)
    _one_line_error(other, "part.obj", "unsupported file type", ".igs")
    _one_line_error(tmp_path, tmp_path.name, "not a file")
    _one_line_error(42, "int")


def test_bad_file_prints_nothing(tmp_path, capfd):
    data = (FIXTURES / "bracket.step").read_bytes()
    patched = tmp_path / "patched.step"
    patched.write_bytes(data[: len(data) // 3] + b"\nEND-ISO-10303-21;\n")
    with pytest.raises(InputError):
        load_shape(patched)
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_cadquery_workplane_shape_and_multi_value_workplane():
    cq = pytest.importorskip("cadquery")
    wp = cq.Workplane("XY").box(10, 20, 30)
    loaded = load_shape(wp)
    assert loaded.source == "<cadquery Workplane>" and loaded.units == "mm"
    assert loaded.shape.ShapeType() == TopAbs_SOLID
    assert load_shape(wp.val()).source == "<cadquery Solid>"
    two = cq.Workplane("XY").pushPoints([(0, 0), (30, 0)]).box(5, 5, 5)
    assert load_shape(two).shape.ShapeType() == TopAbs_COMPOUND
    _one_line_error(cq.Workplane("XY"), "Workplane", "empty")


def test_build123d_part_and_raw_topods():
    bd = pytest.importorskip("build123d")
    part = bd.Box(10, 20, 30) - bd.Cylinder(3, 30)
    loaded = load_shape(part)
    assert loaded.source.startswith("<build123d")
    assert _diag(loaded.shape) == pytest.approx(math.sqrt(10**2 + 20**2 + 30**2), rel=1e-3)
    raw = load_shape(part.wrapped)
    assert raw.source == "<TopoDS_Shape>" and raw.shape.IsSame(part.wrapped)
    _one_line_error(TopoDS_Shape(), "empty")


@pytest.mark.corpus
def test_units_follow_occts_cascade_unit_setting():
    from OCP.Interface import Interface_Static

    before = Interface_Static.CVal_s("xstep.cascade.unit")
    try:
        assert Interface_Static.SetCVal_s("xstep.cascade.unit", "M")
        loaded = load_shape(CORPUS / "live-clones__gmsh__wing_fuselage.step")
        assert loaded.units == "m"
        assert _diag(loaded.shape) == pytest.approx(0.9188, rel=1e-3)
    finally:
        Interface_Static.SetCVal_s("xstep.cascade.unit", before)
    assert load_shape(FIXTURES / "cylinder.step").units == "mm"


def test_quiet_occt_restores_the_printers():
    from OCP.Message import Message

    from cadedge.occt.reader import quiet_occt

    before = Message.DefaultMessenger_s().Printers().Size()
    with quiet_occt():
        with quiet_occt():
            assert Message.DefaultMessenger_s().Printers().Size() == 0
        assert Message.DefaultMessenger_s().Printers().Size() == 0
    assert Message.DefaultMessenger_s().Printers().Size() == before


@pytest.mark.parametrize("path", FIXTURE_FILES + corpus_params(), ids=lambda p: p.name)
def test_the_vertex_sample_bounds_the_box_diagonal_from_below(path):
    """The box is skipped only where the sampled bound already rules the warning out; the bound must
    never exceed the box it stands for (else a loose tolerance could go unreported)."""
    shape = load_shape(path).shape
    for samples in (2, 32, 10_000):
        assert _diagonal_at_least(shape, 0.0, samples) <= _diag(shape)


@pytest.mark.parametrize("path", FIXTURE_FILES + corpus_params(), ids=lambda p: p.name)
def test_the_scan_from_the_dump_warns_as_the_ocp_scan(path):
    """refine_shape scans the tolerances from the shape's dump where there is one (else through OCP): every
    vertex bounds the box from below, and the warnings (with the file's declared precision, none, and 1e-9,
    which brings the box in on most models) are the OCP scan's; refine_shape passes on load_shape's warnings."""
    from cadedge.occt.shape import refine_shape

    loaded = load_shape(path)
    dump = shapedump.read(loaded.shape)
    if dump is not None:
        assert _diagonal_from_dump(dump, 0.0) <= _diag(loaded.shape)
        for declared in (loaded.declared, None, 1e-9):
            assert tolerance_warnings(loaded.shape, loaded.units, declared, dump) == \
                   tolerance_warnings(loaded.shape, loaded.units, declared)
    assert refine_shape(path, ald=0.1).warnings[:len(loaded.warnings)] == loaded.warnings
