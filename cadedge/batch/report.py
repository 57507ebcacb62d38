"""Plain results of a batch: one :class:`FileResult` per input, progress snapshots, the report."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path


@dataclass(frozen=True)
class FileResult:
    """One input's outcome: ``status`` is "ok" or "failed" (then ``error`` holds the reason)."""

    input: str
    output: str
    status: str
    edges: int | None = None
    segments: int | None = None
    worst_ald: float | None = None
    seconds: float | None = None
    error: str | None = None
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class BatchProgress:
    """Sent to the ``progress`` callback once before the first task (``last`` None) and after each."""

    total: int
    done: int
    ok: int
    failed: int
    skipped: int
    skipped_failed: int
    last: FileResult | None = None


@dataclass
class BatchReport:
    """What a batch did. ``results`` are the inputs processed now; ``skipped`` the inputs finished
    in an earlier run; ``skipped_failed`` the inputs that failed earlier and were not retried.
    ``seconds`` is the whole call; ``phases`` splits it: ``plan`` (inputs and index), ``start`` (cluster
    started or scheduler reached), ``run`` (from then to the last outcome recorded), ``close`` (cluster
    closed); ``start``, ``run`` and ``close`` only when something was due."""

    outdir: Path
    index: Path
    results: list[FileResult] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    skipped_failed: list[FileResult] = field(default_factory=list)
    seconds: float = 0.0
    phases: dict[str, float] = field(default_factory=dict)

    @property
    def ok(self) -> list[FileResult]:
        return [r for r in self.results if r.status == "ok"]

    @property
    def failed(self) -> list[FileResult]:
        return [r for r in self.results if r.status == "failed"]

    @property
    def all_ok(self) -> bool:
        """True when no input named is in a failed state (now or from an earlier run)."""
        return not self.failed and not self.skipped_failed
