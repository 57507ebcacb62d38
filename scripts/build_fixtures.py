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
- ``misread/dimpled_ball.step``: a sphere with 22 dimples, one sphere face with 22 holes, that OCCT's own STEP
  reader misreads: its shape healing takes holes for faces of their own and drops the rest of the face
  (23 faces read as 43, one solid as 21; the loader warns). It lies in a folder of its own, out of the
  benchmarks that take every fixture.
"""

from __future__ import annotations

import math
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


def dimpled_ball(count: int = 22, radius: float = 21.35) -> cq.Shape:
    """A ball with ``count`` spherical dimples 0.5 deep on a Fibonacci lattice (each cutting sphere's
    axis radial, so its seam stays clear of the dimple's rim)."""
    ball = cq.Solid.makeSphere(radius, angleDegrees1=-90)
    golden = math.pi * (3 - math.sqrt(5))
    for i in range(count):
        z = 1 - 2 * (i + 0.5) / count
        at = cq.Vector(math.sqrt(1 - z * z) * math.cos(golden * i), math.sqrt(1 - z * z) * math.sin(golden * i), z)
        ball = ball.cut(cq.Solid.makeSphere(3.0, at * (radius + 2.5), at, angleDegrees1=-90))
    return ball


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
        "misread/dimpled_ball": dimpled_ball(),
    }


def main() -> int:
    OUT.mkdir(exist_ok=True)
    for name, obj in shapes().items():
        path = OUT / f"{name}.step"
        path.parent.mkdir(exist_ok=True)
        cq.exporters.export(obj, str(path), exportType="STEP")
        print(f"{path.relative_to(OUT.parent)}: {path.stat().st_size} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
