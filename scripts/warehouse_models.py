"""Catalogue parts from bd_warehouse (build123d's parts library), for ``cadedge mesh`` on parts as users draw them.

Fasteners (ISO hex nuts plain and threaded, a DIN square nut, a washer, socket-head, hex-head and
countersunk screws, their threads left out but for the threaded nut), a 608 ball bearing, ASME weld-neck
and blind flanges, a spur gear and a chain sprocket: the sweep of docs/mesh.md's *Files from elsewhere*.
bd_warehouse is not a dependency of cadedge: install it beside it first.

    pip install bd_warehouse
    python scripts/warehouse_models.py warehouse      # writes warehouse/<name>.step for every part
    python scripts/bench_mesh_fidelity.py warehouse/*.step --cadedge-only --eps 1e-2 1e-3

``MODELS`` maps each name to a builder returning a build123d ``Part``.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any, Callable


def _fastener(kind: str, *args: Any, **kw: Any) -> Callable[[], Any]:
    def build() -> Any:
        from bd_warehouse import fastener

        return getattr(fastener, kind)(*args, **kw)
    return build


def _bearing() -> Any:
    from bd_warehouse.bearing import SingleRowDeepGrooveBallBearing

    return SingleRowDeepGrooveBallBearing("M8-22-7")


def _weld_neck_flange() -> Any:
    from bd_warehouse.flange import WeldNeckFlange

    return WeldNeckFlange(nps="2", flange_class=150)


def _blind_flange() -> Any:
    from bd_warehouse.flange import BlindFlange

    return BlindFlange(nps="2", flange_class=150)


def _spur_gear() -> Any:
    from bd_warehouse.gear import SpurGear

    return SpurGear(module=2, tooth_count=20, pressure_angle=20, thickness=8)


def _sprocket() -> Any:
    from bd_warehouse.sprocket import Sprocket

    return Sprocket(num_teeth=16)


MODELS: dict[str, Callable[[], Any]] = {
    "hexnut_m8": _fastener("HexNut", "M8-1.25", "iso4032", simple=True),
    "hexnut_m8_thread": _fastener("HexNut", "M8-1.25", "iso4032", simple=False),
    "squarenut_m6": _fastener("SquareNut", "M6-1", "din557", simple=True),
    "washer_m8": _fastener("PlainWasher", "M8", "iso7089"),
    "shcs_m6": _fastener("SocketHeadCapScrew", "M6-1", 20, "iso4762", simple=True),
    "hexhead_m8": _fastener("HexHeadScrew", "M8-1.25", 30, "iso4014", simple=True),
    "csk_m5": _fastener("CounterSunkScrew", "M5-0.8", 16, "iso10642", simple=True),
    "bearing_608": _bearing,
    "flange_wn": _weld_neck_flange,
    "flange_blind": _blind_flange,
    "spur_gear": _spur_gear,
    "sprocket": _sprocket,
}


def write_model(name: str, folder: Path) -> Path:
    """Write part ``name`` as ``folder/<name>.step``; returns the path."""
    from build123d import export_step

    path = Path(folder) / f"{name}.step"
    export_step(MODELS[name](), str(path))
    return path


if __name__ == "__main__":
    from hard_models import write_all

    sys.exit(write_all(sys.argv[1:], list(MODELS), write_model, "bd_warehouse part", "warehouse"))
