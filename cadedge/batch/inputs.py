"""Batch inputs: expand files, folders and globs into model files, and give each a unique output name.

Folders are searched recursively for ``.step``/``.stp``/``.igs``/``.iges``/``.brep`` (any case); globs
may use ``**``. Inputs are
deduplicated by resolved path, keeping the first occurrence's order. Output names are the file's stem
plus ``.json``; when two inputs share a stem (in this batch, or with a different input already in the
index), the colliding ones get ``<stem>-<8 hex digits of sha1(resolved path)>.json``, so a name is
stable for a given file and never shared by two files.
"""

from __future__ import annotations

import glob
import hashlib
import os
from collections import Counter
from pathlib import Path
from typing import Iterable, Mapping

from ..errors import InputError
from ..formats import INPUT_SUFFIXES

_KINDS = "/".join(INPUT_SUFFIXES)
_GLOB_CHARS = frozenset("*?[")


def _is_step(path: Path) -> bool:
    return path.suffix.lower() in INPUT_SUFFIXES


def _step_files_under(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file() and _is_step(p))


def _expand_one(item: str) -> list[Path]:
    path = Path(item).expanduser()
    if path.is_dir():
        found = _step_files_under(path)
        if not found:
            raise InputError(f"{item}: folder holds no {_KINDS} files")
        return found
    if path.is_file():
        return [path]
    if _GLOB_CHARS.intersection(item):
        found = []
        for match in sorted(glob.glob(os.path.expanduser(item), recursive=True)):
            m = Path(match)
            if m.is_dir():
                found.extend(_step_files_under(m))
            elif m.is_file() and _is_step(m):
                found.append(m)
        if not found:
            raise InputError(f"{item}: pattern matches no {_KINDS} files")
        return found
    raise InputError(f"{item}: no such file or folder")


def expand_inputs(items: Iterable[str | os.PathLike]) -> list[Path]:
    """Resolved model paths named by ``items`` (files, folders, globs), deduplicated, in order.

    Raises :class:`InputError` naming the first item that is missing or matches nothing, and when
    there are no items at all. A file named explicitly is taken whatever its suffix.
    """
    seen: dict[Path, None] = {}
    any_item = False
    for item in items:
        any_item = True
        for path in _expand_one(os.fspath(item)):
            seen.setdefault(path.resolve(), None)
    if not any_item:
        raise InputError("no inputs given")
    return list(seen)


def path_hash(path: Path) -> str:
    """8 hex digits identifying a resolved path."""
    return hashlib.sha1(str(path).encode("utf-8", "surrogateescape")).hexdigest()[:8]


def output_names(paths: Iterable[Path], taken: Mapping[str, str] | None = None) -> dict[Path, str]:
    """A unique ``.json`` file name for each resolved path.

    ``taken`` maps names already used in the output folder to the input (as a string) that owns them
    (from the index): an input keeps the name it owns there, and no other input gets it.
    """
    taken = dict(taken or {})
    owned = {inp: name for name, inp in taken.items()}
    paths = list(paths)
    fresh = [p for p in paths if str(p) not in owned]
    stems = Counter(p.stem for p in fresh)
    names: dict[Path, str] = {}
    for p in paths:
        if str(p) in owned:
            names[p] = owned[str(p)]
            continue
        plain = f"{p.stem}.json"
        unique = stems[p.stem] == 1 and taken.get(plain, str(p)) == str(p)
        names[p] = plain if unique else f"{p.stem}-{path_hash(p)}.json"
        taken[names[p]] = str(p)
    return names
