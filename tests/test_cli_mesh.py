"""``cadedge mesh``: in-process CLI runs on real fixtures with real gmsh."""

from __future__ import annotations

import io
import re
import sys

import pytest

pytest.importorskip("gmsh")
trimesh = pytest.importorskip("trimesh")

from cadedge.cli import main  # noqa: E402
from cadedge.cli.mesh import StatusLine  # noqa: E402

from conftest import FIXTURES  # noqa: E402

CYL = str(FIXTURES / "cylinder.step")


def test_mesh_msh_prints_the_check_and_exits_0(tmp_path, capsys):
    out = tmp_path / "cyl.msh"
    assert main(["mesh", CYL, "--ald", "1e-2", "-o", str(out)]) == 0
    text = capsys.readouterr()
    assert "closed, watertight" in text.out and "check: ok" in text.out
    assert "edge-grid nodes in mesh:" in text.out
    assert text.err == ""
    assert out.read_text().startswith("$MeshFormat")


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_on_a_terminal_a_status_line_says_what_it_does_and_is_cleared(tmp_path, capsys, monkeypatch):
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    assert main(["mesh", CYL, "--ald", "1e-2", "-o", str(tmp_path / "cyl.msh")]) == 0
    drawn = terminal.getvalue()
    assert re.search(r"\r\x1b\[Kcadedge mesh: \d+ s: (refining edges|area target|meshing|gmsh)", drawn)
    assert drawn.endswith("\r\x1b[K")  # cleared before the summary
    assert "check: ok" in capsys.readouterr().out


def test_the_status_line_stays_off_without_a_terminal_or_with_quiet(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sys, "stderr", _Terminal())
    status = StatusLine(stream=io.StringIO())  # not a terminal
    status("meshing faces: 1/3 meshed")
    status.close()
    assert status.stream.getvalue() == ""
    assert main(["mesh", CYL, "--ald", "1e-2", "-o", str(tmp_path / "cyl.msh"), "--quiet"]) == 0
    assert sys.stderr.getvalue() == "" and capsys.readouterr().out == ""


def test_mesh_stl_is_watertight(tmp_path, capsys):
    out = tmp_path / "prism.stl"  # six faces, B-spline ones among them; the bracket's gmsh run costs twice as much
    assert main(["mesh", str(FIXTURES / "spline_prism.step"), "--ald", "1e-2", "-o", str(out), "--quiet"]) == 0
    assert capsys.readouterr().out == ""
    mesh = trimesh.load(out, force="mesh")  # STL repeats coordinates per triangle: merge them back
    mesh.merge_vertices()
    assert mesh.is_watertight


def test_sizes_mode_and_geo_export(tmp_path, capsys):
    assert main(["mesh", CYL, "--ald", "1e-2", "--mode", "sizes", "-o", str(tmp_path / "c.vtk")]) == 0
    assert "check: ok" in capsys.readouterr().out
    geo = tmp_path / "c.geo"
    assert main(["mesh", CYL, "--ald", "1e-2", "-o", str(geo)]) == 0
    assert geo.exists() and geo.with_suffix(".brep").exists()
    assert 'Merge "c.brep";' in geo.read_text()


@pytest.mark.parametrize("argv, needle", [
    (["mesh", "no_such.step", "-o", "x.msh"], "no_such.step"),
    (["mesh", CYL, "-o", "x.obj"], "x.obj"),
    (["mesh", CYL, "-o", "missing_dir/x.msh"], "missing_dir"),
    (["mesh", CYL, "--ald", "two", "-o", "x.msh"], "--ald"),
    (["mesh", CYL, "--growth", "-1", "-o", "x.msh"], "--growth"),
    (["mesh", str(FIXTURES / "helix_wire.step"), "-o", "x.msh"], "no faces"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, monkeypatch, capsys, argv, needle):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and needle in err and "Traceback" not in err
    assert not list(tmp_path.glob("x.*"))
