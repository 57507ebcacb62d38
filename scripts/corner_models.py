"""Parts whose faces narrow to sharp corners, and flat caps bounded by one spline, for ``cadedge mesh``.

They are the parts of docs/mesh.md's *Boundary segments graded into a face's narrow corners* table and
of its planar-fit figures: a square nut and an internal hex socket whose chamfer or countersink cone
touches the flats (cusps: 0-degree corners), a 5-degree wedge, a 12-degree wedge with a round back, an
airfoil with a sharp trailing edge, a plate with a thin V notch (its top face nearly 360 degrees round
the notch's tip), extrusions of a 20 mm stadium outline (one periodic spline through 120 points) with
round ends of 0.3 and 1 mm, and a disk with a hole touching its rim (two cusps a face). The M10 hex nut
is ``scripts/large_models.py``'s ``hex_nut``.

    python scripts/corner_models.py corners      # writes corners/<name>.step for every model
    python scripts/bench_mesh_fidelity.py corners/*.step --cadedge-only --eps 1e-2 1e-3

``MODELS`` maps each name to a builder returning a cadquery ``Workplane``.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Callable

import cadquery as cq


def _chamfer_keep(r0: float, big: float, height: float, angle: float = 30.0) -> cq.Workplane:
    """The solid of revolution that chamfers both ends of a prism at ``angle`` degrees, its cone through
    the circle of radius ``r0`` on each end face."""
    rise = (big - r0) * math.tan(math.radians(angle))
    profile = cq.Workplane("XZ").polyline([(0, 0), (r0, 0), (big, rise), (big, height - rise), (r0, height),
                                           (0, height)]).close()
    return profile.revolve(360, (0, 0, 0), (0, 1, 0))


def square_nut() -> cq.Workplane:
    """A 10 x 10 x 5 square nut with a 5 mm bore, chamfered at 30 degrees by a cone that touches its four
    flats (each chamfer face ends in two cusps)."""
    nut = cq.Workplane("XY").rect(10.0, 10.0).extrude(5.0)
    return nut.intersect(_chamfer_keep(5.0, 10.0 / math.sqrt(2) + 0.5, 5.0)).faces(">Z").workplane().hole(5.0)


def hex_socket_cs() -> cq.Workplane:
    """A 30 x 30 x 10 block with a hex socket 12 across its flats, countersunk at 45 degrees by a cone whose
    smallest circle touches the flats (cusps on the inside)."""
    block = cq.Workplane("XY").box(30.0, 30.0, 10.0).translate((0, 0, 5.0))
    socket = cq.Workplane("XY").polygon(6, 12.0 / math.cos(math.pi / 6)).extrude(10.0)
    cone = cq.Solid.makeCone(16.0, 6.0, 10.0, pnt=cq.Vector(0, 0, 10.0), dir=cq.Vector(0, 0, -1))
    return block.cut(socket).cut(cq.Workplane().add(cone))


def wedge5() -> cq.Workplane:
    """A prism 3 thick whose section is a 5-degree wedge 40 long."""
    half = 40.0 * math.tan(math.radians(2.5))
    return cq.Workplane("XY").polyline([(0, 0), (40.0, half), (40.0, -half)]).close().extrude(3.0)


def wedge12_round() -> cq.Workplane:
    """A 12-degree wedge 30 long with a round back, 2 thick."""
    half = 30.0 * math.tan(math.radians(6.0))
    return (cq.Workplane("XY").moveTo(0, 0).lineTo(30.0, half).threePointArc((33.5, 0), (30.0, -half))
            .close().extrude(2.0))


def airfoil_sharp() -> cq.Workplane:
    """An airfoil of chord 40 (two splines meeting at its trailing edge at about 8 degrees), 20 long."""
    section = (cq.Workplane("XY").moveTo(40, 0)
               .spline([(25, -0.6), (10, -1.0), (2, -0.8), (0, 0)], includeCurrent=True)
               .spline([(2, 1.6), (10, 2.6), (25, 1.8), (40, 0)], includeCurrent=True).close())
    return section.extrude(20.0)


def vnotch() -> cq.Workplane:
    """A 50 x 40 x 3 plate with a V notch 26 deep and about 0.5 degrees wide cut into one side."""
    plate = cq.Workplane("XY").box(50.0, 40.0, 3.0).translate((25.0, 20.0, 0))
    open_ = math.tan(math.radians(3.0)) + 0.05
    notch = cq.Workplane("XY").polyline([(-1.0, 20.0 - open_), (25.0, 20.0), (-1.0, 20.0 + open_)]).close()
    return plate.cut(notch.extrude(10.0).translate((0, 0, -5.0)))


def _stadium(radius: float, length: float = 20.0, points: int = 120, height: float = 6.0) -> cq.Workplane:
    """The extrusion of a stadium outline (straight sides ``length`` long, round ends of ``radius``) drawn
    as one periodic spline through ``points`` of its points."""
    perimeter = 2 * length + 2 * math.pi * radius
    outline = []
    for k in range(points):
        s = perimeter * k / points
        if s < length:
            outline.append((-length / 2 + s, -radius))
        elif s < length + math.pi * radius:
            a = -math.pi / 2 + (s - length) / radius
            outline.append((length / 2 + radius * math.cos(a), radius * math.sin(a)))
        elif s < 2 * length + math.pi * radius:
            outline.append((length / 2 - (s - length - math.pi * radius), radius))
        else:
            a = math.pi / 2 + (s - 2 * length - math.pi * radius) / radius
            outline.append((-length / 2 + radius * math.cos(a), radius * math.sin(a)))
    return cq.Workplane("XY").spline(outline, periodic=True).close().extrude(height)


def stadium_03() -> cq.Workplane:
    """:func:`_stadium` with round ends of 0.3 (its caps are 0.6 wide)."""
    return _stadium(0.3)


def stadium_10() -> cq.Workplane:
    """:func:`_stadium` with round ends of 1."""
    return _stadium(1.0)


def rim_hole() -> cq.Workplane:
    """A disk of radius 10, 5 thick, with a hole of radius 4 touching its rim from inside: two cusps on each
    flat face (two tangent circles), whose tips the area fits cut finer than the refined edges."""
    return cq.Workplane().circle(10).extrude(5).cut(cq.Workplane().center(6, 0).circle(4).extrude(5))


MODELS: dict[str, Callable[[], cq.Workplane]] = {
    "square_nut": square_nut, "hex_socket_cs": hex_socket_cs, "wedge5": wedge5, "wedge12_round": wedge12_round,
    "airfoil_sharp": airfoil_sharp, "vnotch": vnotch, "stadium_03": stadium_03, "stadium_10": stadium_10,
    "rim_hole": rim_hole,
}


def write_model(name: str, folder: Path) -> Path:
    """Write model ``name`` as ``folder/<name>.step``; returns the path."""
    path = Path(folder) / f"{name}.step"
    cq.exporters.export(MODELS[name](), str(path), exportType="STEP")
    return path


if __name__ == "__main__":
    from hard_models import write_all

    sys.exit(write_all(sys.argv[1:], list(MODELS), write_model, "narrow-corner model", "corners"))
