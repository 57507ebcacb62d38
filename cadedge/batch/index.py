"""The batch index: one SQLite row per input in ``OUTDIR/index.sqlite``.

Written only by the client process (one writer; WAL journal so readers never block it). Keyed by the
resolved input path; the input's size and mtime and the refinement options are stored so that a
changed input or changed options make the input due again.
"""

from __future__ import annotations

import json
import sqlite3
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

from ..errors import InputError

INDEX_NAME = "index.sqlite"

_SCHEMA = """
CREATE TABLE IF NOT EXISTS results (
    input TEXT PRIMARY KEY,
    output TEXT NOT NULL,
    status TEXT NOT NULL CHECK (status IN ('ok', 'failed')),
    edges INTEGER,
    segments INTEGER,
    worst_ald REAL,
    seconds REAL,
    error TEXT,
    warnings TEXT NOT NULL DEFAULT '[]',
    size INTEGER NOT NULL,
    mtime_ns INTEGER NOT NULL,
    options TEXT NOT NULL,
    finished_at TEXT NOT NULL
)
"""


@dataclass(frozen=True)
class IndexRow:
    """One input's last recorded outcome."""

    input: str
    output: str
    status: str
    edges: int | None
    segments: int | None
    worst_ald: float | None
    seconds: float | None
    error: str | None
    warnings: str
    size: int
    mtime_ns: int
    options: str
    finished_at: str


def options_key(options: dict[str, Any]) -> str:
    """The canonical text of refinement options stored with each row."""
    return json.dumps(options, sort_keys=True)


class BatchIndex:
    """The SQLite index of a batch output folder; use as a context manager or call :meth:`close`."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        try:
            self._db = sqlite3.connect(self.path)
            self._db.execute("PRAGMA journal_mode=WAL")
            self._db.execute(_SCHEMA)
            self._db.commit()
        except sqlite3.Error as exc:
            raise InputError(f"{self.path}: cannot open the batch index: {exc}") from None

    def __enter__(self) -> "BatchIndex":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._db.close()

    def get(self, input: str) -> IndexRow | None:
        row = self._db.execute("SELECT * FROM results WHERE input = ?", (input,)).fetchone()
        return IndexRow(*row) if row else None

    def rows(self) -> Iterator[IndexRow]:
        for row in self._db.execute("SELECT * FROM results ORDER BY input"):
            yield IndexRow(*row)

    def names(self) -> dict[str, str]:
        """Output name -> the input that owns it."""
        return dict(self._db.execute("SELECT output, input FROM results"))

    def record(self, *, input: str, output: str, status: str, size: int, mtime_ns: int, options: str,
               edges: int | None = None, segments: int | None = None, worst_ald: float | None = None,
               seconds: float | None = None, error: str | None = None,
               warnings: list[str] | tuple[str, ...] = ()) -> None:
        """Insert or replace one input's outcome and commit at once (a crash loses nothing recorded)."""
        finished = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        self._db.execute(
            "INSERT OR REPLACE INTO results VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (input, output, status, edges, segments, worst_ald, seconds, error, json.dumps(list(warnings)),
             size, mtime_ns, options, finished))
        self._db.commit()
