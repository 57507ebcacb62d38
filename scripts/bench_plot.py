"""Size and load time of the ``--plot x.html`` pages in headless Chromium (software WebGL).

Per model: edges, grid points, triangles (mesh pages), page size, seconds to the load event and to
plotly's first WebGL frame, the median of ``--runs`` loads in one browser. Prints a markdown table
(the one in docs/plot.md):

    python scripts/bench_plot.py fixtures/bracket.step fixtures/sphere.step

Needs Chromium (``chromium`` on PATH or ``CADEDGE_CHROMIUM``); uses the DevTools-pipe driver of the
test suite (tests/chromium.py).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

import cadedge  # noqa: E402
from cadedge.mesh import mesh_shape  # noqa: E402
from cadedge.plot import plot_grid, plot_mesh  # noqa: E402
from chromium import Browser, find_chromium  # noqa: E402
from test_plot_browser import READY  # noqa: E402


def load_times(browser: Browser, page: Path, runs: int) -> tuple[float, float]:
    """Median seconds to the load event and to plotly's WebGL canvas."""
    loads, ready = [], []
    for _ in range(runs):
        start = time.monotonic()
        loads.append(browser.open(page.resolve().as_uri()))
        if not browser.evaluate(READY) or browser.errors:
            raise RuntimeError(f"{page}: no plot, or errors {browser.errors}")
        ready.append(time.monotonic() - start)
    return statistics.median(loads), statistics.median(ready)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+", type=Path)
    parser.add_argument("--ald", type=float, default=1e-3)
    parser.add_argument("--mesh-ald", type=float, default=1e-2)
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    executable = find_chromium()
    if executable is None:
        sys.exit("no Chromium found: install Debian's chromium or set CADEDGE_CHROMIUM")
    browser = Browser(executable)
    print("| model | page | edges | grid points | triangles | size (MB) | load event (s) | first frame (s) |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for model in args.models:
                grid = cadedge.refine_shape(model, ald=args.ald)
                points = sum(len(e.points) for e in grid.edges if not e.degenerate)
                page = Path(tmp) / f"{model.stem}.html"
                plot_grid(grid, page)
                load, ready = load_times(browser, page, args.runs)
                print(f"| {model.name} | grid, ALD {args.ald:g} | {len(grid.edges)} | {points} | - | "
                      f"{page.stat().st_size / 1e6:.2f} | {load:.1f} | {ready:.1f} |")
                result = mesh_shape(model, ald=args.mesh_ald)
                points = sum(len(e.points) for e in result.grid.edges if not e.degenerate)
                page = Path(tmp) / f"{model.stem}-mesh.html"
                plot_mesh(result, page)
                load, ready = load_times(browser, page, args.runs)
                print(f"| {model.name} | mesh, ALD {args.mesh_ald:g} | {len(result.grid.edges)} | {points} | "
                      f"{len(result.triangles)} | {page.stat().st_size / 1e6:.2f} | {load:.1f} | {ready:.1f} |")
    finally:
        browser.close()


if __name__ == "__main__":
    main()
