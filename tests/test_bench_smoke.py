"""scripts/bench.py on one small fixture: every method meets eps, and the rows and table are well formed.

Not timed: speed targets live in the benchmark itself (docs/performance.md).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

pytest.importorskip("OCP")
pytest.importorskip("gmsh")

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("cadedge_bench", ROOT / "scripts" / "bench.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def test_bench_row_on_a_fixture(bench, tmp_path):
    eps = 1e-2
    rows = bench.bench([ROOT / "fixtures" / "cylinder.step"], [eps], use_gmsh=True, use_dp=True)
    (row,) = rows
    assert row["edges"] == 3
    for side in ("cadedge", "occt", "gmsh"):
        assert row[side]["ald"] <= eps, side
        assert row[side]["segments"] >= 3, side
    # two circles and a seam line: the optimum is known in closed form, and nobody beats it
    assert row["dp"]["segments"] <= min(row[s]["segments"] for s in ("cadedge", "occt", "gmsh"))
    assert row["cadedge"]["segments"] <= 1.10 * row["dp"]["segments"]
    line = bench.format_row(row)
    assert line.startswith("| cylinder.step | 3 | 0.01 |") and line.count("|") == bench.HEADER.count("|")
    paths = bench.plot(rows, tmp_path / "performance")
    assert all(p.stat().st_size > 1000 for p in paths)


def test_occt_tuning_is_the_largest_angle_that_meets_eps(bench):
    model = bench.Model(ROOT / "fixtures" / "helix_wire.step")
    r = bench.run_occt(model, 1e-3)
    assert r["ald"] <= 1e-3
    _, worse = bench.occt_pass(model, r["angle"] * 1.01)
    assert worse > 1e-3 * 0.98  # a slightly larger angle is at (or over) the target
