"""The small things a user trips over: --version and python -m cadedge, paths shown as given, warnings
capped in every command, outputs checked before any work, complex curve values, empty build123d
shapes, the evaluation count, and Ctrl-C."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cadedge
from cadedge.cli import main
from cadedge.cli.refine import MAX_WARNINGS
from conftest import FIXTURES, ROOT

BRACKET = FIXTURES / "bracket.step"


def _env() -> dict[str, str]:
    return dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))


def test_version_in_process(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"cadedge {cadedge.__version__}"


def test_python_dash_m_cadedge():
    version = subprocess.run([sys.executable, "-m", "cadedge", "--version"], capture_output=True, text=True,
                             env=_env(), cwd=ROOT, timeout=120)
    assert version.returncode == 0 and version.stdout.strip() == f"cadedge {cadedge.__version__}"
    info = subprocess.run([sys.executable, "-m", "cadedge", "info", "fixtures/cylinder.step"], capture_output=True,
                          text=True, env=_env(), cwd=ROOT, timeout=300)
    assert info.returncode == 0 and "edges 3" in info.stdout


@pytest.mark.parametrize("command", ["refine", "info", "mesh"])
def test_messages_show_the_path_as_given(tmp_path, capsys, command, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "deep" / "er").mkdir(parents=True)
    given = os.path.join("deep", "er", "missing.step")
    argv = [command, given] + ([] if command == "info" else ["-o", "out" + (".json" if command == "refine"
                                                                                 else ".msh")])
    assert main(argv) == 2
    # mesh names the input on every line, errors included (its problems and warnings are many)
    lead = f"cadedge {command}: " if command == "mesh" else f"cadedge {command}: error: "
    assert capsys.readouterr().err.strip() == f"{lead}{given}: no such file"


def test_info_and_refine_cap_their_warnings(tmp_path, capsys):
    pytest.importorskip("OCP")
    from cadedge.occt.describe import describe_shape

    data = BRACKET.read_bytes()
    head = data[: int(len(data) * 0.6)]
    cut = tmp_path / "cut.step"  # many distinct load-check messages (one per missing entity)
    cut.write_bytes(head[: head.rfind(b";\n") + 1] + b"\nENDSEC;\nEND-ISO-10303-21;\n")
    total = len(dict.fromkeys(describe_shape(cut, allow_partial=True).warnings))
    assert total > MAX_WARNINGS
    for argv in (["info", str(cut)], ["refine", str(cut), "-o", str(tmp_path / "o.json"), "--quiet"]):
        assert main([*argv, "--allow-partial"]) == 0
        warned = [line for line in capsys.readouterr().err.splitlines()
                  if line.startswith(f"cadedge {argv[0]}: {cut}: warning:")]
        assert len(warned) == MAX_WARNINGS + 1 and warned[0].endswith("refining what did load")
        assert f"... and {total - MAX_WARNINGS} more warnings" in warned[-1]


def test_mesh_shows_the_refinement_warnings(tmp_path, capsys):
    pytest.importorskip("gmsh")
    out = tmp_path / "o.msh"
    # a min_length of 8 keeps the cylinder's circles from reaching the target: the refiner says so
    main(["mesh", str(FIXTURES / "cylinder.step"), "--ald", "1e-2", "--min-length", "8", "-o", str(out),
          "--quiet"])
    err = capsys.readouterr().err
    assert f"cadedge mesh: {FIXTURES / 'cylinder.step'}: warning: edge 1: ald target 0.01 not reached" in err


@pytest.mark.parametrize("argv", [
    ["refine", "IN", "-o", "DIR"],
    ["refine", "IN", "-o", "o.json", "--plot", "DIR"],
    ["mesh", "IN", "-o", "DIR"],
])
def test_an_output_that_is_a_folder_fails_before_any_work(tmp_path, capsys, argv):
    folder = tmp_path / ("x.png" if "--plot" in argv else "x.msh" if argv[0] == "mesh" else "x.json")
    folder.mkdir()
    missing = tmp_path / "missing.step"  # the output is checked before the input is even looked at
    argv = [str(missing) if a == "IN" else str(folder) if a == "DIR" else str(tmp_path / a) if a == "o.json"
            else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{folder}: is a folder" in err[0] and "no such file" not in err[0]


@pytest.mark.parametrize("fn", [
    lambda t: np.column_stack([np.cos(t), np.sin(t)]).astype(complex),  # vectorised
    lambda t: (math.cos(t) + 0j, math.sin(t)),  # scalar
    lambda t: np.array([math.cos(t), math.sin(t) * 1j]),  # scalar, numpy complex
])
def test_complex_curve_values_are_rejected(fn):
    with pytest.raises(cadedge.CurveEvaluationError, match="complex values"):
        cadedge.refine_curve(fn, (0.0, 1.0), ald=1e-3)


def test_complex_values_from_a_curve_object_are_rejected():
    class Complexish:
        domain = (0.0, 1.0)

        def evaluate(self, u):
            return np.column_stack([u, u * 1j])

    with pytest.raises(cadedge.CurveEvaluationError, match="complex values"):
        cadedge.refine_curve(Complexish(), ald=1e-3)


def test_evaluations_count_the_real_calls_of_a_scalar_function():
    calls = 0

    def scalar_only(t):
        nonlocal calls
        calls += 1
        return (math.cos(t), math.sin(t))  # math.cos fails on the vectorised probe

    g = cadedge.refine_curve(scalar_only, (0.0, 3.0), ald=1e-3)
    assert g.evaluations == calls


@pytest.mark.parametrize("name", ["Compound", "Part"])
def test_empty_build123d_shapes_are_an_input_error(name):
    bd = pytest.importorskip("build123d")
    with pytest.raises(cadedge.InputError, match=rf"<build123d {name}>: empty shape"):
        cadedge.refine_shape(getattr(bd, name)())


def test_ctrl_c_during_a_real_refine(tmp_path):
    """SIGINT sent once the refinement's kernel has started ends the run with exit 130, one line and no file.

    The kernel refines the bracket at 1e-9 in about 3 s, so a signal sent after a fixed delay could arrive
    after the work was done (exit 0) on a loaded machine. The child says when its first kernel call starts
    and, after that call, waits (up to 60 s) for the signal inside the refinement: it always lands while
    the refine is running, and a lost signal lets the refine finish with exit 0, which fails the test."""
    pytest.importorskip("OCP")
    code = ("import sys, time\n"
            "import cadedge.kernels as kernels\n"
            "from cadedge.cli import main\n"
            "real = kernels.refine_edges\n"
            "def refine_edges(*args, **kwargs):\n"
            "    kernels.refine_edges = real\n"
            "    print('refining', flush=True)\n"
            "    out = real(*args, **kwargs)\n"
            "    time.sleep(60)\n"
            "    return out\n"
            "kernels.refine_edges = refine_edges\n"
            f"sys.exit(main(['refine', {str(BRACKET)!r}, '--ald', '1e-9', '-o', {str(tmp_path / 'o.json')!r}]))\n")
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=_env())
    try:
        assert proc.stdout.readline().strip() == "refining"
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert err.strip() == "cadedge refine: interrupted", err
    assert not Path(tmp_path / "o.json").exists()


def test_a_closed_stdout_pipe_ends_quietly():
    pytest.importorskip("OCP")
    # ``cadedge info x | head -1``: the reader is gone before cadedge writes
    proc = subprocess.Popen([sys.executable, "-m", "cadedge", "info", str(BRACKET)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=_env(), cwd=ROOT)
    proc.stdout.close()
    try:
        err = proc.stderr.read()
        proc.wait(timeout=300)
    finally:
        proc.kill()
    assert proc.returncode == 141 and "Traceback" not in err and "BrokenPipe" not in err, err


def test_ctrl_c_turned_into_another_error_by_native_code_is_still_interrupted(monkeypatch, capsys):
    import cadedge.cli.info as info

    def interrupted_while_loading(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:  # what an extension module interrupted in its init raises
            raise ImportError("initialization failed") from exc

    monkeypatch.setattr(info, "run", interrupted_while_loading)
    assert main(["info", str(BRACKET)]) == 130
    assert capsys.readouterr().err.strip() == "cadedge info: interrupted"
    with pytest.raises(ImportError):  # --debug shows what happened
        main(["--debug", "info", str(BRACKET)])

    def plain_bug(args):
        raise ImportError("a real import problem")

    monkeypatch.setattr(info, "run", plain_bug)
    with pytest.raises(ImportError, match="a real import problem"):
        main(["info", str(BRACKET)])


def test_ctrl_c_while_the_local_cluster_starts_leaves_no_traceback():
    pytest.importorskip("distributed")
    # SIGINT 0.6 s into connect(), distributed already imported: while the worker processes start
    code = ("import os, signal, sys\n"
            "import distributed\n"
            "from cadedge.batch.runner import connect\n"
            "signal.signal(signal.SIGALRM, lambda *a: os.kill(os.getpid(), signal.SIGINT))\n"
            "signal.setitimer(signal.ITIMER_REAL, 0.6)\n"
            "try:\n"
            "    with connect(workers=1):\n"
            "        print('started', flush=True)\n"
            "except KeyboardInterrupt:\n"
            "    print('interrupted', flush=True)\n"
            "    sys.exit(130)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_env(), timeout=120)
    assert proc.stdout.strip() == "interrupted" and proc.returncode == 130, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr and "Exception ignored" not in proc.stderr, proc.stderr
