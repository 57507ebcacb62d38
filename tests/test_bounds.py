"""Bounded work: targets below what double precision resolves are refused up front, an edge that needs
more samples than the cap ends with a warning, and a model whose grids would be too large ends with
one clear error, never a MemoryError or minutes of silent work."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

import cadedge
from cadedge.cli import main
from cadedge.errors import InputError
from cadedge.options import MIN_ALD, MIN_ALD_TEXT
from conftest import FIXTURES


@pytest.mark.parametrize("ald", [1e-10, 1e-16, 1e-20, 5e-324])
def test_api_refuses_targets_below_the_floor(ald, tmp_path):
    with pytest.raises(InputError, match=rf"ald {ald!r} is below {MIN_ALD_TEXT}, the smallest target"):
        cadedge.refine_curve(lambda t: (t, t * t), (0.0, 1.0), ald=ald)
    with pytest.raises(InputError, match=MIN_ALD_TEXT):  # before the (missing) file is looked at
        cadedge.refine_shape(tmp_path / "missing.step", ald=ald)


def test_batch_refuses_targets_below_the_floor(tmp_path):
    from cadedge.batch import run_batch

    with pytest.raises(InputError, match=MIN_ALD_TEXT):
        run_batch([FIXTURES / "cylinder.step"], tmp_path / "out", ald=1e-12)
    assert not (tmp_path / "out").exists()


def test_the_floor_itself_is_met_on_a_circle():
    t0 = time.perf_counter()
    g = cadedge.refine_curve(lambda u: np.column_stack([np.cos(u), np.sin(u)]), (0.0, 2 * math.pi), ald=MIN_ALD)
    true = 1.0 - math.fsum(np.linalg.norm(np.diff(g.points, axis=0), axis=1)) / (2 * math.pi)
    assert true <= MIN_ALD and g.ald_estimate <= MIN_ALD
    assert time.perf_counter() - t0 < 60


@pytest.mark.parametrize("command", ["refine", "mesh"])
@pytest.mark.parametrize("ald", ["1e-20", "1e-10"])
def test_cli_refuses_with_one_line_naming_the_floor(tmp_path, capsys, command, ald):
    pytest.importorskip("OCP")
    out = tmp_path / ("o.json" if command == "refine" else "o.msh")
    rc = main([command, str(FIXTURES / "bracket.step"), "--ald", ald, "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1
    lead = f"cadedge {command}: " if command == "mesh" else f"cadedge {command}: error: "
    assert err[0] == (f"{lead}{FIXTURES / 'bracket.step'}: --ald {ald} is below "
                      f"{MIN_ALD_TEXT}, the smallest target double precision can resolve")
    assert not out.exists()


@pytest.mark.parametrize("command", ["refine", "mesh", "batch"])
def test_help_states_the_floor(capsys, command):
    assert main([command, "--help"]) == 0
    assert f"{MIN_ALD_TEXT} <= EPS < 1" in " ".join(capsys.readouterr().out.split())


def test_an_edge_past_the_sampling_cap_warns():
    t0 = time.perf_counter()
    with pytest.warns(cadedge.CadedgeWarning) as caught:
        g = cadedge.refine_curve(lambda u: np.column_stack([u, np.sin(2e4 * u)]), (0.0, 1.0), ald=MIN_ALD)
    assert any("not reached" in str(w.message) and "sampling cap" in str(w.message) for w in caught)
    assert any("exploration stopped" in w for w in g.warnings)
    assert g.evaluations < 1_000_000 and time.perf_counter() - t0 < 120


def test_a_model_past_the_segment_cap_is_one_clear_error(monkeypatch, tmp_path, capsys):
    pytest.importorskip("OCP")
    import cadedge.occt.shape as shape

    monkeypatch.setattr(shape, "MAX_MODEL_SEGMENTS", 100)
    with pytest.raises(InputError, match=r"bracket.step: the grids would exceed 100 segments \(reached after "
                                         r"\d+ of 36 edges\); use a larger ald"):
        cadedge.refine_shape(FIXTURES / "bracket.step", ald=1e-4)
    out = tmp_path / "b.json"
    assert main(["refine", str(FIXTURES / "bracket.step"), "--ald", "1e-4", "-o", str(out)]) == 2
    assert "would exceed 100 segments" in capsys.readouterr().err and not out.exists()


def test_a_max_length_forcing_too_many_segments_is_refused_up_front(tmp_path, capsys):
    from cadedge.target import MAX_LENGTH_SEGMENTS

    t0 = time.perf_counter()
    with pytest.raises(InputError, match=rf"max_length 1e-07 would split a curve 1 long into more than "
                                         rf"{MAX_LENGTH_SEGMENTS:,} segments, the cap per edge"):
        cadedge.refine_curve(lambda t: np.column_stack([t, 0 * t]), (0.0, 1.0), ald=1e-3, max_length=1e-7)
    assert time.perf_counter() - t0 < 30  # it once filled 23 GB on a 36-edge model
    pytest.importorskip("OCP")
    out = tmp_path / "b.json"
    assert main(["refine", str(FIXTURES / "bracket.step"), "--max-length", "1e-7", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bracket.step: edge 1: max_length 1e-07 would split" in err[0] and not out.exists()
