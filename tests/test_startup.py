"""Start-up: each CLI command imports only what it uses, the console script loads OCP out of the
collector's way (frozen), and the public API still resolves in full."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"


def _modules_after(code: str) -> set[str]:
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys\nprint('\\n'.join(sys.modules))"],
                         capture_output=True, text=True, check=True).stdout
    return set(out.split())


def test_import_cadedge_loads_no_numpy():
    assert "numpy" not in _modules_after("import cadedge")


def test_info_loads_neither_numpy_nor_the_refiner():
    pytest.importorskip("OCP")
    path = str(FIXTURES / "sphere.step")
    mods = _modules_after(f"from cadedge.cli import main\nassert main(['info', {path!r}]) == 0")
    assert not {"numpy", "cadedge.refine", "cadedge.mesh", "cadedge.batch", "gmsh", "dask"} & mods


def test_refine_loads_no_mesher_batch_or_plotting(tmp_path):
    pytest.importorskip("OCP")
    out = tmp_path / "s.json"
    path = str(FIXTURES / "sphere.step")
    mods = _modules_after(f"from cadedge.cli import main\n"
                          f"assert main(['refine', {path!r}, '--ald', '1e-3', '-o', {str(out)!r}]) == 0")
    assert not {"cadedge.mesh", "cadedge.batch", "gmsh", "dask", "matplotlib", "scipy"} & mods
    assert out.exists()
    # the JSON writer alone: no other format's module, nor meshio
    assert "cadedge.exporters.json" in mods
    assert not {"cadedge.exporters.csv", "cadedge.exporters.vtp", "cadedge.exporters._meshio", "meshio"} & mods


@pytest.mark.parametrize("args", [["--help"], ["mesh", "--help"]])
def test_help_loads_no_mesher_checker_or_cluster(args):
    """``cadedge --help`` builds every subcommand's parser; the mesh command's imported the watertight
    check's trimesh with it (1.2-1.5 s of a 1.5 s run)."""
    mods = _modules_after("import contextlib, io\nfrom cadedge.cli import main\n"
                          f"with contextlib.redirect_stdout(io.StringIO()):\n    assert main({args!r}) == 0")
    assert "cadedge.mesh" in mods  # the mesh command's parser was built
    assert not {"trimesh", "gmsh", "scipy", "OCP", "dask", "meshio"} & {m.split(".")[0] for m in mods}


def test_every_public_name_resolves():
    import cadedge

    for name in cadedge.__all__:
        assert getattr(cadedge, name) is not None
    assert set(cadedge.__all__) <= set(dir(cadedge))
    with pytest.raises(AttributeError):
        cadedge.no_such_name  # noqa: B018


def _console(args: list[str], extra_env: dict[str, str] | None = None) -> str:
    """stderr's last line of the console script's entry point run with ``args``, reporting at exit the
    collector's state, the frozen count and OPENBLAS_NUM_THREADS."""
    code = ("import atexit, gc, os, sys\n"
            "atexit.register(lambda: print('state', gc.isenabled(), gc.get_freeze_count(),\n"
            "                              os.environ.get('OPENBLAS_NUM_THREADS'), file=sys.stderr))\n"
            "from cadedge.cli import entry\n"
            f"sys.argv = ['cadedge', *{args!r}]\n"
            "entry()\n")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"} | (extra_env or {})
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    return done.stderr.strip().splitlines()[-1]


def test_console_info_imports_ocp_frozen_out_of_the_collector():
    pytest.importorskip("OCP")
    _, enabled, frozen, blas = _console(["info", str(FIXTURES / "sphere.step")]).split()
    # OCP's objects (some 10^5) are frozen; the collector is back on for the rest of the run
    assert enabled == "True" and int(frozen) > 50_000
    assert blas == "1"


def test_console_refine_freezes_and_keeps_a_users_blas_threads(tmp_path):
    pytest.importorskip("OCP")
    args = ["refine", str(FIXTURES / "sphere.step"), "-o", str(tmp_path / "s.json")]
    _, enabled, frozen, blas = _console(args).split()
    assert enabled == "True" and int(frozen) > 50_000 and blas == "1"
    assert _console(args, {"OPENBLAS_NUM_THREADS": "2"}).split()[3] == "2"
    assert (tmp_path / "s.json").exists()


def test_main_in_process_leaves_the_collector_alone():
    pytest.importorskip("OCP")
    path = str(FIXTURES / "sphere.step")
    mods = _modules_after("import gc, os\nos.environ.pop('OPENBLAS_NUM_THREADS', None)\n"
                          f"from cadedge.cli import main\nassert main(['info', {path!r}]) == 0\n"
                          "assert gc.isenabled() and gc.get_freeze_count() == 0\n"
                          "assert 'OPENBLAS_NUM_THREADS' not in os.environ")
    assert "cadedge.occt.describe" in mods
