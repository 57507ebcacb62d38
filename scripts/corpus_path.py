"""Where the third-party STEP corpus is, for the tests and the benchmark scripts alike.

The corpus (real STEP files from other projects, described in its ``SOURCES.tsv``) is never copied
into the repository. It is found through the environment variable ``CADEDGE_CORPUS`` (a folder; a
relative path is taken from the current directory), else in ``../shared/corpus`` beside the
repository when that folder exists. Without it, the tests that read it skip and say why; with
``CADEDGE_REQUIRE_CORPUS=1`` (as in CI) a missing corpus is an error instead.
"""

from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENV = "CADEDGE_CORPUS"
REQUIRE_ENV = "CADEDGE_REQUIRE_CORPUS"
#: Used when ``CADEDGE_CORPUS`` is not set.
DEFAULT = ROOT.parent / "shared" / "corpus"
STEP_SUFFIXES = (".step", ".stp")


def find_corpus() -> Path | None:
    """The corpus folder (absolute), or None when ``CADEDGE_CORPUS`` or the default names no folder."""
    value = os.environ.get(ENV)
    folder = Path(value).expanduser() if value else DEFAULT
    return folder.resolve() if folder.is_dir() else None


def missing_reason() -> str:
    """One line saying why there is no corpus and how to point at it."""
    value = os.environ.get(ENV)
    if value:
        return f"third-party STEP corpus not found: {ENV}={value} is not a folder"
    return (f"third-party STEP corpus not found: set {ENV} to its folder "
            "(default ../shared/corpus beside the repository)")


def corpus_required() -> bool:
    """True when a missing corpus must fail rather than skip (``CADEDGE_REQUIRE_CORPUS=1``, as in CI)."""
    return os.environ.get(REQUIRE_ENV, "").strip().lower() not in ("", "0", "false", "no")


def step_files(folder: Path | None) -> list[Path]:
    """The STEP files of the corpus folder, sorted by name; none without a folder."""
    if folder is None:
        return []
    return sorted(p for p in folder.iterdir() if p.suffix.lower() in STEP_SUFFIXES)


def sources(folder: Path | None) -> dict[str, dict[str, str]]:
    """Rows of the corpus's ``SOURCES.tsv`` (what each file holds), keyed by file name; none without a folder."""
    if folder is None:
        return {}
    lines = (folder / "SOURCES.tsv").read_text(encoding="utf-8").splitlines()
    header = lines[0].split("\t")
    return {row[0]: dict(zip(header, row)) for row in (line.split("\t") for line in lines[1:] if line.strip())}


def require_corpus() -> Path:
    """The corpus folder for a script that cannot run without it; else exits with the reason."""
    folder = find_corpus()
    if folder is None:
        raise SystemExit(missing_reason())
    return folder
