"""``cadedge refine`` and ``cadedge info`` in-process through ``cadedge.cli.main`` on real STEP files:
success paths, the summary table, plots, warnings, the progress bar, and every bad-input case
(exit 2, one stderr line naming the file, no traceback, no output file)."""

from __future__ import annotations

import io
import json
import re
import shutil
from pathlib import Path

import pytest

pytest.importorskip("OCP")

from cadedge.cli import main  # noqa: E402
from cadedge.cli.refine import Progress  # noqa: E402
from cadedge.exporters import FORMATS  # noqa: E402
from cadedge.exporters.json import validate  # noqa: E402

from conftest import CORPUS, FIXTURES
BRACKET = FIXTURES / "bracket.step"
SPHERE = FIXTURES / "sphere.step"
CUBE_FILET = CORPUS / "live-clones__gmsh__cube_filet.stp"  # 74 edges: Line 34, Circle 32, 8 degenerate


def _table_rows(stdout: str) -> dict[str, list[str]]:
    return {parts[0]: parts[1:] for line in stdout.splitlines() if (parts := line.split())}


def test_refine_writes_json_and_prints_summary(tmp_path, capsys):
    out = tmp_path / "bracket.json"
    assert main(["refine", str(BRACKET), "--ald", "1e-3", "-o", str(out)]) == 0
    captured = capsys.readouterr()
    assert "error" not in captured.err
    doc = json.loads(out.read_text())
    validate(doc)
    assert doc["source"] == "bracket.step" and doc["units"] == "mm" and doc["options"]["ald"] == 1e-3
    rows = _table_rows(captured.out)
    by_type: dict[str, list[dict]] = {}
    for e in doc["edges"]:
        by_type.setdefault(e["curve"], []).append(e)
    for curve, edges in by_type.items():
        assert rows[curve][:2] == [str(len(edges)), str(sum(len(e["params"]) - 1 for e in edges))]
        assert float(rows[curve][2]) == pytest.approx(max(e["ald_estimate"] for e in edges), rel=1e-2, abs=1e-12)
    assert rows["total"][:2] == [str(doc["summary"]["edges"]), str(doc["summary"]["segments"])]
    assert str(out) in captured.out
    assert doc["summary"]["max_ald_estimate"] <= 1e-3


def test_refine_options_reach_the_output(tmp_path, capsys):
    out = tmp_path / "b.json"
    argv = ["refine", str(BRACKET), "--ald", "2e-3", "--max-length", "5", "--min-length", "0.01",
            "--max-growth", "1.4", "-o", str(out), "--quiet"]
    assert main(argv) == 0
    assert capsys.readouterr().out == ""
    doc = json.loads(out.read_text())
    assert doc["options"] == {"ald": 2e-3, "min_length": 0.01, "max_length": 5.0, "max_growth": 1.4}
    for e in doc["edges"]:
        pts = e["points"]
        longest = max(sum((a - b) ** 2 for a, b in zip(p, q)) ** 0.5 for p, q in zip(pts, pts[1:]))
        assert longest <= 5.0 * (1 + 1e-9)


@pytest.mark.parametrize("suffix", sorted(FORMATS))
def test_refine_every_output_format(tmp_path, capsys, suffix):
    out = tmp_path / f"sphere{suffix}"
    assert main(["refine", str(SPHERE), "-o", str(out), "--quiet"]) == 0
    assert out.stat().st_size > 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]


