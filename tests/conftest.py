"""Shared test paths: the committed fixtures and the third-party STEP corpus (never copied in)."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "fixtures"
CORPUS = (ROOT.parent / "shared" / "corpus").resolve()
FIXTURE_FILES = sorted(FIXTURES.glob("*.step"))
CORPUS_FILES = sorted(p for p in CORPUS.glob("*") if p.suffix.lower() in (".step", ".stp"))


def corpus_sources() -> dict[str, dict[str, str]]:
    """Rows of ``SOURCES.tsv`` (what each corpus file holds), keyed by file name."""
    lines = (CORPUS / "SOURCES.tsv").read_text().splitlines()
    header = lines[0].split("\t")
    return {row[0]: dict(zip(header, row)) for row in (line.split("\t") for line in lines[1:] if line.strip())}


@pytest.fixture(scope="session")
def fixtures_dir() -> Path:
    return FIXTURES


@pytest.fixture(scope="session")
def corpus_dir() -> Path:
    if not CORPUS_FILES:
        pytest.fail(f"no STEP files in the corpus folder {CORPUS}")
    return CORPUS
