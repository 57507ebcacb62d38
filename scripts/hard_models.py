"""Hard models for ``cadedge mesh``: the shapes that broke it, built with cadquery and OCP.

Helical sweeps, revolved and lofted splines, thin and sliver faces, tiny edges beside long ones,
multi-body assemblies (one part placed twice), a hole through a fillet, a B-spline cage, loose
tolerances, free edges, seams and degenerate edges, and an AP242 STEP written with PMI (a dimension and
annotation curves) through OCCT's XDE writer (``STEPCAFControl_Writer``). A second set, kinds the first
one lacks: a threaded bolt (helical thread, build123d), fillets and chamfers on a boolean of four
primitives, a drafted and shelled box, a non-planar sweep, a sphere-cylinder-cone union with tangent
seams, a knurled cylinder (110 faces), a plate with a sliver slot and a tiny hole, an XDE assembly
with one part instanced three times, a faceted solid (an STL mesh sewn into 228 planar faces) and a
tube swept along a polyline with round bends. A third set: a non-manifold general fuse (inner faces
shared by two solids), a STEP sewn across real gaps between its faces, disjoint bodies with a free
polyline and tolerances wider than a slot (OCCT BREP: STEP keeps no per-entity tolerances) and an IGES
file of unsewn trimmed surfaces. A fourth: a thickened wavy plate (offset surfaces), a twisted blade
with a sharp trailing edge (curvature radii from 27 mm to 0.1 mm on one face) and a propeller (three
lofted blades with sharp edges on a hub), and two wings whose sections' splines hook back past the
trailing edge to the seam, one of them 0.12 mm thick. A fifth, parts drawn every day and scale: a gear, cadquery's
bottle, a cut torus, an ellipsoid, a filleted cone on a cylinder, a mug, a filleted pocket box, a
0.2 mm-walled shell, a thin washer, a sphere with a 0.3 mm hole, and the bracket fixture scaled by
1e-3 and 1e3 and moved far from the origin. A sixth: two tees whose run cylinder has its seam through
the point where the branch touches it (a tangential inlet, an equal pipe tee): two vertices of the run's
face at one point; and a sphere and a revolved spline cut to 270 degrees (a face spanning more than half a
turn between two poles). A seventh: a flat coil (a rectangle swept along a helix), whose helicoidal bands'
boundary slivers cancel. An eighth: a key blade as an Alias export (every face a B-spline
surface, its top wall's section through square notches). A ninth: a fillet dying out along an edge, one
B-spline strip whose parameters stretch about 200 times more along it than across. A tenth, features
not tried before: text embossed on a plate and cut into a cylinder, variable-radius fillets, a vertex
blend of three fillets of unequal radii, a conical spring, a plate with 240 chamfered holes and a sphere
grazed by a hole. An eleventh: curved faces with many holes (a ball with 150 dimples, written as BREP since
OCCT's STEP reader misreads it, and a tube with 96 holes), a torus elbow with a branch, a square-to-circle
loft, an oblique extrusion, a B-spline face whose parameter speed varies 100 times and a shelled vase
with a window. A twelfth: a tapered pipe thread, a torus knot piped as one face, a revolved sine profile
(solid, and shelled: its inner face an offset folding on itself), two cylinders crossing at 8 degrees,
a crowned hex nut, a block with every edge filleted 0.05, a plate with 0.1 mm ribs, a spherical cap with
36 slots, four fillets meeting at a pyramid's apex, a diamond knurl, a bent sheet with reliefs, a
bevel gear whose teeth meet the blank at cusps, and a shelled multi-section sweep.

    python scripts/hard_models.py OUTDIR            # writes OUTDIR/<name>.step (.brep, .igs) for every model

``MODELS`` maps each name to a builder returning an OCP ``TopoDS_Shape``; ``write_model(name, folder)``
writes one STEP file (``XDE_WRITERS`` through XDE, the others through cadquery's exporter).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Callable

import cadquery as cq


def spring() -> object:
    """A circle swept along a helix (4 turns): helical B-spline faces with a seam along the sweep."""
    path = cq.Wire.makeHelix(pitch=2.0, height=8.0, radius=3.0)
    return cq.Workplane("XZ").center(3.0, 0.0).circle(0.5).sweep(cq.Workplane().add(path), isFrenet=True).val().wrapped


def flat_coil(turns: int = 4) -> object:
    """A 3 x 2 mm rectangle swept ``turns`` turns along a helix of radius 15 and pitch 6: two helicoidal
    bands 3 mm wide, whose outer helix's chords cut them short and inner one's add to them (their slivers
    cancel), and two helical bands 2 mm wide."""
    path = cq.Wire.makeHelix(pitch=6.0, height=6.0 * turns, radius=15.0)
    section = cq.Workplane("XZ").center(15.0, 0.0).rect(3.0, 2.0)
    return section.sweep(cq.Workplane().add(path), isFrenet=True).val().wrapped


def revolved_spline() -> object:
    """A spline profile revolved a full turn: a B-spline surface of revolution with a seam and poles."""
    prof = (cq.Workplane("XZ").moveTo(0, 0).lineTo(1.0, 0)
            .spline([(2.0, 1.0), (1.2, 2.0), (2.6, 3.2), (1.0, 4.0)], includeCurrent=True).lineTo(0, 4.0).close())
    return prof.revolve(360, (0, 0, 0), (0, 1, 0)).val().wrapped


def lofted_spline() -> object:
    """A loft through a circle, a rotated ellipse and a closed spline."""
    w1 = cq.Wire.makeCircle(2.0, cq.Vector(0, 0, 0), cq.Vector(0, 0, 1))
    w2 = cq.Wire.assembleEdges([cq.Edge.makeEllipse(3.0, 1.2, cq.Vector(0, 0, 3), cq.Vector(0.2, 0, 1))])
    pts = [(1.5 * math.cos(t) * (1 + 0.3 * math.cos(3 * t)), 1.5 * math.sin(t) * (1 + 0.3 * math.cos(3 * t)), 6.0)
           for t in [2 * math.pi * k / 9 for k in range(9)]]
    w3 = cq.Wire.assembleEdges([cq.Edge.makeSpline([cq.Vector(*p) for p in pts], periodic=True)])
    return cq.Solid.makeLoft([w1, w2, w3], ruled=False).wrapped


def twisted_blade() -> object:
    """A blade lofted through airfoil-like splines twisted by 60 degrees."""
    wires = []
    for k in range(4):
        a, z = math.radians(20.0 * k), 3.0 * k
        base = [(0, 0), (2, 1.5), (5, 1.8), (8, 0.6), (10, 0), (8, -0.3), (5, -0.6), (2, -0.6)]
        rot = [cq.Vector(x * math.cos(a) - y * math.sin(a), x * math.sin(a) + y * math.cos(a), z) for x, y in base]
        wires.append(cq.Wire.assembleEdges([cq.Edge.makeSpline(rot, periodic=True)]))
    return cq.Solid.makeLoft(wires, ruled=False).wrapped


def _wing(scale: float) -> object:
    """A wing lofted from a 20 mm NACA 0012 section to an 8 mm NACA 0010 one 40 mm on, its thickness
    times ``scale``: each section a periodic spline through ten points starting at the trailing edge."""
    def section(chord: float, thickness: float, shift: float, z: float) -> cq.Wire:
        pts = []
        for k, x in enumerate((1.0, 0.8, 0.5, 0.25, 0.1, 0.0, 0.1, 0.25, 0.5, 0.8)):
            y = 5 * thickness * (0.2969 * math.sqrt(x) - 0.126 * x - 0.3516 * x**2 + 0.2843 * x**3 - 0.1036 * x**4)
            pts.append(cq.Vector(shift + chord * x, scale * chord * (y if k < 6 else -y), z))
        return cq.Wire.assembleEdges([cq.Edge.makeSpline(pts, periodic=True)])

    return cq.Solid.makeLoft([section(20.0, 0.12, 0.0, 0.0), section(8.0, 0.10, 6.0, 40.0)], ruled=False).wrapped


def hooked_wing() -> object:
    """A wing whose sections' splines overshoot the trailing edge by 0.3 mm and hook back to the seam (a
    sharp ridge beside the lofted face's seam)."""
    return _wing(1.0)


def razor_wing() -> object:
    """hooked_wing 20 times thinner (0.12 mm over its 20 mm chord): its lofted face folds over a ridge at
    both edges and its end caps are strips 0.03-0.1 mm wide bounded by one closed spline."""
    return _wing(0.05)


