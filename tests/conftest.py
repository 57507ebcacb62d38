"""Shared test paths: the committed fixtures and the third-party STEP corpus (never copied in).

The corpus is found as ``scripts/corpus_path.py`` says (``$CADEDGE_CORPUS``, else a default folder
beside the repository). Tests that read it carry the ``corpus`` marker (parametrized ones take their
files from :func:`corpus_params`); without the corpus they skip with one line saying why, so a fresh
clone runs everything else. With ``CADEDGE_REQUIRE_CORPUS=1`` (CI) a missing corpus stops the run and a
skipped corpus test fails.
"""

from __future__ import annotations

import importlib.util
import signal
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "fixtures"
FIXTURE_FILES = sorted(FIXTURES.glob("*.step"))


def _load_corpus_path():
    """scripts/corpus_path.py, importable as ``corpus_path`` (the scripts the tests load import it so)."""
    if "corpus_path" not in sys.modules:
        spec = importlib.util.spec_from_file_location("corpus_path", ROOT / "scripts" / "corpus_path.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules["corpus_path"] = module
        spec.loader.exec_module(module)
    return sys.modules["corpus_path"]


corpus_path = _load_corpus_path()
#: The corpus folder, or None.
CORPUS_DIR: Path | None = corpus_path.find_corpus()
#: Where corpus files are named from; without a corpus the default path, which only ``corpus`` tests use.
CORPUS: Path = CORPUS_DIR or corpus_path.DEFAULT
CORPUS_FILES: list[Path] = corpus_path.step_files(CORPUS_DIR)
NO_CORPUS = corpus_path.missing_reason()


def corpus_sources() -> dict[str, dict[str, str]]:
    """Rows of ``SOURCES.tsv`` (what each corpus file holds), keyed by file name; empty without the corpus."""
    return corpus_path.sources(CORPUS_DIR)


def corpus_params(values=None) -> list:
    """Parameters over corpus items (default: every corpus STEP file), each marked ``corpus``.

    Without the corpus, one placeholder that skips, so the test reports the reason instead of vanishing.
    """
    if CORPUS_DIR is None:
        return [pytest.param(None, id="corpus", marks=pytest.mark.corpus)]
    values = CORPUS_FILES if values is None else values
    return [pytest.param(v, id=getattr(v, "name", str(v)), marks=pytest.mark.corpus) for v in values]


def pytest_configure(config):
    if CORPUS_DIR is None and corpus_path.corpus_required():
        raise pytest.UsageError(f"{corpus_path.REQUIRE_ENV} is set, but the {NO_CORPUS}")
    _ctrl_c_as_in_a_terminal()


def _ctrl_c_as_in_a_terminal() -> None:
    """Let SIGINT raise KeyboardInterrupt here, and so in the children the tests start, as in a terminal.

    A shell without job control starts a background command (``cmd &`` in a script, ``nohup``) with SIGINT
    ignored; the children inherit that and a new Python keeps it, so the tests that send a child Ctrl-C
    (and expect exit 130) failed when the suite was started so, or passed only if an earlier test in the
    same process had happened to set a handler. Run under pytest-xdist, this runs in each worker too.
    """
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_report_header(config):
    if CORPUS_DIR is None:
        return f"cadedge corpus: none, corpus tests skip ({NO_CORPUS})"
    return f"cadedge corpus: {CORPUS_DIR} ({len(CORPUS_FILES)} STEP files)"


def pytest_collection_modifyitems(config, items):
    if CORPUS_DIR is None:
        skip = pytest.mark.skip(reason=NO_CORPUS)
        for item in items:
            if item.get_closest_marker("corpus"):
                item.add_marker(skip)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if report.skipped and item.get_closest_marker("corpus") and corpus_path.corpus_required():
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
        report.outcome = "failed"
        report.longrepr = f"corpus test skipped although {corpus_path.REQUIRE_ENV} is set: {reason}"


@pytest.fixture(scope="session")
def fixtures_dir() -> Path:
    return FIXTURES


@pytest.fixture(scope="session")
def corpus_dir() -> Path:
    """The corpus folder; skips (fails under ``CADEDGE_REQUIRE_CORPUS``) without it."""
    if CORPUS_DIR is None:
        pytest.skip(NO_CORPUS)
    return CORPUS_DIR


@pytest.fixture(scope="session")
def gapped_box_step(tmp_path_factory) -> Path:
    """A 12 x 8 x 5 box whose faces were moved apart by up to 0.02, sewn at 0.1 and written as STEP: read
    back, each face has pcurves of its own with gaps of about 0.02 between one and the next, and edges
    with tolerances of 0.014-0.028."""
    pytest.importorskip("OCP")
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing, BRepBuilderAPI_Transform
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.gp import gp_Trsf, gp_Vec
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    from cadedge.occt.loading import quiet_occt
    from cadedge.occt.topology import Topology

    sew = BRepBuilderAPI_Sewing(0.1)
    for i, face in enumerate(Topology(BRepPrimAPI_MakeBox(12.0, 8.0, 5.0).Shape()).faces):
        d = 0.01 * ((i * 7919) % 5 - 2)
        move = gp_Trsf()
        move.SetTranslation(gp_Vec(d, -0.5 * d, 0.7 * d))
        sew.Add(BRepBuilderAPI_Transform(face, move, True).Shape())
    sew.Perform()
    path = tmp_path_factory.mktemp("gapped") / "gapped_box.step"
    with quiet_occt():
        writer = STEPControl_Writer()
        writer.Transfer(sew.SewedShape(), STEPControl_AsIs)
        writer.Write(str(path))
    return path


def stadium_cap(radius: float = 1.0, length: float = 20.0, n: int = 120):
    """A planar face bounded by one periodic spline through ``n`` points of a stadium outline (straight
    sides ``length`` long, round ends of ``radius``), and that curve; built with OCP's own
    ``GeomAPI_Interpolate``, so on both OCP lines."""
    import math

    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeWire
    from OCP.GeomAPI import GeomAPI_Interpolate
    from OCP.gp import gp_Pnt

    from cadedge.occt.compat import TColgp_HArray1OfPnt

    perimeter = 2 * length + 2 * math.pi * radius
    pts = TColgp_HArray1OfPnt(1, n)
    for k in range(n):
        s = perimeter * k / n
        if s < length:
            x, y = -length / 2 + s, -radius
        elif s < length + math.pi * radius:
            a = -math.pi / 2 + (s - length) / radius
            x, y = length / 2 + radius * math.cos(a), radius * math.sin(a)
        elif s < 2 * length + math.pi * radius:
            x, y = length / 2 - (s - length - math.pi * radius), radius
        else:
            a = math.pi / 2 + (s - 2 * length - math.pi * radius) / radius
            x, y = -length / 2 + radius * math.cos(a), radius * math.sin(a)
        pts.SetValue(k + 1, gp_Pnt(x, y, 0.0))
    interp = GeomAPI_Interpolate(pts, True, 1e-9)
    interp.Perform()
    curve = interp.Curve()
    edge = BRepBuilderAPI_MakeEdge(curve).Edge()
    return BRepBuilderAPI_MakeFace(BRepBuilderAPI_MakeWire(edge).Wire(), True).Face(), curve


def half_ellipsoid():
    """The lower half of an ellipsoid with semi-axes 1.038, 0.36 and 0.2076 as one face: a sphere made a
    rational B-spline surface by OCCT's non-uniform scaling, cut at its equator, as in gmsh's
    ellipses.brep; its pole is a degenerate edge, its seam an edge on the face twice. gmsh's
    Frontal-Delaunay turns a triangle or a few over beside the pole."""
    import math

    from OCP.BRep import BRep_Tool
    from OCP.BRepBuilderAPI import BRepBuilderAPI_GTransform, BRepBuilderAPI_MakeFace
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeSphere
    from OCP.gp import gp_GTrsf, gp_Mat
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer

    from cadedge.occt.compat import TopoDS  # OCP 8.0 has no OCP.TopoDS.TopoDS.Face_s

    scale = gp_GTrsf()
    scale.SetVectorialPart(gp_Mat(1.038, 0, 0, 0, 0.36, 0, 0, 0, 0.2076))
    ellipsoid = BRepBuilderAPI_GTransform(BRepPrimAPI_MakeSphere(1.0).Shape(), scale, True).Shape()
    surface = BRep_Tool.Surface_s(TopoDS.Face_s(TopExp_Explorer(ellipsoid, TopAbs_FACE).Current()))
    return BRepBuilderAPI_MakeFace(surface, 0.0, 2 * math.pi, -math.pi / 2, 0.0, 1e-7).Face()


def listed_cone_and_sphere():
    """A cone fused with a sphere on its apex, in a compound that lists the solid's vertices and edges, last
    first, before the solid (as gmsh writes a whole model to BREP; its benchmark simple_plane.brep is one):
    cadedge's ids follow that listing, gmsh binds points and curves in another order. The cone's apex is a
    degenerate edge."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCone, BRepPrimAPI_MakeSphere
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt

    cone = BRepPrimAPI_MakeCone(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 10.0, 0.0, 12.0).Shape()
    solid = BRepAlgoAPI_Fuse(cone, BRepPrimAPI_MakeSphere(gp_Pnt(0, 0, 14.0), 4.0).Shape()).Shape()
    return _listed(solid, lambda n: range(n, 0, -1), lambda n: range(n, 0, -1))


def listed_step_with_pieces_swapped():
    """Two boxes fused into a step, in a compound that lists the solid's vertices and edges before it, in
    the solid's own order but for two pieces of one line (edges 5 and 17 of the solid, parameters [0, 1]
    and [1, 2] of one OCCT line) swapped: cadedge's edge 5 is gmsh's curve 17, and gmsh's curve 5 the
    other piece of the same line."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.gp import gp_Pnt

    solid = BRepAlgoAPI_Fuse(BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), gp_Pnt(2, 1, 1)).Shape(),
                             BRepPrimAPI_MakeBox(gp_Pnt(1, 0, 0), gp_Pnt(3, 1, 0.5)).Shape()).Shape()

    def swapped(n):
        order = list(range(1, n + 1))
        order[4], order[16] = 17, 5
        return order

    return _listed(solid, lambda n: range(1, n + 1), swapped)


def _listed(solid, vertex_order, edge_order):
    """A compound of ``solid``'s vertices and edges (MapShapes indices in the orders ``vertex_order(n)`` and
    ``edge_order(n)`` give), then ``solid`` itself."""
    from OCP.BRep import BRep_Builder
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_VERTEX
    from OCP.TopExp import TopExp
    from OCP.TopoDS import TopoDS_Compound

    from cadedge.occt.compat import TopTools_IndexedMapOfShape

    builder, compound = BRep_Builder(), TopoDS_Compound()
    builder.MakeCompound(compound)
    for kind, order in ((TopAbs_VERTEX, vertex_order), (TopAbs_EDGE, edge_order)):
        found = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(solid, kind, found)
        for i in order(found.Extent()):
            builder.Add(compound, found.FindKey(i))
    builder.Add(compound, solid)
    return compound
