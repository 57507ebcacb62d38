"""IGES and OCCT BREP inputs, written by OCCT at test time from the STEP fixtures: the same edges in
the same MapShapes order as the STEP, units converted, read by every command, and bad files refused
with one line saying which problem it is."""

from __future__ import annotations

import json
import re
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.Bnd import Bnd_Box  # noqa: E402
from OCP.BRepBndLib import BRepBndLib  # noqa: E402
from OCP.BRepTools import BRepTools  # noqa: E402
from OCP.IGESControl import IGESControl_Controller, IGESControl_Writer  # noqa: E402
from OCP.Interface import Interface_Static  # noqa: E402

import cadedge  # noqa: E402
from cadedge.cli import main  # noqa: E402
from cadedge.errors import InputError  # noqa: E402
from cadedge.occt.reader import load_shape, quiet_occt  # noqa: E402
from conftest import FIXTURE_FILES, FIXTURES  # noqa: E402


@contextmanager
def _brep_mode():
    """IGES written as B-rep entities (shared edges), as CAD systems exchange solids."""
    IGESControl_Controller.Init_s()
    before = Interface_Static.IVal_s("write.iges.brep.mode")
    Interface_Static.SetIVal_s("write.iges.brep.mode", 1)
    try:
        yield
    finally:
        Interface_Static.SetIVal_s("write.iges.brep.mode", before)


def write_iges(step: Path, dest: Path, unit: str = "MM") -> Path:
    shape = load_shape(step).shape
    with quiet_occt(), _brep_mode():
        writer = IGESControl_Writer(unit, 1)
        writer.AddShape(shape)
        writer.ComputeModel()
        assert writer.Write(str(dest))
    return dest


def write_brep(step: Path, dest: Path) -> Path:
    assert BRepTools.Write_s(load_shape(step).shape, str(dest))
    return dest


def _signature(grid: cadedge.ShapeGrid) -> list[tuple]:
    return [(e.id, e.curve, e.vertices, tuple(e.faces), e.degenerate) for e in grid.edges]


@pytest.mark.parametrize("step", FIXTURE_FILES, ids=lambda p: p.stem)
@pytest.mark.parametrize("fmt", ["igs", "brep"])
def test_same_edges_in_the_same_order_as_the_step(tmp_path, step, fmt):
    other = (write_iges if fmt == "igs" else write_brep)(step, tmp_path / f"{step.stem}.{fmt}")
    a = cadedge.refine_shape(step, ald=1e-3)
    b = cadedge.refine_shape(other, ald=1e-3)
    assert b.source == other.name and b.units == "mm"
    assert _signature(b) == _signature(a)
    assert np.allclose([v.point for v in b.vertices], [v.point for v in a.vertices], rtol=0, atol=1e-6)
    for ea, eb in zip(a.edges, b.edges):
        assert np.allclose(eb.points[[0, -1]], ea.points[[0, -1]], rtol=0, atol=1e-6)
        assert eb.length == pytest.approx(ea.length, rel=1e-6, abs=1e-9)
        assert eb.ald_estimate <= 1e-3


def _diag(shape) -> float:
    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box, False)
    return box.SquareExtent() ** 0.5  # not box.Get(): OCP 8.0 cannot return its Limits struct


def test_iges_in_inches_is_read_in_millimetres(tmp_path):
    step = FIXTURES / "bracket.step"
    inches = write_iges(step, tmp_path / "bracket_in.igs", unit="IN")
    assert b"4HINCH" in inches.read_bytes()  # the global section declares inches
    loaded = load_shape(inches)
    assert loaded.units == "mm"
    assert _diag(loaded.shape) == pytest.approx(_diag(load_shape(step).shape), rel=1e-6)


def test_every_command_reads_iges_and_brep(tmp_path, capsys):
    step = FIXTURES / "spline_prism.step"
    files = [write_iges(step, tmp_path / "prism.IGES"), write_brep(step, tmp_path / "prism.brep")]
    for path in files:
        out = tmp_path / f"{path.suffix[1:]}.json"
        assert main(["refine", str(path), "--ald", "1e-3", "-o", str(out), "--quiet"]) == 0
        doc = json.loads(out.read_text())
        assert doc["source"] == path.name and doc["summary"]["edges"] == 12
        assert main(["info", str(path)]) == 0
        assert "faces 6, edges 12, vertices 8" in capsys.readouterr().out
    pytest.importorskip("gmsh")
    mesh = tmp_path / "prism.msh"
    assert main(["mesh", str(files[0]), "--ald", "1e-2", "-o", str(mesh), "--quiet"]) == 0
    assert mesh.is_file()


