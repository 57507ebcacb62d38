"""How each face's meshing went: the strategy that meshed it or every failed attempt's reason, and the
short lines that name the failed faces."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class FaceFailure:
    """A face gmsh could not mesh conformingly: B-rep face id, gmsh surface tag and gmsh's reason."""

    face: int
    surface: int
    reason: str

    def line(self) -> str:
        return f"face {self.face}: gmsh failed: {self.reason}"


@dataclass
class FaceOutcome:
    """How a face fared: the strategy that meshed it (``None``: failed) and every failed attempt's reason;
    ``tangles``, where its boundary crossed itself, as balls (centre, radius) round those places
    (:func:`cadedge.mesh.parametric.tangle_zones`)."""

    face: int
    surface: int
    strategy: str | None = None
    attempts: list[tuple[str, str]] = field(default_factory=list)
    triangles: int = 0
    tangles: list[tuple[tuple[float, float, float], float]] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.strategy is not None

    def reason(self) -> str:
        """Short reason for a failed face: gmsh's message for the first strategy tried, how many others
        failed and how many were not tried (barred after a hang, or out of time)."""
        if not self.attempts:
            return "not meshed"
        tried = [a for a in self.attempts if not a[1].startswith("not tried")] or self.attempts
        name, first = tried[0]
        more = [f"{len(tried) - 1} other strategies failed"] if len(tried) > 1 else []
        if len(tried) < len(self.attempts):
            more.append(f"{len(self.attempts) - len(tried)} not tried")
        return f"{name}: {first}" + (f" ({', '.join(more)})" if more else "")


def _id_list(ids: list[int], limit: int = 8) -> str:
    shown = ", ".join(str(i) for i in ids[:limit])
    return shown + (f", ... ({len(ids)} in all)" if len(ids) > limit else "")


#: At most this many failure lines without ``verbose``; the rest is counted.
MAX_FAILURE_LINES = 5


def failure_lines(failures: list[FaceFailure], outcomes: list[FaceOutcome], *, total: int,
                  verbose: bool = False) -> list[str]:
    """The failed faces, short: one line per distinct reason naming its faces (at most
    :data:`MAX_FAILURE_LINES`); with ``verbose`` one line per face and failed attempt."""
    if not failures:
        return []
    if verbose:
        by_face = {o.face: o for o in outcomes}
        out = []
        for f in failures:
            attempts = by_face[f.face].attempts if f.face in by_face else []
            out += [f"face {f.face}: {name}: {why}" for name, why in attempts] or [f.line()]
        return out
    groups: dict[str, list[int]] = {}
    for f in failures:
        groups.setdefault(f.reason, []).append(f.face)
    head = f"{len(failures)} of {total} faces failed" if total else f"{len(failures)} faces failed"
    lines = []
    for reason, faces in sorted(groups.items(), key=lambda kv: -len(kv[1]))[:MAX_FAILURE_LINES]:
        word = "face" if len(faces) == 1 else "faces"
        lines.append(f"{head}: {word} {_id_list(faces)}: {reason}")
    if len(groups) > MAX_FAILURE_LINES:
        lines.append(f"{head}: {len(groups) - MAX_FAILURE_LINES} more reasons (--verbose lists every face)")
    return lines
