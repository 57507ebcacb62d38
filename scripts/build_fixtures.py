"""Build the small STEP fixtures in ``fixtures/`` with cadquery (run from the repository root).

    python scripts/build_fixtures.py

Each file exercises one kind of topology the OCCT layer must handle:

- ``bracket.step``: an L bracket with fillets and holes (the README's bundled example).
- ``cylinder.step``: full-circle edges and a seam edge.
- ``sphere.step``: degenerate edges at the poles and a seam.
- ``spline_prism.step``: a spline profile extruded: B-spline edges.
- ``two_solids.step``: a two-solid compound (an assembly of a box and a cylinder).
- ``open_face.step``: an open shell: a single B-spline face.
- ``helix_wire.step``: loose edges: a helix wire with no faces.
"""

from __future__ import annotations

import sys
from pathlib import Path

import cadquery as cq

OUT = Path(__file__).resolve().parents[1] / "fixtures"


def bracket() -> cq.Workplane:
    """An L bracket, 60 x 40 base, 30 high flange, filleted, with two base holes and a flange hole."""
    base = cq.Workplane("XY").box(60, 40, 6, centered=(True, True, False))
    flange = cq.Workplane("XY").box(6, 40, 36, centered=(False, True, False)).translate((-30, 0, 0))
    body = base.union(flange).edges("|Y and >Z").fillet(2.0)
    body = body.edges("|Y").edges(cq.selectors.NearestToPointSelector((-24, 0, 6))).fillet(4.0)
    body = body.faces(">Z[-2]").workplane().pushPoints([(10, 10), (10, -10)]).hole(6.0)
    return body.faces("<X").workplane(centerOption="CenterOfBoundBox").center(0, 6).hole(8.0)


def shapes() -> dict[str, cq.Shape | cq.Workplane]:
    prism = (cq.Workplane("XY").spline([(15, -6), (30, 0)], includeCurrent=True).lineTo(30, 15)
             .spline([(15, 22), (0, 15)], includeCurrent=True).close().extrude(5.0))
    compound = cq.Compound.makeCompound([cq.Solid.makeBox(10, 10, 10),
                                         cq.Solid.makeCylinder(4, 12, cq.Vector(20, 5, 0))])
    grid = [[cq.Vector(x * 10.0, y * 10.0, 3.0 * ((x - 1.5) ** 2 - (y - 1.5) ** 2) / 2.25)
             for y in range(4)] for x in range(4)]
    face = cq.Face.makeSplineApprox(grid)
    helix = cq.Wire.makeHelix(pitch=4.0, height=12.0, radius=5.0)
    return {
        "bracket": bracket(),
        "cylinder": cq.Workplane("XY").cylinder(20.0, 8.0),
        "sphere": cq.Workplane("XY").sphere(10.0),
        "spline_prism": prism,
        "two_solids": compound,
        "open_face": face,
        "helix_wire": helix,
    }


def main() -> int:
    OUT.mkdir(exist_ok=True)
    for name, obj in shapes().items():
        path = OUT / f"{name}.step"
        cq.exporters.export(obj, str(path), exportType="STEP")
        print(f"{path.relative_to(OUT.parent)}: {path.stat().st_size} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
