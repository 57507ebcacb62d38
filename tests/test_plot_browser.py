"""The HTML pages in a real headless Chromium, as a user opens them: offline (a file URL, every
network request counted as an error), no JS error, a canvas that is not blank, hover labels with the
edge's id, curve type, segments, length and ALD (and the face id on a mesh), and the colour buttons.

Marked ``browser``; skipped when no Chromium is found (``CADEDGE_CHROMIUM`` or ``chromium`` on PATH),
unless ``CADEDGE_REQUIRE_BROWSER=1`` (CI), where a missing browser fails.
"""

from __future__ import annotations

import io
import os
import re
from pathlib import Path

import numpy as np
import pytest

import cadedge
from cadedge.plot import plot_grid, plot_mesh
from chromium import Browser, find_chromium

pytestmark = pytest.mark.browser
FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
WIDTH, HEIGHT = 1000, 750
READY = ("new Promise(r => { let n = 0; const check = () => { const gd = document.querySelector('.js-plotly-plot');"
         " const ok = gd && gd._fullLayout && document.querySelector('.gl-container canvas');"
         " if (ok || n++ > 400) r(Boolean(ok)); else setTimeout(check, 50); }; check(); })")
HOVER_TEXT = ("new Promise(r => { let n = 0; const check = () => { const t = Array.from("
              "document.querySelectorAll('.hovertext')).map(e => e.textContent).join('|');"
              " if (t || n++ > 40) r(t); else setTimeout(check, 50); }; check(); })")
EDGE_LABEL = re.compile(r"edge (\d+) \((\w+)\)segments (\d+)length ([-+.\de]+) mmALD ([-+.\de]+)")


@pytest.fixture(scope="module")
def browser():
    executable = find_chromium()
    if executable is None:
        if os.environ.get("CADEDGE_REQUIRE_BROWSER") == "1":
            pytest.fail("CADEDGE_REQUIRE_BROWSER=1 but no Chromium found (set CADEDGE_CHROMIUM)")
        pytest.skip("no Chromium found: install Debian's chromium or set CADEDGE_CHROMIUM")
    b = Browser(executable, width=WIDTH, height=HEIGHT)
    yield b
    b.close()


def open_page(browser: Browser, path: Path) -> np.ndarray:
    """Load ``path``, wait for plotly's WebGL canvas, check there is no error; the screenshot as RGB."""
    from PIL import Image

    browser.open(path.resolve().as_uri())
    assert browser.evaluate(READY), "plotly never drew its WebGL canvas"
    assert browser.errors == []
    shot = np.asarray(Image.open(io.BytesIO(browser.screenshot())).convert("RGB")).astype(int)
    assert shot.shape == (HEIGHT, WIDTH, 3)
    return shot


def coloured_pixels(shot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Saturated pixels in the scene, away from the title, buttons, legend and colour bar (plotly's
    own scene background and grid are grey-blue, with little saturation)."""
    saturation = shot.max(axis=2) - shot.min(axis=2)
    mask = saturation > 60
    mask[:90], mask[:, int(0.88 * WIDTH):], mask[:200, :150] = False, False, False
    ys, xs = np.nonzero(mask)
    return xs, ys


def hover_labels(browser: Browser, xs: np.ndarray, ys: np.ndarray, pattern: re.Pattern, tries: int = 12):
    """Move the mouse over up to ``tries`` of the given pixels; the first label matching ``pattern``."""
    picks = np.random.default_rng(0).choice(len(xs), size=min(tries, len(xs)), replace=False)
    seen = []
    for i in picks:
        browser.move_mouse(float(xs[i]), float(ys[i]))
        text = browser.evaluate(HOVER_TEXT)
        seen.append(text)
        match = pattern.search(text or "")
        if match:
            return match
    raise AssertionError(f"no hover label matching {pattern.pattern!r}; saw {seen}")


def test_grid_page_draws_hovers_and_recolours(browser, tmp_path):
    grid = cadedge.refine_shape(FIXTURES / "bracket.step", ald=1e-3)
    page = tmp_path / "bracket.html"
    plot_grid(grid, page)
    shot = open_page(browser, page)
    xs, ys = coloured_pixels(shot)
    assert len(xs) > 2000, "the edges were not drawn"
    match = hover_labels(browser, xs, ys, EDGE_LABEL)
    edge = grid.edges[int(match[1]) - 1]
    assert (match[2], int(match[3])) == (edge.curve, edge.segments)
    assert float(match[4]) == pytest.approx(edge.length, rel=1e-5)
    assert float(match[5]) == pytest.approx(edge.ald_estimate, rel=1e-2, abs=1e-12)
    title = "document.querySelector('.cbtitle').textContent"
    assert browser.evaluate(title) == "segments"
    browser.evaluate("document.querySelectorAll('.updatemenu-button')[1]"
                     ".dispatchEvent(new MouseEvent('click', {bubbles: true}))")
    assert browser.evaluate(title) == "ALD"
    assert browser.errors == []


def test_mesh_page_shows_faces_and_edges(browser, tmp_path):
    from cadedge.mesh import mesh_shape

    result = mesh_shape(FIXTURES / "cylinder.step", ald=1e-2)
    page = tmp_path / "cylinder.html"
    plot_mesh(result, page)
    shot = open_page(browser, page)
    xs, ys = coloured_pixels(shot)
    assert len(xs) > 20000, "the triangles were not drawn"
    match = hover_labels(browser, xs, ys, re.compile(r"face (\d+)"))
    assert int(match[1]) in set(np.unique(result.triangle_faces).tolist())
    assert browser.errors == []


def test_mesh_page_with_more_faces_than_plotly_has_shades(browser, tmp_path):
    """plotly.js shades a mesh with at most 256 colours; 300 faces must still draw without an error."""
    from cadedge.mesh import MeshResult

    grid = cadedge.refine_shape(FIXTURES / "bracket.step", ald=1e-2)
    u, v = np.meshgrid(np.linspace(0, 1, 31), np.linspace(0, 1, 11))
    nodes = np.column_stack([60 * u.ravel() - 30, 20 * v.ravel() - 10, np.full(u.size, -6.0)])
    quads = np.array([[r * 31 + c, r * 31 + c + 1, (r + 1) * 31 + c] for r in range(10) for c in range(30)])
    result = MeshResult(source="strip", mode="nodes", grid=grid, nodes=nodes, triangles=quads,
                        triangle_faces=np.arange(1, len(quads) + 1), failures=[], check=None)
    page = tmp_path / "many.html"
    plot_mesh(result, page)
    xs, ys = coloured_pixels(open_page(browser, page))
    assert len(xs) > 20000
