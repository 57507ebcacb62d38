"""JSON exporter: the ``cadedge.edgegrid/1`` document (docs/api.md).

Floats are written with Python's shortest round-trip ``repr``, so a vertex point shared bit-identically
by several edges stays bit-identical after ``json.loads``. The JSON Schema ships as package data
(``cadedge/schema/edgegrid-1.schema.json``); :func:`validate` checks a document against it plus the
few rules a schema cannot state (matching array lengths, ids in order, known vertex ids).
"""

from __future__ import annotations

import json
import math
from functools import lru_cache
from typing import Any

import numpy as np

from ..errors import CadedgeError, InputError
from ..shapegrid import SCHEMA, ShapeEdgeGrid, ShapeGrid, VertexGrid

SCHEMA_RESOURCE = "edgegrid-1.schema.json"
OPTION_KEYS = ("ald", "min_length", "max_length", "max_growth")


def _number(value: Any, what: str) -> float | None:
    """A finite Python float, or None for None; NaN/inf is a bug upstream and is refused, naming ``what``."""
    if value is None:
        return None
    out = float(value)
    if not math.isfinite(out):
        raise CadedgeError(f"{what} is {out!r}, which JSON cannot hold")
    return out


def _floats(values: Any, what: str) -> list:
    arr = np.asarray(values, dtype=float)
    if not np.isfinite(arr).all():
        raise CadedgeError(f"{what} has non-finite values, which JSON cannot hold")
    return arr.tolist()


def _vertex(v: VertexGrid) -> dict[str, Any]:
    what = f"vertex {v.id}"
    return {"id": int(v.id), "point": _floats(np.reshape(v.point, 3), f"{what} point"),
            "spacing": _number(v.spacing, f"{what} spacing")}


def _edge(e: ShapeEdgeGrid) -> dict[str, Any]:
    what = f"edge {e.id}"
    return {"id": int(e.id), "vertices": [int(e.vertices[0]), int(e.vertices[1])], "curve": str(e.curve),
            "degenerate": bool(e.degenerate), "closed": bool(e.closed), "faces": [int(f) for f in e.faces],
            "params": _floats(e.params, f"{what} params"),
            "points": _floats(np.reshape(e.points, (-1, 3)), f"{what} points"),
            "length": 0.0 if e.degenerate else _number(e.length, f"{what} length"),
            "ald_estimate": _number(e.ald_estimate, f"{what} ald_estimate"),
            "spacing": [_number(s, f"{what} spacing") for s in e.spacing]}


def to_document(grid: ShapeGrid) -> dict[str, Any]:
    """The ``cadedge.edgegrid/1`` document of ``grid`` as plain Python data (numpy converted)."""
    options = {key: _number(grid.options.get(key), f"option {key}") for key in OPTION_KEYS}
    if grid.options.get("ald_for"):  # local targets (refine_shape's ald_for), only when given
        options["ald_for"] = [{"kind": str(r["kind"]), "id": int(r["id"]),
                               "ald": _number(r["ald"], f"option ald_for {r['kind']} {r['id']}")}
                              for r in grid.options["ald_for"]]
    summary = grid.summary()
    return {"schema": SCHEMA, "source": str(grid.source), "units": str(grid.units), "options": options,
            "vertices": [_vertex(v) for v in grid.vertices], "edges": [_edge(e) for e in grid.edges],
            "summary": {"edges": int(summary["edges"]), "segments": int(summary["segments"]),
                        "max_ald_estimate": _number(summary["max_ald_estimate"], "max_ald_estimate"),
                        "seconds": _number(summary["seconds"], "seconds")}}


def to_bytes(grid: ShapeGrid) -> bytes:
    """UTF-8 JSON at full float precision, laid out one vertex or edge per line (diff- and grep-friendly)."""
    doc = to_document(grid)
    head = ",\n".join(f" {json.dumps(k)}: {json.dumps(doc[k], allow_nan=False)}"
                      for k in ("schema", "source", "units", "options"))
    parts = [f"{{\n{head},"]
    for key in ("vertices", "edges"):
        items = ",\n".join(f"  {json.dumps(item, allow_nan=False)}" for item in doc[key])
        parts.append(f' "{key}": [\n{items}\n ],' if items else f' "{key}": [],')
    parts.append(f' "summary": {json.dumps(doc["summary"], allow_nan=False)}\n}}\n')
    return "\n".join(parts).encode("utf-8")


@lru_cache(maxsize=1)
def schema() -> dict[str, Any]:
    """The shipped JSON Schema (draft 2020-12) of ``cadedge.edgegrid/1``."""
    from importlib import resources  # only for validation: not on the write path

    text = resources.files("cadedge").joinpath("schema", SCHEMA_RESOURCE).read_text(encoding="utf-8")
    return json.loads(text)


def validate(document: dict[str, Any]) -> None:
    """Raise :class:`InputError` naming the first problem if ``document`` is not valid ``cadedge.edgegrid/1``."""
    import jsonschema

    validator = jsonschema.Draft202012Validator(schema())
    error = jsonschema.exceptions.best_match(validator.iter_errors(document))
    if error is not None:
        where = "/".join(str(p) for p in error.absolute_path) or "(document)"
        raise InputError(f"not a valid {SCHEMA} document at {where}: {error.message}")
    vertex_ids = [v["id"] for v in document["vertices"]]
    if vertex_ids != list(range(1, len(vertex_ids) + 1)):
        raise InputError(f"not a valid {SCHEMA} document: vertex ids are not 1..{len(vertex_ids)} in order")
    edge_ids = [e["id"] for e in document["edges"]]
    if edge_ids != list(range(1, len(edge_ids) + 1)):
        raise InputError(f"not a valid {SCHEMA} document: edge ids are not 1..{len(edge_ids)} in order")
    if any(r["kind"] == "edge" and r["id"] > len(edge_ids) for r in document["options"].get("ald_for", [])):
        raise InputError(f"not a valid {SCHEMA} document: options.ald_for names an unknown edge")
    for e in document["edges"]:
        if len(e["params"]) != len(e["points"]):
            raise InputError(f"not a valid {SCHEMA} document: edge {e['id']} has {len(e['params'])} params "
                             f"but {len(e['points'])} points")
        if any(not 1 <= v <= len(vertex_ids) for v in e["vertices"]):
            raise InputError(f"not a valid {SCHEMA} document: edge {e['id']} names an unknown vertex")
        if any(b <= a for a, b in zip(e["params"], e["params"][1:])) and not e["degenerate"]:
            raise InputError(f"not a valid {SCHEMA} document: edge {e['id']} params are not increasing")
    if document["summary"]["edges"] != len(edge_ids):
        raise InputError(f"not a valid {SCHEMA} document: summary.edges is not the number of edges")
