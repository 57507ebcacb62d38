"""The examples in docstrings run as written."""

import doctest
import importlib

import pytest

MODULES = ["cadedge.refine", "cadedge.yardsticks.reference", "cadedge.mesh.status", "cadedge.mesh.segments",
           "cadedge.mesh.shards", "cadedge.mesh.report",
           "cadedge.mesh.coincident", "cadedge.mesh.quality", "cadedge.mesh.gridded", "cadedge.mesh.torus_fit",
           "cadedge.mesh.moves", "cadedge.occt.step"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0, f"{name} has no examples"
    assert result.failed == 0