def thin_plate() -> object:
    """A 40 x 40 x 0.02 plate with a hole: side faces 2000 times longer than wide."""
    return cq.Workplane().box(40, 40, 0.02).faces(">Z").workplane().hole(6).val().wrapped


def sliver_faces() -> object:
    """Two boxes fused, the second turned by 0.3 degrees: long sliver faces where they nearly coincide."""
    a = cq.Workplane().box(10, 10, 10)
    b = cq.Workplane().box(10, 10, 10).rotate((0, 0, 0), (0, 0, 1), 0.3).translate((0.0, 0.0, 5.0))
    return a.union(b).val().wrapped


def tiny_edges() -> object:
    """A 100 x 20 x 5 bar with a 0.05 notch and a 0.02 chamfer: tiny edges beside 100-long ones."""
    bar = cq.Workplane().box(100, 20, 5)
    notch = cq.Workplane().box(0.05, 0.05, 5).translate((10, 10, 0))
    return bar.cut(notch).edges("|X and >Z and >Y").chamfer(0.02).val().wrapped


def hole_through_fillet() -> object:
    """A block with a 4 mm fillet and a slanted hole drilled through the fillet."""
    block = cq.Workplane().box(20, 20, 10).edges("|Y and >Z and >X").fillet(4.0)
    drill = cq.Solid.makeCylinder(1.0, 30, cq.Vector(-2, 0, -8), cq.Vector(1, 0, 1.2))
    return block.cut(cq.Workplane().add(drill)).val().wrapped


def bspline_cage() -> object:
    """An open cage of 4 B-spline faces (a lofted tube through spline rectangles, no caps)."""
    def rect(z: float, s: float) -> cq.Wire:
        c = [cq.Vector(-s, -s, z), cq.Vector(s, -s, z), cq.Vector(s, s, z), cq.Vector(-s, s, z)]
        mids = [cq.Vector(0, -1.3 * s, z), cq.Vector(1.3 * s, 0, z), cq.Vector(0, 1.3 * s, z),
                cq.Vector(-1.3 * s, 0, z)]
        return cq.Wire.assembleEdges([cq.Edge.makeSpline([c[i], mids[i], c[(i + 1) % 4]]) for i in range(4)])

    loft = cq.Solid.makeLoft([rect(0, 2.0), rect(3, 1.0), rect(6, 2.5)], ruled=False)
    sides = [f for f in loft.Faces() if f.geomType() != "PLANE"]
    return cq.Shell.makeShell(sides).wrapped


def wavy_plate() -> object:
    """A B-spline surface with waves, trimmed to a rectangle, plus its border as free edges."""
    pts = [[cq.Vector(x, y, 0.6 * math.sin(x) * math.cos(0.7 * y)) for y in range(0, 11)] for x in range(0, 11)]
    return cq.Face.makeSplineApprox(pts).wrapped


def thick_wavy_plate() -> object:
    """A wavy B-spline surface thickened by 1.5: its far side is an offset surface, where OCCT's adaptive
    area integration is 0.4% off (the fixed-order one is right there)."""
    pts = [[cq.Vector(5.0 * i, 5.0 * j, 2.0 * math.sin(0.9 * i) * math.cos(0.7 * j)) for j in range(9)] for i in range(9)]
    return cq.Face.makeSplineApprox(pts).thicken(1.5).wrapped


def sharp_blade() -> object:
    """A blade lofted through five periodic splines with a sharp trailing edge, twisted by 80 degrees: its
    curvature spans four orders of magnitude across a face (radius 27 mm mid-chord, 0.1 mm at the edge)."""
    base = [(-12, 0), (-4, 3.5), (6, 2.5), (14, 0), (6, -0.8), (-4, -1.2)]
    wires = []
    for k in range(5):
        a, z = math.radians(20.0 * k), 15.0 * k
        rot = [cq.Vector(x * math.cos(a) - y * math.sin(a), x * math.sin(a) + y * math.cos(a), z) for x, y in base]
        wires.append(cq.Wire.assembleEdges([cq.Edge.makeSpline(rot, periodic=True)]))
    return cq.Solid.makeLoft(wires, ruled=False).wrapped


def propeller() -> object:
    """A hub with three blades lofted from a 5 x 0.8 ellipse to a 2.4 x 0.3 one turned by 50 degrees: the
    blades' edges are sharp (radius 0.02 mm at the tip) along 14 mm seams, and each blade face hangs gmsh
    at its curvature sizes (gmsh alone did not finish within 300 s at 12 triangles per circle)."""
    hub = cq.Workplane("XY").circle(4).extrude(6)
    blade = (cq.Workplane("YZ").workplane(offset=3).ellipse(2.5, 0.4)
             .workplane(offset=14).transformed(rotate=(0, 0, 50)).ellipse(1.2, 0.15).loft())
    for k in range(3):
        hub = hub.union(blade.translate((0, 0, 3)).rotate((0, 0, 0), (0, 0, 1), 120 * k))
    return hub.val().wrapped


def gear() -> object:
    """A toothed wheel: an 18-tooth star extruded 8 mm, its 36 vertical edges filleted 0.8 mm, an 8 mm
    bore."""
    pts = [((20 if i % 2 == 0 else 17) * math.cos(math.pi * i / 18), (20 if i % 2 == 0 else 17)
            * math.sin(math.pi * i / 18)) for i in range(36)]
    return (cq.Workplane().polyline(pts).close().extrude(8).edges("|Z").fillet(0.8)
            .faces(">Z").workplane().hole(8).val().wrapped)


def bottle() -> object:
    """cadquery's classic bottle: arcs and lines extruded, a neck, shelled to 0.3 mm."""
    length, width, thick = 20.0, 6.0, 3.0
    body = (cq.Workplane("XY").center(-length / 2.0, 0).vLine(width / 2.0)
            .threePointArc((length / 2.0, width / 2.0 + thick), (length, width / 2.0)).vLine(-width / 2.0)
            .mirrorX().extrude(30.0, True))
    body = body.faces(">Z").workplane(centerOption="CenterOfMass").circle(3.0).extrude(2.0, True)
    return body.faces(">Z").shell(0.3).val().wrapped


def cut_torus() -> object:
    """A torus (radii 10 and 3) with a quarter cut away by a box."""
    return cq.Workplane().add(cq.Solid.makeTorus(10, 3)).cut(
        cq.Workplane().box(30, 30, 30).translate((15, 15, 0))).val().wrapped


