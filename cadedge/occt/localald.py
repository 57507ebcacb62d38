"""Local ALD targets, ``refine_shape(..., ald_for={key: eps})``: the keys resolved to one target per edge.

A key names an edge or a face of the shape being refined:

- a build123d or cadquery ``Edge``/``Face``, or an OCP ``TopoDS_Edge``/``TopoDS_Face`` (any
  ``TopoDS_Shape`` of those types), matched with ``IsSame`` (same TShape and location, any orientation)
  against the shape's ``TopExp::MapShapes``; a copy or a moved/transformed shape is a different shape;
- a cadquery ``Workplane`` selection, e.g. ``part.faces(">Z")``: every edge or face it holds;
- an id as a pair ``("edge", n)`` or ``("face", n)``, 1-based as in the output and ``cadedge info``.
  A bare integer is refused: an edge id and a face id are both plain integers, so the pair says which.

A face stands for its edges. An edge's target is the finest (smallest) of the global ``ald`` and every
setting that reaches it: its own, and those of each face it bounds. Keys and targets are checked in
two steps: :func:`check_ald_for` before the (possibly slow) read, :func:`edge_targets` against the
model's topology once it is loaded.
"""

from __future__ import annotations

import numbers
from collections import defaultdict
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS_Shape

from ..errors import InputError
from ..options import refine_options
from .compat import TopTools_IndexedMapOfShape
from .topology import Topology

KINDS = ("edge", "face")
_SHAPE_KINDS = {TopAbs_EDGE: "edge", TopAbs_FACE: "face"}


@dataclass(frozen=True)
class LocalAld:
    """One checked setting: an edge or face given by ``shape`` (a ``TopoDS_Shape``) or by ``id``."""

    kind: str
    ald: float
    label: str
    id: int | None = None
    shape: TopoDS_Shape | None = None


def _label(obj: Any) -> str:
    """A short name of a key for messages: ``('edge', 3)`` as written, a shape as ``<build123d Edge>``."""
    if isinstance(obj, (tuple, str, numbers.Number)):
        return repr(obj)
    if isinstance(obj, TopoDS_Shape):
        return f"<{type(obj).__name__}>"
    return f"<{type(obj).__module__.split('.')[0]} {type(obj).__name__}>"


def _wrapped(obj: Any) -> TopoDS_Shape | None:
    """The ``TopoDS_Shape`` inside a cadquery/build123d object, or None."""
    try:
        inner = obj.wrapped
    except (AttributeError, AssertionError):  # build123d asserts on an empty shape's .wrapped
        return None
    return inner if isinstance(inner, TopoDS_Shape) else None


def _shape_setting(shape: TopoDS_Shape, eps: float, label: str) -> LocalAld:
    if shape.IsNull():
        raise InputError(f"ald_for key {label}: null shape")
    kind = _SHAPE_KINDS.get(shape.ShapeType())
    if kind is None:
        got = str(shape.ShapeType()).rsplit("_", 1)[-1].lower()
        raise InputError(f"ald_for key {label}: expected an edge or a face, got a {got}")
    return LocalAld(kind=kind, ald=eps, label=label, shape=shape)


def _settings(key: Any, eps: float) -> list[LocalAld]:
    """The settings one key stands for (a cadquery Workplane may hold several edges or faces)."""
    if isinstance(key, tuple) and len(key) == 2 and isinstance(key[0], str):
        kind, ident = key
        if kind not in KINDS or isinstance(ident, bool) or not isinstance(ident, numbers.Integral):
            raise InputError(f"ald_for key {key!r}: an id key is ('edge', N) or ('face', N) with an integer N")
        if ident < 1:
            raise InputError(f"ald_for key {key!r}: ids start at 1")
        return [LocalAld(kind=kind, ald=eps, label=f"{kind} {int(ident)}", id=int(ident))]
    if isinstance(key, numbers.Integral):
        raise InputError(f"ald_for key {key!r}: a bare integer could be an edge or a face id; "
                         f"write ('edge', {key!r}) or ('face', {key!r})")
    if isinstance(key, TopoDS_Shape):
        return [_shape_setting(key, eps, _label(key))]
    if hasattr(key, "vals") and callable(key.vals):  # cadquery Workplane: each object it holds
        items = key.vals()
        shapes = [_wrapped(v) for v in items]
        if not items or any(s is None for s in shapes):
            raise InputError(f"ald_for key {_label(key)}: the selection holds no edges or faces")
        return [_shape_setting(s, eps, f"{_label(key)} item {k + 1} {_label(v)}")
                for k, (s, v) in enumerate(zip(shapes, items))]
    shape = _wrapped(key)
    if shape is not None:
        return [_shape_setting(shape, eps, _label(key))]
    raise InputError(f"ald_for key {_label(key)}: expected an edge or a face (build123d, cadquery or TopoDS) "
                     "or an id ('edge', N) / ('face', N)")


def check_ald_for(ald_for: Mapping[Any, Any] | None) -> list[LocalAld]:
    """The settings of ``ald_for`` with their targets checked as ``ald`` is; InputError naming the key."""
    if ald_for is None:
        return []
    if not isinstance(ald_for, Mapping):
        raise InputError(f"ald_for must be a mapping from edges or faces to their ald, got a "
                         f"{type(ald_for).__name__}")
    out: list[LocalAld] = []
    for key, value in ald_for.items():
        try:
            eps = refine_options(value)["ald"]
        except InputError as exc:
            raise InputError(f"ald_for key {_label(key)}: {exc}") from None
        out.extend(_settings(key, eps))
    return out


def _index(shape: TopoDS_Shape, kind: Any) -> TopTools_IndexedMapOfShape:
    m = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, kind, m)
    return m


def _id_of(s: LocalAld, topo: Topology, maps: dict[str, TopTools_IndexedMapOfShape]) -> int:
    """The 1-based id of the edge or face a setting names; InputError if the shape has none such."""
    count = len(topo.edges) if s.kind == "edge" else len(topo.faces)
    if s.shape is None:
        if s.id > count:
            have = f"{s.kind}s 1 to {count}" if count else f"no {s.kind}s"
            raise InputError(f"local ald for {s.label}: no such {s.kind} (the shape has {have})")
        return s.id
    if s.kind not in maps:
        maps[s.kind] = _index(topo.shape, TopAbs_EDGE if s.kind == "edge" else TopAbs_FACE)
    found = maps[s.kind].FindIndex(s.shape)
    if found == 0:
        article = "an" if s.kind == "edge" else "a"
        raise InputError(f"ald_for key {s.label}: not {article} {s.kind} of the shape being refined (a copy, or "
                         f"a moved or transformed shape, is a different {s.kind}: select it from the refined shape)")
    return found


def edge_targets(settings: list[LocalAld], topo: Topology, ald: float) -> tuple[np.ndarray, list[dict[str, Any]],
                                                                                 list[str]]:
    """Per edge (MapShapes order) the finest target among ``ald`` and the settings reaching it.

    Also returns the settings by id, as recorded in the output's ``options.ald_for`` (one entry per
    edge or face named, the finest value where one is named twice; edges first, by id), and notes
    for settings coarser than ``ald``, which therefore change nothing.
    """
    targets = np.full(len(topo.edges), ald, dtype=float)
    named: dict[tuple[str, int], float] = {}
    maps: dict[str, TopTools_IndexedMapOfShape] = {}
    for s in settings:
        key = (s.kind, _id_of(s, topo, maps))
        named[key] = min(named.get(key, s.ald), s.ald)
    face_edges: dict[int, list[int]] = defaultdict(list)
    if any(kind == "face" for kind, _ in named):
        for i, faces in enumerate(topo.edge_faces):
            for f in faces:
                face_edges[f].append(i)
    for (kind, ident), eps in named.items():
        idx = [ident - 1] if kind == "edge" else face_edges[ident]
        targets[idx] = np.minimum(targets[idx], eps)
    records = [{"kind": kind, "id": ident, "ald": named[(kind, ident)]}
               for kind, ident in sorted(named, key=lambda k: (KINDS.index(k[0]), k[1]))]
    notes = [f"local ald for {r['kind']} {r['id']}: {r['ald']:g} is coarser than ald {ald:g}, and the "
             "finest target wins, so it changes nothing" for r in records if r["ald"] > ald]
    return targets, records, notes
