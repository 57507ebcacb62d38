"""The README's "Python API in CAD scripts" examples run as written, so the README cannot rot.

Each fenced ``python`` block starting with ``# example: NAME`` is executed in a fresh namespace inside
a temporary folder; the JSON it writes must validate against the shipped schema.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from cadedge.exporters.json import validate

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCK = re.compile(r"```python\n(# example: (\S+)\n.*?)```", re.S)


def examples() -> dict[str, str]:
    section = README.read_text(encoding="utf-8").split("## Python API in CAD scripts", 1)[1].split("\n## ", 1)[0]
    return {name: code for code, name in BLOCK.findall(section)}


def test_readme_has_both_examples():
    assert sorted(examples()) == ["build123d", "cadquery"]


@pytest.mark.parametrize("name, output", [("cadquery", "plate.json"), ("build123d", "bracket.json")])
def test_readme_example_runs(name, output, tmp_path, monkeypatch, capsys):
    pytest.importorskip(name)
    monkeypatch.chdir(tmp_path)
    exec(compile(examples()[name], f"README.md:{name}", "exec"), {"__name__": "__main__"})
    doc = json.loads((tmp_path / output).read_text())
    validate(doc)
    printed = capsys.readouterr().out
    assert doc["summary"]["edges"] == 27 and doc["source"].startswith(f"<{name}")
    assert str(doc["summary"]["edges"]) in printed
    assert doc["summary"]["max_ald_estimate"] <= doc["options"]["ald"]


def test_readme_api_example_runs(tmp_path, monkeypatch, capsys):
    """The "Python API" block: curves in both modes and a bundled fixture written as VTK."""
    section = README.read_text(encoding="utf-8").split("## Python API\n", 1)[1].split("\n## ", 1)[0]
    (code, name), = BLOCK.findall(section)
    assert name == "api"
    monkeypatch.chdir(tmp_path)
    (tmp_path / "fixtures").mkdir()
    (tmp_path / "fixtures" / "bracket.step").write_bytes((README.parent / "fixtures" / "bracket.step").read_bytes())
    namespace = {"__name__": "__main__"}
    exec(compile(code, "README.md:api", "exec"), namespace)
    assert namespace["grid"].ald_estimate <= 1e-4 and namespace["paper"].mode == "paper"
    assert (tmp_path / "bracket.vtp").stat().st_size > 0
    assert capsys.readouterr().out.strip()