def ellipsoid() -> object:
    """A sphere of radius 5 scaled 3 x 1.5 x 1 (OCCT turns it into B-spline faces)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_GTransform
    from OCP.gp import gp_GTrsf

    scale = gp_GTrsf()
    for i, f in enumerate((3.0, 1.5, 1.0), 1):
        scale.SetValue(i, i, f)
    return BRepBuilderAPI_GTransform(cq.Solid.makeSphere(5).wrapped, scale, True).Shape()


def cone_apex() -> object:
    """A cone to a point on a cylinder, their circular edges filleted 1 mm."""
    return (cq.Workplane().add(cq.Solid.makeCone(6, 0, 12)).union(cq.Workplane().circle(6).extrude(-5))
            .edges("%CIRCLE").fillet(1.0).val().wrapped)


def mug() -> object:
    """A revolved cup with an elliptical handle swept along a spline."""
    body = (cq.Workplane("XZ").polyline([(0, 0), (4, 0), (4.5, 9), (4.2, 9), (3.7, 0.4), (0, 0.4)]).close()
            .revolve(360, (0, 0, 0), (0, 1, 0)))
    path = cq.Workplane("XZ").spline([(4.2, 7.5), (7, 6), (7, 3), (4.1, 1.5)], includeCurrent=False)
    handle = cq.Workplane("YZ").workplane(offset=4.2).center(0, 7.5).ellipse(0.6, 0.35).sweep(path)
    return body.union(handle).val().wrapped


def pocket_box() -> object:
    """A box with filleted vertical edges and top, chamfered bottom and a filleted rectangular pocket."""
    return (cq.Workplane().box(20, 14, 8).edges("|Z").fillet(3).faces(">Z").edges().fillet(1.5)
            .faces("<Z").chamfer(1.0).faces(">Z").workplane().rect(10, 6).cutBlind(-4)
            .faces(">Z[-2]").edges().fillet(0.5).val().wrapped)


def thin_shell() -> object:
    """A 100 x 60 x 30 box with 5 mm fillets, shelled inwards to a 0.2 mm wall."""
    return cq.Workplane().box(100, 60, 30).edges().fillet(5).shell(-0.2).val().wrapped


def washer_thin() -> object:
    """A ring 100 mm across, 0.5 mm wide and 0.5 mm thick."""
    return cq.Workplane().circle(50).circle(49.5).extrude(0.5).val().wrapped


def sphere_pinhole() -> object:
    """A sphere of radius 20 drilled through by a 0.3 mm hole."""
    return cq.Workplane().sphere(20).cut(cq.Workplane("YZ").circle(0.15).extrude(30, both=True)).val().wrapped


def _bracket() -> cq.Shape:
    return cq.importers.importStep(str(Path(__file__).resolve().parents[1] / "fixtures" / "bracket.step")).val()


def bracket_micro() -> object:
    """The bracket fixture scaled by 1e-3 (a part drawn in metres)."""
    return _bracket().scale(1e-3).wrapped


def bracket_huge() -> object:
    """The bracket fixture scaled by 1e3."""
    return _bracket().scale(1e3).wrapped


def bracket_far() -> object:
    """The bracket fixture moved 2.3e5 from the origin."""
    return _bracket().translate(cq.Vector(1e5, -2e5, 3e4)).wrapped


def loose_tolerance() -> object:
    """A filleted box whose edge and vertex tolerances are forced up to 0.05 (a loosely sewn file)."""
    from OCP.ShapeFix import ShapeFix_ShapeTolerance
    from OCP.TopAbs import TopAbs_SHAPE

    shape = cq.Workplane().box(10, 8, 6).edges("|Z").fillet(1.5).faces(">Z").hole(3).val().wrapped
    ShapeFix_ShapeTolerance().SetTolerance(shape, 0.05, TopAbs_SHAPE)
    return shape


def free_edges() -> object:
    """An open box (one face removed) beside a loose circle and a loose line: free and lone edges."""
    box = cq.Workplane().box(4, 4, 4).faces(">Z").shell(-0.5).val()
    open_shell = cq.Shell.makeShell([f for f in box.Faces() if f.Center().z < 1.99 or f.geomType() != "PLANE"])
    circle = cq.Edge.makeCircle(1.0, cq.Vector(8, 0, 0))
    line = cq.Edge.makeLine(cq.Vector(8, 3, 0), cq.Vector(12, 3, 0))
    return cq.Compound.makeCompound([open_shell, circle, line]).wrapped


def seams_and_poles() -> object:
    """A sphere, a cone with its apex, a torus and a half-revolved profile: seams and degenerate edges."""
    return cq.Compound.makeCompound([
        cq.Solid.makeSphere(2.0, angleDegrees1=-90, angleDegrees2=90),
        cq.Solid.makeCone(1.5, 0.0, 3.0, pnt=cq.Vector(6, 0, 0)),
        cq.Solid.makeTorus(3.0, 0.7, pnt=cq.Vector(0, 9, 0)),
        cq.Workplane("XZ").moveTo(0, 0).lineTo(1, 0).threePointArc((1.5, 1), (1, 2)).lineTo(0, 2).close()
          .revolve(180, (0, 0, 0), (0, 1, 0)).translate((12, 0, 0)).val(),
    ]).wrapped


def assembly() -> object:
    """Five touching and overlapping bodies, one of them the same solid placed twice (shared TShape)."""
    bolt = cq.Workplane().cylinder(6, 0.8).val()
    loc1 = cq.Location(cq.Vector(2, 0, 3))
    loc2 = cq.Location(cq.Vector(-2, 0, 3))
    return cq.Compound.makeCompound([
        cq.Workplane().box(8, 4, 2).val(),
        bolt.moved(loc1), bolt.moved(loc2),
        cq.Workplane().sphere(1.2).translate((0, 0, 1.5)).val(),
        cq.Workplane().box(2, 2, 2).translate((4.5, 0, 0)).val(),
    ]).wrapped


def threaded_bolt() -> object:
    """A bolt with a helical thread (a triangle swept along a helix, build123d) fused to its core and a head."""
    import build123d as bd

    pitch, r_core, depth, length = 1.0, 2.5, 0.55, 6.0
    x0 = r_core - 0.05  # the thread root sits inside the core: the fusion cuts it along a helical seam
    helix = bd.Helix(pitch=pitch, height=length, radius=x0)
    profile = bd.make_face(bd.Polyline((x0, 0, -0.4 * pitch), (x0 + depth, 0, 0), (x0, 0, 0.4 * pitch), close=True))
    thread = bd.sweep(profile, path=helix, is_frenet=True)
    bottom = (bd.Align.CENTER, bd.Align.CENTER, bd.Align.MIN)
    core = bd.Cylinder(r_core, length + 2, align=bottom).moved(bd.Location((0, 0, -1)))
    head = bd.Cylinder(4.0, 2.0, align=bottom).moved(bd.Location((0, 0, -3)))
    return core.fuse(thread).fuse(head).wrapped


def filleted_boolean() -> object:
    """A box, a boss, a rib and a ball fused, then vertical edges filleted, the base chamfered, a hole drilled."""
    body = (cq.Workplane().box(30, 20, 8).union(cq.Workplane().cylinder(12, 6).translate((8, 0, 6)))
            .union(cq.Workplane().box(4, 18, 10).translate((-8, 0, 5)))
            .union(cq.Workplane().sphere(4).translate((-8, 0, 10))))
    return body.edges("|Z").fillet(1.0).faces("<Z").chamfer(0.8).faces(">Z").workplane().hole(3.0).val().wrapped


def shelled_drafted() -> object:
    """A box extruded with a 6-degree draft, its slanted corners filleted, shelled open at the top."""
    box = cq.Workplane().rect(20, 14).extrude(10, taper=6).edges("not(|X or |Y)").fillet(2.0)
    return box.faces(">Z").shell(-0.8).val().wrapped


def swept_nonplanar() -> object:
    """An ellipse swept along a non-planar 3-D spline: B-spline faces twisting along the path."""
    pts = [(0, 0, 0), (5, 3, 2), (10, -2, 6), (15, 1, 4), (20, 0, 10)]
    path = cq.Wire.assembleEdges([cq.Edge.makeSpline([cq.Vector(*p) for p in pts])])
    return cq.Workplane("YZ").ellipse(1.5, 0.8).sweep(cq.Workplane().add(path), transition="round").val().wrapped


def tangent_union() -> object:
    """A sphere, a cylinder of the same radius and a cone on it fused: tangent seams between the pieces."""
    r = 3.0
    cyl = cq.Solid.makeCylinder(r, 10, cq.Vector(0, 0, 0), cq.Vector(0, 0, 1))
    ball = cq.Solid.makeSphere(r, cq.Vector(0, 0, 0))
    cone = cq.Solid.makeCone(r, 0.0, 6, cq.Vector(0, 0, 10), cq.Vector(0, 0, 1))
    return cq.Workplane().add(cyl).union(cq.Workplane().add(ball)).union(cq.Workplane().add(cone)).val().wrapped


def knurled() -> object:
    """A cylinder with 36 axial V-grooves cut around it (a knurl): 110 faces, many of them long and thin."""
    cut = None
    for k in range(36):
        groove = (cq.Workplane().box(0.6, 0.6, 14).rotate((0, 0, 0), (0, 0, 1), 45).translate((6, 0, 0))
                  .rotate((0, 0, 0), (0, 0, 1), 10.0 * k))
        cut = groove if cut is None else cut.union(groove)
    return cq.Workplane().cylinder(12, 6).cut(cut).val().wrapped


def sliver_hole() -> object:
    """A plate with a 0.004-wide slot and a 0.02-diameter pin hole through it: sliver and tiny hole faces."""
    plate = cq.Workplane().box(20, 20, 2)
    slot = cq.Workplane().box(8, 0.004, 4).translate((2, 3, 0))
    pin = cq.Workplane().cylinder(4, 0.01).translate((-5, -5, 0))
    return plate.cut(slot).cut(pin).val().wrapped


def star_prism() -> object:
    """A five-pointed star 6 mm high: a periodic spline through 100 points, its radius linear in the angle
    between 20 at the tips and 8 at the valleys, so its side folds at all ten (faces of linear extrusion
    laid flat along their folds' lines)."""
    points = []
    for i in range(100):
        t = 2.0 * math.pi * i / 100
        r = 20.0 - 12.0 * (1.0 - abs(1.0 - 2.0 * (i % 20) / 20))
        points.append((r * math.cos(t), r * math.sin(t)))
    return cq.Workplane("XY").spline(points, periodic=True).close().extrude(6.0).val().wrapped


def notched_block() -> object:
    """A 20 x 10 block 8 mm deep whose top is a spline through a 3.5 mm deep V notch 1 mm wide: the one
    fold of an open section (its top face, an extrusion, was 1.3e-2 short at ALD 1e-3 when its triangles
    spanned the notch)."""
    top = [(10, 5), (6, 5.5), (2, 5.2), (0.5, 4.0), (0, 1.5), (-0.5, 4.0), (-2, 5.2), (-6, 5.5), (-10, 5)]
    wire = cq.Workplane("XY").moveTo(-10, -5).lineTo(10, -5).lineTo(10, 5).spline(top[1:], includeCurrent=True)
    return wire.close().extrude(8.0).val().wrapped


def tangent_inlet_tee() -> object:
    """A 10 mm radius run along x and a 4 mm radius branch up z, its axis 6 mm off the run's, so that
    its side touches the run's wall at (0, 10, 0): the run's seam passes there, and the run's face has
    the seam's vertex and the intersection loop's vertex at that one point."""
    run = cq.Workplane("YZ").circle(10).extrude(30, both=True)
    return run.union(cq.Workplane("XY").center(0, 6).circle(4).extrude(25)).val().wrapped


def pipe_tee_equal() -> object:
    """Two 10 mm radius pipes (bored 8 mm) crossing at right angles: the saddle curves of equal radii
    meet at two tangent points, one of them on the run's seam (two vertices of its face at one point)."""
    run = cq.Workplane("YZ").circle(10).extrude(30, both=True)
    body = run.union(cq.Workplane("XY").circle(10).extrude(30))
    body = body.cut(cq.Workplane("YZ").circle(8).extrude(31, both=True))
    return body.cut(cq.Workplane("XY").circle(8).extrude(31)).val().wrapped


def sphere_sector() -> object:
    """A 50 mm sphere cut to 270 degrees about its axis: one spherical face between two meridians that meet
    at both poles, which Frontal-Delaunay meshed on the other side of its boundary (the missing quarter)."""
    return cq.Solid.makeSphere(50, angleDegrees1=-90, angleDegrees2=90, angleDegrees3=270).wrapped


def revolved_sector() -> object:
    """A spline profile whose ends lie on the axis, revolved 270 degrees: a surface of revolution between
    two poles spanning more than half a turn (the missing quarter meshed at ALD 1e-3, not at 1e-2)."""
    profile = cq.Workplane("XZ").spline([(0, -50), (40, -20), (45, 20), (0, 50)], tangents=[(1, 0), (-1, 0)],
                                        includeCurrent=False).close()
    return profile.revolve(270, (0, 0, 0), (0, 1, 0)).val().wrapped


def vanishing_fillet() -> object:
    """A fillet dying out along a 162 mm edge, as a DesignModeler race car nose has one: a rational B-spline
    strip whose section goes from a quarter circle of radius 5 to a straight line of length 0 (width as
    ``(1 - s)**1.5``, bulge as ``(1 - s)**3``), its length over 0.16 of ``u`` and its width over all of
    ``v``, so its parameters stretch about 200 times more one way than the other; its narrow end is a
    degenerate edge. Frontal-Delaunay left it a Schwarz lantern, 25% over its area at 1e-2."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.Geom import Geom_BSplineSurface
    from OCP.gp import gp_Pnt

    from cadedge.occt.compat import (TColgp_Array2OfPnt, TColStd_Array1OfInteger, TColStd_Array1OfReal,
                                     TColStd_Array2OfReal)

    rows = 8
    poles, weights = TColgp_Array2OfPnt(1, rows, 1, 3), TColStd_Array2OfReal(1, rows, 1, 3)
    for i in range(rows):
        s = i / (rows - 1)
        r, bulge = 5.0 * (1 - s) ** 1.5, 0.5 + 0.5 * (1 - s) ** 3
        for j, (x, y, w) in enumerate([(r, 0.0, 1.0), (r * bulge, r * bulge, math.sqrt(0.5)), (0.0, r, 1.0)]):
            poles.SetValue(i + 1, j + 1, gp_Pnt(x, y, 162.0 * s))
            weights.SetValue(i + 1, j + 1, w)
    u_knots, u_mults = TColStd_Array1OfReal(1, rows - 2), TColStd_Array1OfInteger(1, rows - 2)
    for k in range(rows - 2):
        u_knots.SetValue(k + 1, 0.16 * k / (rows - 3))
        u_mults.SetValue(k + 1, 4 if k in (0, rows - 3) else 1)
    v_knots, v_mults = TColStd_Array1OfReal(1, 2), TColStd_Array1OfInteger(1, 2)
    for k in (1, 2):
        v_knots.SetValue(k, float(k - 1))
        v_mults.SetValue(k, 3)
    surface = Geom_BSplineSurface(poles, weights, u_knots, v_knots, u_mults, v_mults, 3, 2)
    return BRepBuilderAPI_MakeFace(surface, 1e-7).Face()


def text_plate() -> object:
    """Serif text ("Rg&@%8 Qx", 10 mm, DejaVu Serif or the system's fallback) embossed 1.2 mm on an
    80 x 24 x 4 plate with filleted corners: glyph outlines of short B-spline edges with sharp serifs."""
    import build123d as bd

    with bd.BuildPart() as part:
        bd.Box(80, 24, 4)
        bd.fillet(part.edges().filter_by(bd.Axis.Z), 3)
        with bd.BuildSketch(bd.Plane.XY.offset(2)):
            bd.Text("Rg&@%8 Qx", font_size=10, font="DejaVu Serif")
        bd.extrude(amount=1.2)
    return part.part.wrapped


def text_cylinder() -> object:
    """Bold text ("CAD 3S", 9 mm) cut 0.7 mm deep into a cylinder of radius 15, radially: the glyphs'
    side faces meet the cylinder in B-spline curves, their floors a cylinder of radius 14.3."""
    import build123d as bd

    with bd.BuildSketch(bd.Plane.XZ) as text:
        bd.Text("CAD 3S", font_size=9, font="DejaVu Sans", font_style=bd.FontStyle.BOLD)
    glyphs = bd.extrude(text.sketch, amount=20, both=True)
    return (bd.Cylinder(15, 40) - (glyphs & bd.Cylinder(16, 40)) + bd.Cylinder(14.3, 40)).wrapped


def variable_fillet() -> object:
    """A 40 x 30 x 20 box whose four vertical edges are filleted with radii running from 1-4 mm at the
    bottom to 6-3 mm at the top (OCCT's evolving fillets: B-spline faces)."""
    import build123d as bd
    from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet

    box = bd.Box(40, 30, 20)
    fillet = BRepFilletAPI_MakeFillet(box.wrapped)
    for i, edge in enumerate(box.edges().filter_by(bd.Axis.Z)):
        fillet.Add(1.0 + i, 6.0 - i, edge.wrapped)
    fillet.Build()
    return fillet.Shape()


def vertex_blend() -> object:
    """A 30 mm cube whose three edges at one corner are filleted 2, 5 and 9 mm: the corner closed by a
    vertex blend between fillets of unequal radii."""
    import build123d as bd
    from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet

    cube = bd.Box(30, 30, 30)
    fillet = BRepFilletAPI_MakeFillet(cube.wrapped)
    corner = [e for e in cube.edges() if sum(abs(c - 15) < 1e-6 for c in tuple(e.center())) == 2]
    for radius, edge in zip((2.0, 5.0, 9.0), corner):
        fillet.Add(radius, edge.wrapped)
    fillet.Build()
    return fillet.Shape()


def conical_spring() -> object:
    """A 0.8 mm circle swept along a conical helix (radius 12, pitch 5, 30 high, narrowing at 12 degrees):
    one B-spline face 500 mm long round a tube 5 mm round, with its seam along the sweep."""
    import build123d as bd

    helix = bd.Helix(pitch=5, height=30, radius=12, cone_angle=-12)
    section = bd.Plane(origin=helix @ 0, z_dir=helix % 0) * bd.Circle(0.8)
    return bd.sweep(section, path=helix, is_frenet=True).wrapped


def perforated_plate() -> object:
    """A 100 x 44 x 2 plate with 24 x 10 holes of 1.2 mm on a 4 mm pitch, their top rims chamfered 0.2:
    486 faces, 240 narrow cones among them."""
    import build123d as bd

    with bd.BuildPart() as part:
        bd.Box(100, 44, 2)
        with bd.GridLocations(4, 4, 24, 10):
            bd.Hole(0.6)
        bd.chamfer(part.edges().filter_by(bd.GeomType.CIRCLE).group_by(bd.Axis.Z)[-1], 0.2)
    return part.part.wrapped


def grazing_sphere() -> object:
    """A sphere of radius 20 cut by a 5 mm cylinder 15 mm off its centre and by a 4 mm one whose side
    grazes the sphere's top (0.001 mm inside it): a near-tangent intersection."""
    import build123d as bd

    body = bd.Sphere(20) - bd.Cylinder(5, 60).moved(bd.Location((15, 0, 0)))
    return (body - bd.Cylinder(4, 60, rotation=(90, 0, 0)).moved(bd.Location((0, 0, 15.999)))).wrapped


def perforated_tube() -> object:
    """A tube of radii 20 and 18, 100 long, with 96 radial holes of 2 mm in 8 staggered rows: two cylinder
    faces with 92 and 93 holes."""
    import build123d as bd

    holes = [bd.Cylinder(2, 50, rotation=(0, 90, 0), align=(bd.Align.CENTER, bd.Align.CENTER, bd.Align.MIN))
             .moved(bd.Location((0, 0, -40 + 11 * k), (0, 0, 30 * j + 15 * (k % 2))))
             for k in range(8) for j in range(12)]
    return (bd.Cylinder(20, 100) - bd.Cylinder(18, 100) - holes).wrapped


def golf_ball() -> object:
    """A ball of radius 21.35 with 150 spherical dimples 0.5 deep: one sphere face with 150 holes
    (``build_fixtures.dimpled_ball``, whose 22-dimple ball is the fixture OCCT's STEP reader misreads)."""
    from build_fixtures import dimpled_ball

    return dimpled_ball(150).wrapped


def write_golf_ball(path: Path) -> None:
    """:func:`golf_ball` as OCCT BREP: OCCT's STEP reader misreads it (its shape healing takes the sphere
    face's holes for faces of their own and drops the rest: 151 faces read as 295, 41% of the area left)."""
    from OCP.BRepTools import BRepTools

    if not BRepTools.Write_s(golf_ball(), str(path)):
        raise RuntimeError(f"OCCT could not write {path}")


def elbow_branch() -> object:
    """A 90-degree torus elbow (bend radius 30, pipe radius 8) with a 4 mm branch on its outer side: a
    torus-cylinder intersection curve."""
    import build123d as bd

    elbow = bd.Torus(30, 8) & bd.Box(60, 60, 30, align=(bd.Align.MIN, bd.Align.MIN, bd.Align.CENTER))
    a = math.radians(40)
    branch = bd.Cylinder(4, 30, rotation=(0, 90, 0), align=(bd.Align.CENTER, bd.Align.CENTER, bd.Align.MIN))
    return (elbow + branch.moved(bd.Location((30 * math.cos(a), 30 * math.sin(a), 0), (0, 0, 40)))).wrapped


def transition_duct() -> object:
    """A loft from a 40 mm square to a circle of radius 15, 50 mm on: B-spline faces from the square's
    sharp corners to the circle."""
    import build123d as bd

    with bd.BuildPart() as part:
        with bd.BuildSketch():
            bd.Rectangle(40, 40)
        with bd.BuildSketch(bd.Plane.XY.offset(50)):
            bd.Circle(15)
        bd.loft()
    return part.part.wrapped


def oblique_extrusion() -> object:
    """A closed spline extruded 30 mm along (0.6, 0.3, 1): a surface of linear extrusion slanted to its
    section."""
    import build123d as bd

    with bd.BuildPart() as part:
        with bd.BuildSketch():
            with bd.BuildLine():
                bd.Spline((0, 0), (12, -4), (25, 3), (20, 14), (8, 16), (-3, 8), periodic=True)
            bd.make_face()
        bd.extrude(amount=30, dir=(0.6, 0.3, 1))
    return part.part.wrapped


def skewed_patch() -> object:
    """One wavy B-spline face 80 x 30 whose parameter runs about 100 times faster at one end than at
    the other (poles spaced as the cube of their index)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.Geom import Geom_BSplineSurface
    from OCP.gp import gp_Pnt

    from cadedge.occt.compat import TColgp_Array2OfPnt, TColStd_Array1OfInteger, TColStd_Array1OfReal

    nu, nv = 12, 8
    poles = TColgp_Array2OfPnt(1, nu, 1, nv)
    for i in range(nu):
        for j in range(nv):
            s = (i / (nu - 1)) ** 3
            x, y = 80 * s, 30 * (j / (nv - 1)) ** 0.5 * (1 + 0.3 * s)
            poles.SetValue(i + 1, j + 1, gp_Pnt(x, y, 6 * math.sin(x / 9) * math.cos(y / 8)))

    def knots(n: int) -> tuple:
        values, mults = TColStd_Array1OfReal(1, n - 2), TColStd_Array1OfInteger(1, n - 2)
        for a in range(n - 2):
            values.SetValue(a + 1, a / (n - 3))
            mults.SetValue(a + 1, 4 if a in (0, n - 3) else 1)
        return values, mults

    (uk, um), (vk, vm) = knots(nu), knots(nv)
    return BRepBuilderAPI_MakeFace(Geom_BSplineSurface(poles, uk, vk, um, vm, 3, 3), 1e-7).Face()


def vase_window() -> object:
    """A spline profile revolved into a vase, shelled to 1.2 mm open at the top, a window cut through
    its side: a surface of revolution and its offset, trimmed by planes."""
    import build123d as bd

    with bd.BuildPart() as part:
        with bd.BuildSketch(bd.Plane.XZ):
            with bd.BuildLine():
                side = bd.Spline((14, 0), (18, 20), (9, 45), (12, 60))
                bd.Polyline(side @ 1, (0, 60), (0, 0), side @ 0)
            bd.make_face()
        bd.revolve(axis=bd.Axis.Z)
        bd.offset(amount=-1.2, openings=part.faces().sort_by(bd.Axis.Z)[-1])
        with bd.Locations((0, 0, 30)):
            bd.Box(40, 10, 14, align=(bd.Align.MIN, bd.Align.CENTER, bd.Align.CENTER), mode=bd.Mode.SUBTRACT)
    return part.part.wrapped


def key_blade() -> object:
    """A key blade 40 x 10 x 2.5 mm as an Alias export: its top one B-spline curve through square notches
    and a rounded bump (C0 at their corners, 90 degrees at the notches), the block converted so that every
    face is a B-spline surface. gmsh meshed the top's wall in its own parameters, its triangles across the
    corners: 3.2e-2 short at ALD 1e-3."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_NurbsConvert
    from OCP.Geom import Geom_TrimmedCurve
    from OCP.GeomConvert import GeomConvert_CompCurveToBSplineCurve

    top = [(-20, 5), (-14, 5), (-14, 3), (-11, 3), (-11, 5), (-6, 5), (-6, 2), (-3, 2), (-3, 5), (4, 5), (4, 3.5),
           (8, 3.5), (8, 5), (20, 5)]
    pieces = [cq.Edge.makeLine(cq.Vector(*a, 0), cq.Vector(*b, 0)) for a, b in zip(top[:-1], top[1:])]
    pieces[8] = cq.Edge.makeSpline([cq.Vector(-3, 5, 0), cq.Vector(0, 6.2, 0), cq.Vector(4, 5, 0)])
    joined = GeomConvert_CompCurveToBSplineCurve()
    for piece in pieces:
        ends = BRepAdaptor_Curve(piece.wrapped)
        curve = BRep_Tool.Curve_s(piece.wrapped, 0.0, 1.0)  # the floats: OCCT's by-reference bounds, unused
        joined.Add(Geom_TrimmedCurve(curve, ends.FirstParameter(), ends.LastParameter()), 1e-7)
    corners = [cq.Vector(20, 5, 0), cq.Vector(20, -5, 0), cq.Vector(-20, -5, 0), cq.Vector(-20, 5, 0)]
    wire = cq.Wire.assembleEdges([cq.Edge.makeLine(a, b) for a, b in zip(corners[:-1], corners[1:])]
                                 + [cq.Edge(BRepBuilderAPI_MakeEdge(joined.BSplineCurve()).Edge())])
    solid = cq.Solid.extrudeLinear(cq.Face.makeFromWires(wire), cq.Vector(0, 0, 2.5))
    return BRepBuilderAPI_NurbsConvert(solid.wrapped, True).Shape()


def faceted() -> object:
    """A sphere fused with a cylinder, triangulated and sewn back as 228 planar triangle faces (a STEP
    made from an STL mesh): many small faces, thin triangles forced by the facets."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon, BRepBuilderAPI_Sewing
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.TopLoc import TopLoc_Location

    solid = cq.Solid.makeSphere(10).fuse(cq.Solid.makeCylinder(4, 15, cq.Vector(0, 0, 0)))
    BRepMesh_IncrementalMesh(solid.wrapped, 1.2, False, 0.6)
    sew = BRepBuilderAPI_Sewing(1e-6)
    for face in solid.Faces():
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(face.wrapped, loc)
        for i in range(1, tri.NbTriangles() + 1):
            p = [tri.Node(k).Transformed(loc.Transformation()) for k in tri.Triangle(i).Get()]
            sew.Add(BRepBuilderAPI_MakeFace(BRepBuilderAPI_MakePolygon(p[0], p[1], p[2], True).Wire(), True).Face())
    sew.Perform()
    return sew.SewedShape()


def pipe_bends() -> object:
    """A tube (2.0 / 1.6 radii) swept along a polyline with round transitions: toroidal bends between
    straight runs."""
    path = cq.Workplane().polyline([(0, 0, 0), (20, 0, 0), (20, 15, 0), (20, 15, 12), (5, 25, 12)]).val()
    return cq.Workplane("YZ").circle(2.0).circle(1.6).sweep(cq.Workplane().add(path), transition="round").val().wrapped


def nonmanifold() -> object:
    """A box and a cylinder through it joined by OCCT's general fuse (``BOPAlgo_Builder``), not fused:
    the shared inner faces bound two solids, and their edges have three or four faces (non-manifold)."""
    from OCP.BOPAlgo import BOPAlgo_Builder

    builder = BOPAlgo_Builder()
    builder.AddArgument(cq.Workplane().box(10, 10, 10).val().wrapped)
    builder.AddArgument(cq.Workplane().cylinder(14, 3).translate((5, 0, 0)).val().wrapped)
    builder.Perform()
    if builder.HasErrors():
        raise RuntimeError("the general fuse failed")
    return builder.Shape()


def gapped_sewn() -> object:
    """A drilled, filleted box whose faces were moved apart by up to 0.02 and sewn back at tolerance 0.1:
    real gaps between faces; written as STEP, OCCT reads it back with tolerances of about 0.04."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing

    solid = cq.Workplane().box(12, 8, 5).edges("|Z").fillet(2).faces(">Z").workplane().hole(3).val()
    sew = BRepBuilderAPI_Sewing(0.1)
    for i, face in enumerate(solid.Faces()):
        d = 0.01 * ((i * 7919) % 5 - 2)
        sew.Add(face.translate(cq.Vector(d, -0.5 * d, 0.7 * d)).wrapped)
    sew.Perform()
    return sew.SewedShape()


def write_very_loose(path: Path) -> None:
    """Three disjoint bodies (a block with a 0.4-wide slot, a chamfered cylinder, a sphere) and a free
    polyline, every tolerance forced to 0.5, wider than the slot: written as OCCT BREP, since STEP keeps no
    per-entity tolerances (a STEP file read back has OCCT's own)."""
    from OCP.BRepTools import BRepTools
    from OCP.ShapeFix import ShapeFix_ShapeTolerance
    from OCP.TopAbs import TopAbs_SHAPE

    block = cq.Workplane().box(10, 6, 3).faces(">Z").workplane().rect(0.4, 4).cutBlind(-0.3).val()
    cylinder = cq.Workplane().cylinder(4, 1.5).translate((12, 0, 0)).edges(">Z").chamfer(0.3).val()
    ball = cq.Workplane().sphere(1.0).translate((0, 9, 0)).val()
    wire = cq.Wire.makePolygon([cq.Vector(-5, -6, 0), cq.Vector(5, -6, 0), cq.Vector(5, -8, 2)])
    shape = cq.Compound.makeCompound([block, cylinder, ball, wire]).wrapped
    ShapeFix_ShapeTolerance().SetTolerance(shape, 0.5, TopAbs_SHAPE)
    if not BRepTools.Write_s(shape, str(path)):
        raise RuntimeError(f"OCCT could not write {path}")


def write_iges_trimmed(path: Path) -> None:
    """A filleted, drilled block fused with a lofted spline boss, written as IGES trimmed surfaces (faces
    mode: no shared edges, every face its own shell, each seam two coinciding edges of its face)."""
    from OCP.IGESControl import IGESControl_Writer

    body = cq.Workplane().box(20, 14, 6).edges("|Z").fillet(2.5).faces(">Z").workplane().hole(3).val()
    boss = (cq.Workplane().workplane(offset=3).spline([(4, -3), (8, -1), (7, 3), (3, 2)], includeCurrent=False)
            .close().workplane(offset=4).circle(1.5).loft().val())
    writer = IGESControl_Writer("MM", 0)
    writer.AddShape(body.fuse(boss).clean().wrapped)
    writer.ComputeModel()
    if not writer.Write(str(path)):
        raise RuntimeError(f"OCCT could not write {path}")


def write_xde_assembly(path: Path) -> None:
    """A STEP assembly through XDE: a drilled plate and one chamfered bolt placed three times (one shared
    product, three instances under a sub-assembly)."""
    from cadquery.occ_impl.exporters.assembly import exportAssembly

    bolt = cq.Workplane().cylinder(6, 0.8).faces(">Z").chamfer(0.2)
    plate = cq.Workplane().box(12, 6, 2).faces(">Z").workplane().rarray(6, 1, 3, 1).hole(1.8)
    row = cq.Assembly(name="bolts")
    for i, x in enumerate((-6, 0, 6)):
        row.add(bolt, name=f"bolt{i}", loc=cq.Location(cq.Vector(x, 0, 2)))
    assy = cq.Assembly(name="root").add(plate, name="plate").add(row, name="row")
    if not exportAssembly(assy, str(path)):
        raise RuntimeError(f"XDE could not write {path}")


def pmi_part() -> object:
    """The PMI model's geometry: a bracket with holes and fillets, a second body, annotation curves."""
    plate = (cq.Workplane().box(30, 20, 4).edges("|Z").fillet(3).faces(">Z").workplane()
             .rarray(18, 10, 2, 2).hole(3).val())
    boss = cq.Workplane().cylinder(8, 4).translate((0, 0, 6)).val()
    leader = cq.Wire.makePolygon([cq.Vector(15, 10, 2), cq.Vector(25, 18, 2), cq.Vector(35, 18, 2)])
    text = cq.Wire.makePolygon([cq.Vector(26, 19, 2), cq.Vector(27, 21, 2), cq.Vector(28, 19, 2),
                                cq.Vector(29, 21, 2)])
    ring = cq.Edge.makeCircle(1.5, cq.Vector(9, 5, 2.0))  # a diameter symbol drawn on the top face
    return plate.wrapped, boss.wrapped, [leader.wrapped, text.wrapped, ring.wrapped]


def write_pmi_step(path: Path) -> None:
    """Write the PMI model as AP242 through XDE: two bodies, annotation wires and a diameter dimension."""
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.Interface import Interface_Static
    from OCP.STEPCAFControl import STEPCAFControl_Writer
    from OCP.STEPControl import STEPControl_AsIs
    from OCP.TCollection import TCollection_ExtendedString, TCollection_HAsciiString
    from OCP.TDocStd import TDocStd_Document
    from OCP.TopoDS import TopoDS_Compound
    from OCP.BRep import BRep_Builder
    from OCP.XCAFDimTolObjects import XCAFDimTolObjects_DimensionObject, XCAFDimTolObjects_DimensionType
    from OCP.XCAFDoc import XCAFDoc_DocumentTool, XCAFDoc_Dimension
    from cadedge.occt.compat import TDF_LabelSequence

    plate, boss, notes = pmi_part()
    doc = TDocStd_Document(TCollection_ExtendedString("XmlXCAF"))
    shapes = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    dims = XCAFDoc_DocumentTool.DimTolTool_s(doc.Main())
    plate_label = shapes.AddShape(plate, False)
    shapes.AddShape(boss, False)
    comp = TopoDS_Compound()
    builder = BRep_Builder()
    builder.MakeCompound(comp)
    for w in notes:
        builder.Add(comp, w)
    shapes.AddShape(comp, False)
    dim_label = dims.AddDimension()
    dim = XCAFDimTolObjects_DimensionObject()
    dim.SetType(XCAFDimTolObjects_DimensionType.XCAFDimTolObjects_DimensionType_Size_Diameter)
    dim.SetValue(3.0)
    dim.SetPresentation(comp, TCollection_HAsciiString("3 mm"))
    XCAFDoc_Dimension.Set_s(dim_label).SetObject(dim)
    first = TDF_LabelSequence()
    first.Append(plate_label)
    dims.SetDimension(first, TDF_LabelSequence(), dim_label)
    writer = STEPCAFControl_Writer()  # sets the STEP defaults: choose AP242 after it
    Interface_Static.SetIVal_s("write.step.schema", 5)
    writer.SetDimTolMode(True)
    if not writer.Transfer(doc, STEPControl_AsIs) or writer.Write(str(path)) != IFSelect_RetDone:
        raise RuntimeError(f"XDE could not write {path}")


def tapered_thread() -> object:
    """NPT-like tapered pipe thread: a triangle swept along a conical helix (taper 1.79 deg), fused to a cone core."""
    import build123d as bd

    pitch, length, r0 = 1.8, 12.0, 8.0
    cone_angle = 1.79
    helix = bd.Helix(pitch=pitch, height=length, radius=r0, cone_angle=cone_angle)
    d = 1.0
    prof = bd.Plane.XZ * bd.Polygon((r0 - 0.05, -0.4 * pitch), (r0 + d, 0), (r0 - 0.05, 0.4 * pitch), align=None)
    thread = bd.sweep(prof, path=helix, is_frenet=True)
    r_top = r0 + length * math.tan(math.radians(cone_angle))
    core = bd.Solid.make_cone(r0 + 0.02 - 0.1 * math.tan(math.radians(cone_angle)), r_top + 0.02, length + 2,
                              bd.Plane.XY.offset(-1))
    body = core.fuse(thread)
    bore = bd.Cylinder(5, 40)
    return (body - bore).wrapped


def torus_knot() -> object:
    """A (3,2) torus knot (R=12, r=5) as a 200-point periodic spline; a 1.5 mm circle piped along it
    (BRepOffsetAPI_MakePipe on the closed path: one closed B-spline face, exported as a closed shell)."""
    import build123d as bd

    from OCP.BRepOffsetAPI import BRepOffsetAPI_MakePipe
    pts = []
    for i in range(200):
        t = 2 * math.pi * i / 200
        rr = 12 + 5 * math.cos(3 * t)
        pts.append((rr * math.cos(2 * t), rr * math.sin(2 * t), -5 * math.sin(3 * t)))
    path = bd.Wire([bd.Spline(*pts, periodic=True)])
    sec = (bd.Plane(origin=path @ 0, z_dir=path % 0) * bd.Circle(1.5)).wire()
    mp = BRepOffsetAPI_MakePipe(path.wrapped, sec.wrapped)
    mp.Build()
    return mp.Shape()


def _sine_revolved() -> cq.Workplane:
    """A profile r = 10 + 2 sin(z 2 pi / 6) over 60 mm (10 waves, 20 inflections) revolved a full turn."""
    pts = [(10 + 2 * math.sin(2 * math.pi * z / 6.0), z) for z in [i * 0.25 for i in range(241)]]
    prof = (cq.Workplane("XZ").moveTo(0, 0).lineTo(pts[0][0], 0).spline(pts[1:], includeCurrent=True)
            .lineTo(0, 60).close())
    return prof.revolve(360, (0, 0, 0), (0, 1, 0))


def sine_revolve() -> object:
    """:func:`sine_revolve_solid` shelled 0.8 mm open at the top: its inner face is an offset by 0.8 of a
    surface whose radius of curvature goes down to 0.46, so it folds on itself."""
    return _sine_revolved().faces(">Z").shell(-0.8).val().wrapped


def sine_revolve_solid() -> object:
    """A sine profile revolved as a solid (no offset surface): see :func:`_sine_revolved`."""
    return _sine_revolved().val().wrapped


def skew_cylinders() -> object:
    """Two cylinders, radii 10 and 9.9, axes crossing at 8 degrees through one point, fused."""
    a = cq.Solid.makeCylinder(10, 120, cq.Vector(0, 0, -60), cq.Vector(0, 0, 1))
    ang = math.radians(8)
    d = cq.Vector(math.sin(ang), 0, math.cos(ang))
    b = cq.Solid.makeCylinder(9.9, 120, cq.Vector(0, 0, 0) - d * 60, d)
    return a.fuse(b).clean().wrapped


def nut_sphere() -> object:
    """A 24 mm hex prism 12 high, chamfered 1 mm on its vertical edges, intersected with a sphere R=14.5
    (nut crowning), an M12 bore with 1 mm chamfers."""
    hexp = cq.Workplane("XY").polygon(6, 24 / math.cos(math.pi / 6)).extrude(12).translate((0, 0, -6))
    hexp = hexp.edges("|Z").chamfer(1.0)
    sph = cq.Workplane("XY").sphere(14.5)
    body = hexp.intersect(sph)
    body = body.faces(">Z").workplane().hole(12)
    body = body.faces(">Z or <Z").edges("%CIRCLE").edges(cq.selectors.RadiusNthSelector(0)).chamfer(0.8)
    return body.val().wrapped


def tiny_fillets() -> object:
    """A 100 x 60 x 20 block with a 40 x 20 x 10 pocket and 4 bosses; every edge filleted 0.05."""
    w = cq.Workplane("XY").box(100, 60, 20)
    w = w.faces(">Z").workplane().rect(40, 20).cutBlind(-10)
    w = w.faces(">Z").workplane().rarray(70, 40, 2, 2).circle(4).extrude(5)
    w = w.edges().fillet(0.05)
    return w.val().wrapped


def thin_ribs() -> object:
    """A 200 x 150 x 3 plate with 9 ribs 0.1 mm thick and 8 mm high across it and 1 along it (crossing)."""
    w = cq.Workplane("XY").box(200, 150, 3).translate((0, 0, 1.5))
    for i in range(9):
        x = -80 + 20 * i
        w = w.union(cq.Workplane("XY").box(0.1, 140, 8).translate((x, 0, 3 + 4)))
    w = w.union(cq.Workplane("XY").box(190, 0.1, 8).translate((0, 0, 3 + 4)))
    return w.val().wrapped


def cap_slots() -> object:
    """A spherical cap (R=30, 2 mm thick, 40 deg half-angle) with 3 rings of radial slots (6, 12, 18),
    rounded ends, cut straight down."""
    outer = cq.Workplane("XY").sphere(30)
    inner = cq.Workplane("XY").sphere(28)
    shell = outer.cut(inner)
    h = 30 * math.cos(math.radians(40))
    cap = shell.intersect(cq.Workplane("XY").box(80, 80, 40).translate((0, 0, h + 20)))
    for ring, (n, rad) in enumerate([(6, 6.0), (12, 11.5), (18, 16.5)]):
        for k in range(n):
            a = 360.0 * k / n + 7.0 * ring
            slot = (cq.Workplane("XY").workplane(offset=h - 10).center(rad, 0).slot2D(3.0, 1.0, 0)
                    .extrude(40).rotate((0, 0, 0), (0, 0, 1), a))
            cap = cap.cut(slot)
    return cap.val().wrapped


def four_fillet_vertex() -> object:
    """A square pyramid (30 mm base, 20 high, to a point) on a 30 x 30 x 10 block, its 4 slanted edges
    filleted 3 mm: four fillets running into the apex vertex."""
    V = cq.Vector
    base = [V(-15, -15, 10), V(15, -15, 10), V(15, 15, 10), V(-15, 15, 10)]
    apex = V(0, 0, 30)
    faces = [cq.Face.makeFromWires(cq.Wire.makePolygon([base[i], base[(i + 1) % 4], apex], close=True))
             for i in range(4)]
    faces.append(cq.Face.makeFromWires(cq.Wire.makePolygon(base[::-1], close=True)))
    pyr = cq.Solid.makeSolid(cq.Shell.makeShell(faces))
    body = cq.Workplane("XY").box(30, 30, 10).translate((0, 0, 5)).union(cq.Workplane().add(pyr)).clean()
    body = body.edges(cq.selectors.BoxSelector((-16, -16, 10.5), (16, 16, 30.5))).fillet(3.0)
    return body.val().wrapped


def diamond_knurl() -> object:
    """A cylinder R=10, 20 long, with 10 left- and 10 right-hand helical V-grooves (pitch 60, 0.6 deep): a
    diamond knurl."""
    import build123d as bd

    body = bd.Cylinder(10, 20, align=(bd.Align.CENTER, bd.Align.CENTER, bd.Align.MIN))
    cutters = []
    for hand in (False, True):
        helix = bd.Helix(pitch=60, height=30, radius=10, lefthand=hand).moved(bd.Location((0, 0, -5)))
        p0 = helix @ 0
        t0 = helix % 0
        pl = bd.Plane(origin=p0, x_dir=(p0.X, p0.Y, 0), z_dir=t0)
        prof = pl * bd.Polygon((-0.6, 0), (0.8, -0.7), (0.8, 0.7), align=None)
        g = bd.sweep(prof, path=helix, is_frenet=True)
        for k in range(10):
            cutters.append(g.rotate(bd.Axis.Z, 36 * k))
    for c in cutters:
        body = body - c
    return body.wrapped


def sheet_bend() -> object:
    """A 1 mm sheet bent 90 deg (inner radius 1) between a 40 and a 30 mm flange, 50 wide, with two
    rectangular bend reliefs 2 wide at the bend's ends and a 10 mm slot across the bend."""
    t, r = 1.0, 1.0
    prof = (cq.Workplane("XZ").moveTo(-40, 0).lineTo(0, 0)
            .radiusArc((r + t, r + t), -(r + t)).lineTo(r + t, 30).lineTo(r, 30).lineTo(r, r)
            .radiusArc((0, t), r).lineTo(-40, t).close())
    sheet = prof.extrude(-50)
    for y in (1, 47):
        sheet = sheet.cut(cq.Workplane("XY").box(4, 2, 4).translate((0, y + 1, 1.5)))
    sheet = sheet.cut(cq.Workplane("XY").box(6, 10, 8, centered=(False, True, False)).translate((-2, 25, -1)))
    return sheet.val().wrapped


def bevel_gear() -> object:
    """A 20-tooth straight bevel gear: trapezoid teeth lofted toward the cone apex (outer module 2.5,
    face width 12) on a conical frustum, with a 10 mm bore."""
    n, r_out, depth = 20, 25.0, 2.5
    apex_h = 25.0  # 45-degree pitch cone
    k = 1 - 12 / (r_out * math.sqrt(2))  # inner scale
    def tooth(scale):
        c = 2 * math.pi * r_out / n * scale
        pts = [(-0.3 * c, 0), (-0.12 * c, depth * scale * 1.8), (0.12 * c, depth * scale * 1.8), (0.3 * c, 0)]
        # tooth in a plane normal to the cone generatrix at the pitch point
        z = apex_h * (1 - scale)
        rr = r_out * scale
        pl = cq.Plane(origin=(rr, 0, z), xDir=(0, -1, 0), normal=(-1, 0, 1))
        return cq.Wire.makePolygon([pl.toWorldCoords((x, y - 0.5 * depth * scale)) for x, y in pts], close=True)
    t = cq.Solid.makeLoft([tooth(1.0), tooth(k)], True)
    blank = cq.Solid.makeCone(r_out, r_out * k, apex_h * (1 - k), cq.Vector(0, 0, 0), cq.Vector(0, 0, 1))
    body = cq.Workplane().add(blank)
    for i in range(n):
        body = body.union(cq.Workplane().add(t.rotate(cq.Vector(), cq.Vector(0, 0, 1), 360 * i / n)))
    body = body.cut(cq.Workplane("XY").circle(5).extrude(100).translate((0, 0, -50)))
    return body.val().wrapped


def swept_shell() -> object:
    """A section changing from a circle R=8 via an ellipse 10x4 to a circle R=3 swept along a 3-D spline
    (multi-section sweep), shelled 0.6 mm open at both ends."""
    import build123d as bd

    path = bd.Spline((0, 0, 0), (20, 10, 15), (40, -5, 30), (60, 0, 35))
    secs = []
    for u, mk in ((0, lambda: bd.Circle(8)), (0.5, lambda: bd.Ellipse(10, 4)), (1, lambda: bd.Circle(3))):
        secs.append((bd.Plane(origin=path @ u, z_dir=path % u) * mk()).wire())
    solid = cq.Solid.sweep_multi([cq.Wire(w.wrapped) for w in secs], cq.Wire.assembleEdges([cq.Edge(path.wrapped)]),
                                 makeSolid=True)
    s = cq.Workplane().add(solid)
    return s.faces("<X or >X").shell(-0.6).val().wrapped


MODELS: dict[str, Callable[[], object]] = {
    "spring": spring, "flat_coil": flat_coil, "revolved_spline": revolved_spline, "lofted_spline": lofted_spline,
    "twisted_blade": twisted_blade, "hooked_wing": hooked_wing, "razor_wing": razor_wing,
    "thin_plate": thin_plate, "sliver_faces": sliver_faces,
    "tiny_edges": tiny_edges, "hole_through_fillet": hole_through_fillet, "bspline_cage": bspline_cage,
    "wavy_plate": wavy_plate, "loose_tolerance": loose_tolerance, "free_edges": free_edges,
    "seams_and_poles": seams_and_poles, "assembly": assembly,
    "threaded_bolt": threaded_bolt, "filleted_boolean": filleted_boolean, "shelled_drafted": shelled_drafted,
    "swept_nonplanar": swept_nonplanar, "tangent_union": tangent_union, "knurled": knurled,
    "sliver_hole": sliver_hole, "faceted": faceted, "pipe_bends": pipe_bends,
    "nonmanifold": nonmanifold, "gapped_sewn": gapped_sewn, "thick_wavy_plate": thick_wavy_plate,
    "sharp_blade": sharp_blade, "propeller": propeller,
    "gear": gear, "bottle": bottle, "cut_torus": cut_torus, "ellipsoid": ellipsoid, "cone_apex": cone_apex,
    "mug": mug, "pocket_box": pocket_box, "thin_shell": thin_shell, "washer_thin": washer_thin,
    "sphere_pinhole": sphere_pinhole, "bracket_micro": bracket_micro, "bracket_huge": bracket_huge,
    "bracket_far": bracket_far, "star_prism": star_prism, "notched_block": notched_block,
    "tangent_inlet_tee": tangent_inlet_tee, "pipe_tee_equal": pipe_tee_equal,
    "sphere_sector": sphere_sector, "revolved_sector": revolved_sector, "key_blade": key_blade,
    "vanishing_fillet": vanishing_fillet,
    "text_plate": text_plate, "text_cylinder": text_cylinder, "variable_fillet": variable_fillet,
    "vertex_blend": vertex_blend, "conical_spring": conical_spring, "perforated_plate": perforated_plate,
    "grazing_sphere": grazing_sphere,
    "perforated_tube": perforated_tube, "elbow_branch": elbow_branch, "transition_duct": transition_duct,
    "oblique_extrusion": oblique_extrusion, "skewed_patch": skewed_patch, "vase_window": vase_window,
    "tapered_thread": tapered_thread, "torus_knot": torus_knot, "sine_revolve": sine_revolve,
    "sine_revolve_solid": sine_revolve_solid, "skew_cylinders": skew_cylinders, "nut_sphere": nut_sphere,
    "tiny_fillets": tiny_fillets, "thin_ribs": thin_ribs, "cap_slots": cap_slots,
    "four_fillet_vertex": four_fillet_vertex, "diamond_knurl": diamond_knurl, "sheet_bend": sheet_bend,
    "bevel_gear": bevel_gear, "swept_shell": swept_shell,
}
#: Models written through XDE rather than cadquery's shape exporter.
XDE_WRITERS: dict[str, Callable[[Path], None]] = {"pmi_ap242": write_pmi_step, "xde_assembly": write_xde_assembly}
#: Models written in another format, by their own writer: name -> (suffix, writer).
OTHER_FORMATS: dict[str, tuple[str, Callable[[Path], None]]] = {
    "very_loose": (".brep", write_very_loose), "iges_trimmed": (".igs", write_iges_trimmed),
    "golf_ball": (".brep", write_golf_ball)}
NAMES = list(MODELS) + list(XDE_WRITERS) + list(OTHER_FORMATS)


def write_model(name: str, folder: Path) -> Path:
    """Write model ``name`` as ``folder/<name>.step`` (``.brep``, ``.igs`` for ``OTHER_FORMATS``); returns
    the path."""
    if name in OTHER_FORMATS:
        suffix, writer = OTHER_FORMATS[name]
        path = Path(folder) / f"{name}{suffix}"
        writer(path)
        return path
    path = Path(folder) / f"{name}.step"
    if name in XDE_WRITERS:
        XDE_WRITERS[name](path)
    else:
        cq.exporters.export(cq.Shape.cast(MODELS[name]()), str(path), exportType="STEP")
    return path


def write_all(argv: list[str], names: list[str], write: Callable[[str, Path], Path], what: str,
              default: str) -> int:
    """The command line of a model script: write every model of ``names`` (by ``write(name, folder)``)
    into the folder given (``default`` if none), printing each path."""
    import argparse

    ap = argparse.ArgumentParser(description=f"Write every {what} into FOLDER.")
    ap.add_argument("folder", nargs="?", type=Path, default=Path(default), help=f"default: {default}")
    folder = ap.parse_args(argv).folder
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        print(write(name, folder))
    return 0


def main(argv: list[str]) -> int:
    return write_all(argv, NAMES, write_model, "hard model of the mesh benchmark", "hard_models")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
