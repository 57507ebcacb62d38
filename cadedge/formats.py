"""The model file formats cadedge reads, by file suffix: the one list that the reader dispatches on and
that a batch searches folders for. Plain data, no OCP, so the batch driver can use it without OCCT."""

from __future__ import annotations

#: File suffixes (lower case; files match in any case) and the format each is read as.
INPUT_FORMATS: dict[str, str] = {".step": "STEP", ".stp": "STEP", ".igs": "IGES", ".iges": "IGES", ".brep": "BREP"}
#: The suffixes alone, in that order.
INPUT_SUFFIXES: tuple[str, ...] = tuple(INPUT_FORMATS)

__all__ = ["INPUT_FORMATS", "INPUT_SUFFIXES"]
