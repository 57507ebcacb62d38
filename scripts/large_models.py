"""Large everyday parts for ``cadedge mesh``: many faces, long faces beside small features, sharp valleys.

They are the parts of docs/mesh.md's *Large parts* table: a 1 000 mm I-beam with 0.4 mm fillets
(over a hundred thousand boundary segments at 1e-2), a 200 x 200 plate with 900 holes, a heat sink with
40 filleted fins, a disc with 72 filleted holes on a bolt circle, a gear whose side is one spline of 30
lobes with sharp valleys (cyclo_gear), the same with rounder valleys (lobed_gear) and a hex nut whose
30-degree chamfer cone touches its flats; and small curved faces on large parts, each face's curvature
sizes past the triangle budget: a 200 mm flange with 0.2 mm fillets on an O-ring groove (the same at 100
mm), a 0.2 mm torus alone and a 1 x 1 000 mm rod.
They are kept apart from ``scripts/hard_models.py`` because each takes minutes at ``--ald 1e-3``.

    python scripts/large_models.py large         # writes large/<name>.step for every model
    python scripts/bench_mesh_fidelity.py large/*.step --cadedge-only --eps 1e-2 1e-3 --timeout 300

``MODELS`` maps each name to a builder returning an OCP ``TopoDS_Shape``.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Callable

import cadquery as cq


def i_beam() -> object:
    """An I-beam 200 high, 100 wide, 1 000 long (10 mm flanges, 6 mm web), every long edge filleted 0.4."""
    h, b, tf, tw = 200.0, 100.0, 10.0, 6.0
    pts = [(-b / 2, -h / 2), (b / 2, -h / 2), (b / 2, -h / 2 + tf), (tw / 2, -h / 2 + tf), (tw / 2, h / 2 - tf),
           (b / 2, h / 2 - tf), (b / 2, h / 2), (-b / 2, h / 2), (-b / 2, h / 2 - tf), (-tw / 2, h / 2 - tf),
           (-tw / 2, -h / 2 + tf), (-b / 2, -h / 2 + tf)]
    beam = cq.Workplane("XY").polyline(pts).close().extrude(1000.0)
    return beam.edges("|Z").fillet(0.4).val().wrapped


def _plate(side: float, holes: int) -> object:
    """A ``side`` x ``side`` x 3 plate with ``holes`` x ``holes`` holes of 3 mm diameter at a 6.5 mm pitch."""
    grid = [((i - (holes - 1) / 2) * 6.5, (j - (holes - 1) / 2) * 6.5) for i in range(holes) for j in range(holes)]
    plate = cq.Workplane("XY").box(side, side, 3.0)
    return plate.faces(">Z").workplane().pushPoints(grid).hole(3.0).val().wrapped


def perforated_plate() -> object:
    """A 200 x 200 x 3 plate with 30 x 30 holes of 3 mm diameter at a 6.5 mm pitch."""
    return _plate(200.0, 30)


def plate_225() -> object:
    """A 100 x 100 x 3 plate with 15 x 15 holes of 3 mm diameter at a 6.5 mm pitch: the perforated plate's
    faces a quarter as many, meshed in full within the default --timeout at 1e-3."""
    return _plate(100.0, 15)


def heat_sink() -> object:
    """A 100 x 80 x 6 base with 40 fins 1 mm thick and 40 mm high at a 2.5 mm pitch, fin tops filleted 0.4."""
    base = cq.Workplane("XY").box(100.0, 80.0, 6.0).translate((0, 0, 3.0))
    fins = (cq.Workplane("XY").pushPoints([((i - 19.5) * 2.5, 0) for i in range(40)])
            .rect(1.0, 80.0).extrude(40.0).translate((0, 0, 6.0)))
    fins = fins.edges(">Z").fillet(0.4)
    return base.union(fins).val().wrapped


def bolt_circle_fillets() -> object:
    """A disc 200 across and 10 thick with 72 holes of 6 mm on a 160 mm circle, their top edges filleted 0.5."""
    c = 0.5 * (1 - 1 / math.sqrt(2))  # the fillet arc's middle, inset from its corner
    tool = (cq.Workplane("XZ").moveTo(0, -1).lineTo(3, -1).lineTo(3, 9.5)
            .threePointArc((3 + c, 10 - c), (3.5, 10)).lineTo(3.5, 11).lineTo(0, 11).close()
            .revolve(360, (0, 0, 0), (0, 1, 0)).val())
    disc = cq.Workplane("XY").circle(100.0).extrude(10.0).val()
    for k in range(72):  # one cut at a time: OCCT's fillet of the 72 edges, or one cut by all the tools, fails
        a = 2 * math.pi * k / 72
        disc = disc.cut(tool.moved(cq.Location(cq.Vector(80 * math.cos(a), 80 * math.sin(a), 0))))
    return disc.wrapped


def _lobed_gear(power: float) -> object:
    """A gear 10 thick whose side is one periodic spline through 600 points of r = 40 + 3 |cos 15 t|**power
    (30 lobes), with a 20 mm bore."""
    n = 600
    pts = []
    for k in range(n):
        t = 2 * math.pi * k / n
        r = 40.0 + 3.0 * abs(math.cos(15 * t)) ** power
        pts.append((r * math.cos(t), r * math.sin(t)))
    side = cq.Workplane("XY").spline(pts, periodic=True).close().extrude(10.0)
    return side.faces(">Z").workplane().hole(20.0).val().wrapped


def cyclo_gear() -> object:
    """:func:`_lobed_gear` with sharp valleys: r = 40 + 3 |cos 15 t|**0.3."""
    return _lobed_gear(0.3)


def lobed_gear() -> object:
    """:func:`_lobed_gear` with rounder valleys: r = 40 + 3 |cos 15 t|."""
    return _lobed_gear(1.0)


def hex_nut() -> object:
    """An M10 nut (16 across flats, 8 thick, 8.5 bore) chamfered at 30 degrees on both sides by a cone that
    touches the flats: the cone meets each flat at one point."""
    af, height = 16.0, 8.0
    nut = cq.Workplane("XY").polygon(6, af / math.cos(math.pi / 6)).extrude(height)
    r0 = af / 2  # the cone's circle on each end face: tangent to the flats
    big = af / math.cos(math.pi / 6) / 2 + 0.5  # past the corners
    rise = (big - r0) * math.tan(math.radians(30))
    profile = cq.Workplane("XZ").polyline([(0, 0), (r0, 0), (big, rise), (big, height - rise), (r0, height),
                                           (0, height)]).close()
    keep = profile.revolve(360, (0, 0, 0), (0, 1, 0))
    nut = nut.intersect(keep)
    return nut.faces(">Z").workplane().hole(8.5).val().wrapped


def _grooved_flange(diameter: float) -> object:
    """A disc ``diameter`` across and 20 thick with a bore of half that, and an O-ring groove 4 wide and 3
    deep on the circle of 0.4 ``diameter``, whose two top edges are filleted 0.2."""
    body = cq.Workplane("XY").circle(diameter / 2).circle(diameter / 4).extrude(20)
    groove = cq.Workplane("XY").workplane(offset=17).circle(0.4 * diameter).circle(0.4 * diameter - 4).extrude(3)
    body = body.cut(groove)
    rims = [e for e in body.edges().vals() if e.geomType() == "CIRCLE" and abs(e.Center().z - 20) < 1e-6
            and min(abs(e.radius() - 0.4 * diameter), abs(e.radius() - 0.4 * diameter + 4)) < 1e-6]
    return body.val().fillet(0.2, rims).wrapped


def flange_200() -> object:
    """:func:`_grooved_flange` 200 mm across: two 0.2 mm fillets about 500 mm long."""
    return _grooved_flange(200.0)


def flange_100() -> object:
    """:func:`_grooved_flange` 100 mm across."""
    return _grooved_flange(100.0)


def torus_fillet() -> object:
    """A torus R 35, r 0.2: one 0.2 mm fillet along a 220 mm edge, alone."""
    return cq.Solid.makeTorus(35.0, 0.2).wrapped


def rod() -> object:
    """A rod 1 mm across and 1 000 long: one long thin cylinder."""
    return cq.Workplane("XY").circle(0.5).extrude(1000).val().wrapped


MODELS: dict[str, Callable[[], object]] = {
    "i_beam": i_beam, "perforated_plate": perforated_plate, "plate_225": plate_225, "heat_sink": heat_sink,
    "bolt_circle_fillets": bolt_circle_fillets, "cyclo_gear": cyclo_gear, "lobed_gear": lobed_gear,
    "hex_nut": hex_nut, "flange_200": flange_200, "flange_100": flange_100, "torus_fillet": torus_fillet,
    "rod": rod,
}


def write_model(name: str, folder: Path) -> Path:
    """Write model ``name`` as ``folder/<name>.step``; returns the path."""
    path = Path(folder) / f"{name}.step"
    cq.exporters.export(cq.Shape.cast(MODELS[name]()), str(path), exportType="STEP")
    return path


if __name__ == "__main__":
    from hard_models import write_all

    sys.exit(write_all(sys.argv[1:], list(MODELS), write_model, "large model", "large"))