def test_batch_finds_iges_and_brep_in_folders(tmp_path):
    pytest.importorskip("distributed")
    from cadedge.batch import expand_inputs, run_batch

    src = tmp_path / "in"
    src.mkdir()
    write_iges(FIXTURES / "cylinder.step", src / "a.igs")
    write_brep(FIXTURES / "sphere.step", src / "b.brep")
    (src / "notes.txt").write_text("not a model")
    assert [p.name for p in expand_inputs([src])] == ["a.igs", "b.brep"]
    report = run_batch([src], tmp_path / "out", ald=1e-2, workers=1)
    assert report.all_ok and sorted(Path(r.output).name for r in report.ok) == ["a.json", "b.json"]


def _error(path: Path) -> str:
    with pytest.raises(InputError) as info:
        load_shape(path)
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith(f"{path}: ")
    return msg


def test_bad_iges_files_say_which_problem(tmp_path):
    good = write_iges(FIXTURES / "bracket.step", tmp_path / "good.igs").read_bytes()
    lines = good.splitlines(keepends=True)
    cases = {
        "cut.igs": b"".join(lines[: len(lines) // 2]),
        "padded.igs": b"".join(lines[: len(lines) // 2] + lines[-1:]),  # cut, terminate line put back
        "step.igs": (FIXTURES / "cylinder.step").read_bytes(),
        "text.iges": b"hello\n",
        "zero.igs": b"",
    }
    expected = {"cut.igs": "truncated IGES file", "padded.igs": "truncated or corrupt IGES file",
                "step.igs": "not an IGES file (it holds STEP text", "text.iges": "not an IGES file",
                "zero.igs": "empty file"}
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
        assert expected[name] in _error(tmp_path / name)


def test_bad_brep_files_say_which_problem(tmp_path, capfd):
    good = write_brep(FIXTURES / "bracket.step", tmp_path / "good.brep").read_bytes()
    capfd.readouterr()
    cases = {"cut.brep": good[: int(len(good) * 0.8)], "head.brep": good[:200], "text.brep": b"hello\n",
             "zero.brep": b""}
    expected = {"cut.brep": "truncated BREP file", "head.brep": "truncated or corrupt BREP file",
                "text.brep": "not an OCCT BREP file", "zero.brep": "empty file"}
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
        assert expected[name] in _error(tmp_path / name)
    out, err = capfd.readouterr()
    assert out == "" and err == ""  # OCCT never got to print its own complaints


def test_a_brep_that_crashes_or_trips_occts_reader_is_one_clean_error(tmp_path, capfd):
    """OCCT's BREP reader ran in the caller: a curve record of a type it does not know crashed the
    process (SIGSEGV), a shape referring to a shape the file does not hold raised an exception OCP does
    not map to Standard_Failure (a traceback), and a table count of a billion kept it reading for minutes.
    Now the read runs in another process and each is one line naming the file."""
    good = write_brep(FIXTURES / "bracket.step", tmp_path / "good.brep").read_bytes()
    capfd.readouterr()
    curves = re.search(rb"^Curves \d+\n", good, re.MULTILINE).end()
    shapes = re.search(rb"^TShapes \d+\n", good, re.MULTILINE).end()
    reference = re.compile(rb"^([+-])\d+ (\d+ )", re.MULTILINE).search(good, shapes)
    cases = {
        "type.brep": good[:curves] + b"9" + good[curves + 1:],
        "index.brep": good[:reference.start()] + reference.group(1) + b"99999 " + reference.group(2)
        + good[reference.end():],
        "count.brep": re.sub(rb"^Curve2ds \d+", b"Curve2ds 999999999", good, count=1, flags=re.MULTILINE),
    }
    expected = {"type.brep": "corrupt BREP file: OCCT crashed reading it (signal SIGSEGV)",
                "index.brep": "corrupt BREP file (OCCT could not read it: Standard_OutOfRange",
                "count.brep": "corrupt BREP file (its Curve2ds table declares 999999999 records"}
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
        assert expected[name] in _error(tmp_path / name)
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_a_brep_saved_by_occts_draw_is_read_whole(tmp_path):
    """Draw's ``save`` heads the shape with its drawable's type (as BRepTools::Write now does too)
    and ends it with a "0" line (OCCT's own sample files are written so); OCCT reads them, so the
    check must not refuse them."""
    good = write_brep(FIXTURES / "bracket.step", tmp_path / "good.brep").read_bytes()
    good = good if good.startswith(b"DBRep_DrawableShape") else b"DBRep_DrawableShape\n\n" + good
    drawn = tmp_path / "drawn.brep"
    drawn.write_bytes(good.rstrip() + b"\n0\n\n")
    assert _signature(cadedge.refine_shape(drawn, ald=1e-2)) == _signature(cadedge.refine_shape(
        tmp_path / "good.brep", ald=1e-2))
    drawn.write_bytes(good[: int(len(good) * 0.8)] + b"\n0\n\n")
    assert "truncated BREP file" in _error(drawn)


def test_a_brep_with_an_internal_root_or_text_after_its_root_is_read_whole(tmp_path):
    """gmsh's own benchmark files: SlenderSurface.brep's root shape is INTERNAL (``i1 0``), and
    unable_to_recover_edge_2d-2.brep has 44 lines of a .geo script after its root reference (``+1 1 //+``);
    OCCT reads both whole, and the check refused both as truncated. The second is read with a warning."""
    good = write_brep(FIXTURES / "bracket.step", tmp_path / "good.brep").read_bytes().rstrip()
    expected = _signature(cadedge.refine_shape(tmp_path / "good.brep", ald=1e-2))
    head, root = good.rsplit(b"\n", 1)
    assert root[:1] in (b"+", b"-")
    internal = tmp_path / "internal.brep"
    internal.write_bytes(head + b"\ni" + root[1:] + b" \n")
    assert _signature(cadedge.refine_shape(internal, ald=1e-2)) == expected
    assert load_shape(internal).warnings == []
    junk = tmp_path / "junk.brep"
    junk.write_bytes(good + b' //+\nField[2].F = "1500 + 600 * sin (x/500)";\n//+\n')
    assert load_shape(junk).warnings == [
        "BREP file: 3 lines of text after the root shape reference ignored (OCCT's reader reads none of it)"]
    assert _signature(cadedge.refine_shape(junk, ald=1e-2)) == expected


def test_an_iges_face_pointing_at_nothing_is_a_partial_transfer(tmp_path):
    lines = write_iges(FIXTURES / "bracket.step", tmp_path / "good.igs").read_bytes().split(b"\n")
    i = next(k for k, line in enumerate(lines) if line.startswith(b"510,"))  # the first face entity
    data, sequence = lines[i][:64], lines[i][64:]
    lines[i] = re.sub(rb"^510,\d+,", b"510,9999,", data.rstrip()).ljust(64) + sequence  # its surface: none
    bad = tmp_path / "bad.igs"
    bad.write_bytes(b"\n".join(lines))
    msg = _error(bad)
    assert "partial transfer refused" in msg and "1 entity skipped by the transfer" in msg
    loaded = load_shape(bad, allow_partial=True)
    assert loaded.warnings[0].startswith("partial transfer: ")
    assert any("face D5 transfer failed" in w for w in loaded.warnings)


def test_the_reader_and_the_batch_share_one_list_of_suffixes_without_loading_occt():
    import subprocess
    import sys

    from cadedge.batch import inputs
    from cadedge.formats import INPUT_FORMATS, INPUT_SUFFIXES
    from cadedge.occt import reader

    assert reader.SUFFIXES is INPUT_FORMATS and inputs.INPUT_SUFFIXES is INPUT_SUFFIXES
    assert set(INPUT_FORMATS.values()) == {"STEP", "IGES", "BREP"}
    code = "import sys, cadedge.batch.inputs; print('OCP' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout == "False\n"
