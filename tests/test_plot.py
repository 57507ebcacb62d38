"""Plots: the suffix picks PNG (matplotlib) or a self-contained HTML page (plotly); the figure's traces,
hover text and colouring; lazy imports; the CLI's --plot for refine and mesh. The page in a real
browser is tests/test_plot_browser.py."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cadedge.cli import main
from cadedge.errors import InputError
from cadedge.plot import check_plot_path, plot_grid, plot_mesh
from test_exporters import make_grid

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def hand_mesh():
    """A MeshResult of two triangles on faces 1 and 2 around the hand-built grid (plain data)."""
    from cadedge.mesh import MeshResult

    grid = make_grid()
    nodes = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.5]])
    return MeshResult(source="hand.step", mode="nodes", grid=grid, nodes=nodes,
                      triangles=np.array([[0, 1, 2], [1, 3, 2]]), triangle_faces=np.array([1, 2]),
                      failures=[], check=None)


@pytest.mark.parametrize("name, kind", [("a.png", "png"), ("a.html", "html"), ("A.HTML", "html"), ("a.htm", "html")])
def test_check_plot_path_kinds(tmp_path, name, kind):
    assert check_plot_path(tmp_path / name) == kind


@pytest.mark.parametrize("name, needle", [("a.jpg", ".png .html"), ("nofolder/a.html", "does not exist")])
def test_check_plot_path_refuses(tmp_path, name, needle):
    with pytest.raises(InputError, match=needle):
        check_plot_path(tmp_path / name)


def test_color_by_is_checked(tmp_path):
    with pytest.raises(InputError, match="segments, ald"):
        plot_grid(make_grid(), tmp_path / "g.html", color_by="length")
    assert list(tmp_path.iterdir()) == []


def test_grid_figure_traces_hover_and_colours():
    pytest.importorskip("plotly")
    from cadedge.plot.html import grid_figure

    grid = make_grid()
    live = [e for e in grid.edges if not e.degenerate]
    fig = grid_figure(grid, color_by="ald")
    lines, points, vertices = fig.data
    assert (lines.mode, points.mode, vertices.mode) == ("lines", "markers", "markers")
    n = sum(len(e.points) + 1 for e in live)  # a NaN gap after each edge
    assert len(lines.x) == n and np.isnan(np.asarray(lines.x, dtype=float)).sum() == len(live)
    for field in ("edge %{customdata[0]}", "%{customdata[1]}", "segments %{customdata[2]}", "length", "ALD"):
        assert field in lines.hovertemplate
    custom = np.asarray(lines.customdata)
    first = live[1]
    start = len(live[0].points) + 1
    assert custom[start, :3].tolist() == [first.id, first.curve, first.segments]
    assert custom[start, 3:].tolist() == pytest.approx([first.length, first.ald_estimate], rel=1e-3)
    assert np.asarray(lines.line.color)[start] == pytest.approx(first.ald_estimate, rel=1e-3)
    assert points.marker.colorbar.title.text == "ALD"
    assert list(vertices.customdata) == [v.id for v in grid.vertices]
    buttons = fig.layout.updatemenus[0].buttons
    assert [b.label for b in buttons] == ["colour by segments", "colour by ALD"]
    assert buttons[0].args[0]["line.color"][0][start] == first.segments and list(buttons[0].args[1]) == [0, 1]
    assert fig.layout.updatemenus[0].active == 1


def test_mesh_figure_colours_triangles_by_face():
    pytest.importorskip("plotly")
    from cadedge.plot.html import mesh_figure

    mesh = hand_mesh()
    fig = mesh_figure(mesh)
    surface = fig.data[0]
    assert surface.type == "mesh3d" and "face %{customdata}" in surface.hovertemplate
    xyz = np.column_stack([surface.x, surface.y, surface.z])
    corners = np.column_stack([surface.i, surface.j, surface.k])
    assert len(xyz) == 6  # nodes 1 and 2 are on both faces: once per face
    assert np.array_equal(xyz[corners], mesh.nodes[mesh.triangles])
    assert [set(np.asarray(surface.customdata)[c].tolist()) for c in corners] == [{1}, {2}]
    assert len(set(np.asarray(surface.intensity)[corners[0]])) == 1  # one flat colour per face
    assert [t.name for t in fig.data[1:]] == ["edges", "edges", "vertices"]
    assert list(fig.layout.updatemenus[0].buttons[0].args[1]) == [1, 2]


def test_html_page_is_self_contained(tmp_path):
    pytest.importorskip("plotly")
    path = tmp_path / "g.html"
    plot_grid(make_grid(), path)
    page = path.read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and "<title>hand.step: 4 edges" in page
    assert not re.search(r"<script[^>]*\bsrc=", page) and "<link" not in page  # plotly.js is inline
    assert "Plotly.newPlot" in page and len(page) > 1_000_000
    assert [p.name for p in tmp_path.iterdir()] == ["g.html"]


def test_png_grid_and_mesh(tmp_path):
    pytest.importorskip("matplotlib")
    plot_grid(make_grid(), tmp_path / "g.png")
    plot_mesh(hand_mesh(), tmp_path / "m.png")
    assert (tmp_path / "g.png").read_bytes()[:8] == PNG_MAGIC == (tmp_path / "m.png").read_bytes()[:8]


def test_cli_start_imports_no_plotting_library():
    code = ("import sys, cadedge, cadedge.cli, cadedge.plot; "
            "print(sorted(m for m in ('plotly', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_refine_plot_html(tmp_path, capsys):
    pytest.importorskip("plotly")
    out, page = tmp_path / "b.json", tmp_path / "b.html"
    assert main(["refine", str(FIXTURES / "bracket.step"), "-o", str(out), "--plot", str(page)]) == 0
    assert "Plotly.newPlot" in page.read_text(encoding="utf-8")
    assert str(page) in capsys.readouterr().out


@pytest.mark.parametrize("suffix", [".html", ".png"])
def test_mesh_plot(tmp_path, capsys, suffix):
    pytest.importorskip("plotly")
    out, plot = tmp_path / "c.msh", tmp_path / f"c{suffix}"
    assert main(["mesh", str(FIXTURES / "cylinder.step"), "--ald", "1e-2", "-o", str(out), "--plot", str(plot)]) == 0
    assert plot.stat().st_size > 1000 and str(plot) in capsys.readouterr().out


def test_mesh_bad_plot_suffix_is_exit_2_before_work(tmp_path, capsys):
    rc = main(["mesh", str(tmp_path / "missing.step"), "-o", str(tmp_path / "c.msh"), "--plot", str(tmp_path / "c.jpg")])
    err = capsys.readouterr().err
    assert rc == 2 and "c.jpg" in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []
