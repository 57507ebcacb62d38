"""Start-up: each CLI command imports only what it uses, and the public API still resolves in full."""

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


def test_every_public_name_resolves():
    import cadedge

    for name in cadedge.__all__:
        assert getattr(cadedge, name) is not None
    assert set(cadedge.__all__) <= set(dir(cadedge))
    with pytest.raises(AttributeError):
        cadedge.no_such_name  # noqa: B018