def test_refine_plot(tmp_path, capsys):
    image = pytest.importorskip("matplotlib.image")
    out, png = tmp_path / "b.csv", tmp_path / "b.png"
    assert main(["refine", str(BRACKET), "-o", str(out), "--plot", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    height, width, _ = image.imread(png).shape
    assert height > 300 and width > 300
    assert str(png) in capsys.readouterr().out


@pytest.mark.parametrize("name, expected", [
    ("LLNL__axom_data__sliced_cylinder.step", "STEP load fail"),  # Rhino file with unquoted names
    ("live-clones__gmsh__mesh_T106_V3.step", "loose tolerance"),  # healed edge tolerance 0.73 mm
])
@pytest.mark.corpus
def test_refine_prints_model_warnings(tmp_path, capsys, name, expected):
    out = tmp_path / "s.json"
    assert main(["refine", str(CORPUS / name), "-o", str(out)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err and all(line.startswith(f"cadedge refine: {CORPUS / name}: warning: ") for line in err)
    assert any(expected in line for line in err)
    validate(json.loads(out.read_text()))


@pytest.mark.corpus
def test_progress_bar_draws_for_many_edges():
    import cadedge

    stream = io.StringIO()
    bar = Progress(stream=stream, enabled=True)
    grid = cadedge.refine_shape(CUBE_FILET, progress=bar)
    bar.close()
    assert len(grid.edges) == 74
    assert re.search(r"edges:.*/74", stream.getvalue())


def test_progress_bar_silent_for_few_edges_or_no_terminal():
    quiet = io.StringIO()
    bar = Progress(stream=quiet, enabled=True)
    for k in range(1, 11):
        bar(k, 10)
    bar.close()
    not_a_tty = io.StringIO()
    bar = Progress(stream=not_a_tty)  # enabled only on a terminal
    for k in range(1, 101):
        bar(k, 100)
    bar.close()
    assert quiet.getvalue() == "" and not_a_tty.getvalue() == ""


def _write_bad_inputs(folder: Path) -> dict[str, Path]:
    folder.mkdir()
    text = BRACKET.read_text()
    (folder / "notes.txt").write_text("not a model\n")
    (folder / "garbage.step").write_text("hello, I am not STEP\n")
    (folder / "truncated.step").write_text(text[: len(text) // 2])
    (folder / "empty.step").write_bytes(b"")
    header = text[: text.index("DATA;")]
    (folder / "nodata.step").write_text(header + "DATA;\nENDSEC;\nEND-ISO-10303-21;\n")
    shutil.copy(BRACKET, folder / "good.step")
    return {p.name: p for p in folder.iterdir()}


BAD_CASES = [
    # (input name, extra args, output name, name the error must mention)
    ("missing.step", [], "o.json", "missing.step"),
    ("notes.txt", [], "o.json", "notes.txt"),
    ("garbage.step", [], "o.json", "garbage.step"),
    ("truncated.step", [], "o.json", "truncated.step"),
    ("empty.step", [], "o.json", "empty.step"),
    ("nodata.step", [], "o.json", "nodata.step"),
    ("good.step", ["--ald", "0"], "o.json", "good.step"),
    ("good.step", ["--ald", "2"], "o.json", "good.step"),
    ("good.step", ["--ald", "abc"], "o.json", "good.step"),
    ("good.step", ["--ald", "nan"], "o.json", "good.step"),
    ("good.step", ["--max-growth", "1"], "o.json", "good.step"),
    ("good.step", ["--min-length", "2", "--max-length", "1"], "o.json", "good.step"),
    ("good.step", ["--max-length", "-1"], "o.json", "good.step"),
    ("good.step", [], "o.stl", "o.stl"),
    ("good.step", [], "o", "o"),
    ("good.step", [], "nofolder/o.json", "nofolder"),
    ("good.step", ["--plot", "p.jpg"], "o.json", "p.jpg"),
]


@pytest.mark.parametrize("name, extra, output, mentioned", BAD_CASES)
def test_refine_bad_input_exit_2_one_line(tmp_path, capsys, name, extra, output, mentioned):
    inputs = _write_bad_inputs(tmp_path / "in")
    work = tmp_path / "work"
    work.mkdir()
    extra = [str(work / a) if a.endswith((".jpg", ".png")) else a for a in extra]
    rc = main(["refine", str(tmp_path / "in" / name), *extra, "-o", str(work / output)])
    err = capsys.readouterr().err
    assert rc == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("cadedge refine: error: ")
    assert mentioned in lines[0] and "Traceback" not in err
    assert list(work.iterdir()) == []
    assert sorted(p.name for p in (tmp_path / "in").iterdir()) == sorted(inputs)


def test_output_suffix_checked_before_reading_input(tmp_path, capsys):
    rc = main(["refine", str(tmp_path / "missing.step"), "-o", str(tmp_path / "out.xyz")])
    err = capsys.readouterr().err
    assert rc == 2 and "out.xyz" in err and ".json" in err and "no such file" not in err


def test_debug_shows_traceback(tmp_path, capsys):
    rc = main(["--debug", "refine", str(tmp_path / "missing.step"), "-o", str(tmp_path / "o.json")])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" in err and "missing.step" in err
    assert not (tmp_path / "o.json").exists()


@pytest.mark.corpus
def test_info_lists_edges_and_counts(capsys):
    assert main(["info", str(CUBE_FILET)]) == 0
    out = capsys.readouterr().out
    assert "faces 25, edges 74, vertices 40" in out
    assert "curve types: Line 34, Circle 32, (degenerate) 8" in out
    assert "units: mm" in out and "max edge tolerance: 1e-07 mm" in out
    rows = [line.split() for line in out.splitlines() if re.match(r"\s*\d+\s+[A-Z]", line)]
    assert [int(r[0]) for r in rows] == list(range(1, 75))
    assert sum(r[2] == "yes" for r in rows) == 8
    first = rows[0]  # edge 1 of cube_filet: a 40 mm line on face 1
    assert first[1] == "Line" and first[-1] == "40" and first[-3] == "1"


def test_info_agrees_with_refine_ids(tmp_path, capsys):
    out = tmp_path / "b.json"
    assert main(["refine", str(BRACKET), "-o", str(out), "--quiet"]) == 0
    assert main(["info", str(BRACKET)]) == 0
    text = capsys.readouterr().out
    rows = [line.split() for line in text.splitlines() if re.match(r"\s*\d+\s+[A-Z]", line)]
    doc = json.loads(out.read_text())
    for row, e in zip(rows, doc["edges"], strict=True):
        assert int(row[0]) == e["id"] and row[1] == e["curve"]
        assert row[5] == ",".join(map(str, e["vertices"])) and row[6] == ",".join(map(str, e["faces"]))
        assert float(row[-1]) == pytest.approx(e["length"], rel=1e-3)


@pytest.mark.parametrize("name", ["missing.step", "notes.txt", "truncated.step", "empty.step"])
def test_info_bad_input(tmp_path, capsys, name):
    _write_bad_inputs(tmp_path / "in")
    rc = main(["info", str(tmp_path / "in" / name)])
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert rc == 2 and len(lines) == 1 and name in lines[0] and lines[0].startswith("cadedge info: error: ")


@pytest.mark.corpus
def test_info_flags_seams_and_closed_edges(capsys):
    assert main(["info", str(CORPUS / "live-clones__gmsh__periodic_u_cst.step")]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines() if re.match(r"\s*\d+\s+[A-Z]", line)]
    seams = [int(r[0]) for r in rows if r[4] == "yes"]
    degenerate = [int(r[0]) for r in rows if r[2] == "yes"]
    assert len(rows) == 6 and len(seams) == 2 and len(degenerate) == 2  # as SOURCES.tsv describes it
    assert all(r[3] == "yes" for r in rows if int(r[0]) in degenerate)


def test_errors_after_the_read_name_the_file_as_typed(tmp_path, capsys, monkeypatch):
    """The library names a file by its base name once it is read (the results' ``source``); the CLI's line
    names it as the user typed it, like every other line."""
    monkeypatch.chdir(FIXTURES.parent)
    assert main(["refine", "fixtures/bracket.step", "--ald-edge", "99=1e-3", "-o", str(tmp_path / "o.json")]) == 2
    assert capsys.readouterr().err.strip() == ("cadedge refine: error: fixtures/bracket.step: local ald for edge 99: "
                                               "no such edge (the shape has edges 1 to 36)")
