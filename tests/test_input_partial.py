"""Partial, damaged, truncated, garbage and empty model files: refused with one line saying which,
unless ``allow_partial`` (then refined with a warning saying what was lost).

The damaged files are made at test time from the fixtures (cut at a whole entity with the trailer
appended, an entity reference pointed at nothing, the DATA section replaced) and, where present,
from the third-party corpus (``CADEDGE_CORPUS``, else ../shared/corpus).
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest

pytest.importorskip("OCP")

import cadedge  # noqa: E402
from cadedge.cli import main  # noqa: E402
from cadedge.errors import InputError  # noqa: E402
from cadedge.occt.reader import load_shape  # noqa: E402
from conftest import FIXTURES, ROOT  # noqa: E402

TRAILER = b"\nENDSEC;\nEND-ISO-10303-21;\n"
CORPUS = Path(os.environ.get("CADEDGE_CORPUS") or ROOT.parent / "shared" / "corpus")
CORPUS_STEP = sorted(p for p in CORPUS.glob("*") if p.suffix.lower() in (".step", ".stp")) if CORPUS.is_dir() else []


def cut(src: Path, dest: Path, fraction: float, *, mid_entity: bool = False) -> Path:
    """``src`` cut at ``fraction`` after a whole entity (or inside the next one), trailer appended."""
    data = src.read_bytes()
    head = data[: int(len(data) * fraction)]
    end = max(head.rfind(b";\n"), head.rfind(b";\r\n")) + 1
    dest.write_bytes(head[: end + (12 if mid_entity else 0)] + TRAILER)
    return dest


def error_of(source, **kwargs) -> str:
    with pytest.raises(InputError) as info:
        load_shape(source, **kwargs)
    msg = str(info.value)
    assert "\n" not in msg
    return msg


def test_cut_bracket_names_lost_faces_and_solids(tmp_path):
    path = cut(FIXTURES / "bracket.step", tmp_path / "bracket_cut.step", 0.9)
    msg = error_of(path)
    assert msg.startswith(f"{path}: partial transfer refused: ")
    m = re.search(r"(\d+) of 14 faces \(1 of 1 solids\) failed to load", msg)
    assert m and int(m.group(1)) > 0, msg
    assert "--allow-partial" in msg and "missing from the file" in msg
    loaded = load_shape(path, allow_partial=True)
    assert loaded.warnings[0].startswith("partial transfer: ") and m.group(0) in loaded.warnings[0]


def test_entity_pointing_at_nothing_loses_a_solid(tmp_path):
    text = (FIXTURES / "two_solids.step").read_text()
    first = text.index("MANIFOLD_SOLID_BREP(")
    end = text.index(";", first)
    bad = tmp_path / "two_solids_bad.step"
    bad.write_text(text[:first] + "MANIFOLD_SOLID_BREP('',#99999999)" + text[end:])
    msg = error_of(bad)
    assert "partial transfer refused" in msg and "of 9 faces (1 of 2 solids) failed to load" in msg
    grid = cadedge.refine_shape(bad, ald=1e-2, allow_partial=True)
    assert 0 < len(grid.edges) < len(cadedge.refine_shape(FIXTURES / "two_solids.step", ald=1e-2).edges)
    assert any(w.startswith("partial transfer: ") and "1 of 2 solids" in w for w in grid.warnings)


def unshared_tetra(path: Path) -> Path:
    """A tetrahedron written as one MANIFOLD_SOLID_BREP whose four faces have edges and vertices of their
    own, none shared: how some ECAD libraries' faceted models are written (OCCT hands back four shells)."""
    import numpy as np

    corners = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]], dtype=float)
    lines: list[str] = []

    def entity(text: str) -> str:
        ref = f"#{100 + len(lines)}"
        lines.append(f"{ref}={text};")
        return ref

    def point(x) -> str:
        return entity("CARTESIAN_POINT('',(%r,%r,%r))" % tuple(map(float, x)))

    def direction(x) -> str:
        x = np.asarray(x, dtype=float)
        return entity("DIRECTION('',(%r,%r,%r))" % tuple(map(float, x / np.linalg.norm(x))))

    faces = []
    for corner in [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]:  # each face's corners, outward
        q = corners[list(corner)]
        vertices = [entity(f"VERTEX_POINT('',{point(x)})") for x in q]
        edges = []
        for k in range(3):
            vector = entity(f"VECTOR('',{direction(q[(k + 1) % 3] - q[k])},1.0)")
            line = entity(f"LINE('',{point(q[k])},{vector})")
            curve = entity(f"EDGE_CURVE('',{vertices[k]},{vertices[(k + 1) % 3]},{line},.T.)")
            edges.append(entity(f"ORIENTED_EDGE('',*,*,{curve},.T.)"))
        loop = entity(f"EDGE_LOOP('',({','.join(edges)}))")
        bound = entity(f"FACE_OUTER_BOUND('',{loop},.T.)")
        frame = entity(f"AXIS2_PLACEMENT_3D('',{point(q[0])},{direction(np.cross(q[1] - q[0], q[2] - q[0]))},"
                       f"{direction(q[1] - q[0])})")
        plane = entity(f"PLANE('',{frame})")
        faces.append(entity(f"ADVANCED_FACE('',({bound}),{plane},.T.)"))
    head = """ISO-10303-21;
HEADER;
FILE_DESCRIPTION(('a tetrahedron whose faces share no edge'),'2;1');
FILE_NAME('unshared','2026-12-06T00:00:00',(''),(''),'','','');
FILE_SCHEMA(('AUTOMOTIVE_DESIGN'));
ENDSEC;
DATA;
#1=SHAPE_DEFINITION_REPRESENTATION(#2,#3);
#2=PRODUCT_DEFINITION_SHAPE('',$,#4);
#3=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#19,#23),#11);
#4=PRODUCT_DEFINITION('design','',#6,#5);
#5=PRODUCT_DEFINITION_CONTEXT('part definition',#10,'design');
#6=PRODUCT_DEFINITION_FORMATION('','',#8);
#7=APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2003,#10);
#8=PRODUCT('unshared','unshared','',(#9));
#9=PRODUCT_CONTEXT('',#10,'mechanical');
#10=APPLICATION_CONTEXT('core data for automotive mechanical design processes');
#11=(GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#12)) GLOBAL_UNIT_ASSIGNED_CONTEXT((#13,#14,#18)) REPRESENTATION_CONTEXT('',''));
#12=UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-06),#13,'distance_accuracy_value','');
#13=(LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.));
#14=(NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.));
#18=(NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT());
#19=AXIS2_PLACEMENT_3D('',#20,#21,#22);
#20=CARTESIAN_POINT('',(0.0,0.0,0.0));
#21=DIRECTION('',(0.0,0.0,1.0));
#22=DIRECTION('',(1.0,0.0,0.0));
"""
    body = f"#23=MANIFOLD_SOLID_BREP('',#24);\n#24=CLOSED_SHELL('',({','.join(faces)}));\n"
    path.write_text(head + body + "\n".join(lines) + "\nENDSEC;\nEND-ISO-10303-21;\n")
    return path


def test_a_solid_whose_faces_share_no_edge_is_refused_saying_every_face_loaded(tmp_path):
    """The solid is lost but none of its faces: the refusal says so, and allowing the partial transfer
    refines all of them."""
    path = unshared_tetra(tmp_path / "unshared.step")
    msg = error_of(path)
    assert msg == (f"{path}: partial transfer refused: 1 of 1 solids failed to load (all 4 faces loaded, as "
                   "shells or faces outside any solid); allow_partial=True (--allow-partial) refines what did "
                   "load")
    grid = cadedge.refine_shape(path, ald=1e-2, allow_partial=True)
    assert grid.faces == 4 and len(grid.edges) == 12
    assert any(w.startswith("partial transfer: 1 of 1 solids failed to load (all 4 faces") for w in grid.warnings)


def test_every_entity_of_the_only_solid_lost_is_corrupt_even_when_allowed(tmp_path):
    text = (FIXTURES / "bracket.step").read_text()
    first = text.index("MANIFOLD_SOLID_BREP(")
    bad = tmp_path / "nosolid.step"
    bad.write_text(text[:first] + "MANIFOLD_SOLID_BREP('',#99999999)" + text[text.index(";", first):])
    for allow in (False, True):
        msg = error_of(bad, allow_partial=allow)
        assert "corrupt STEP file: nothing transferred" in msg and "14 of 14 faces" in msg


def test_faces_occts_healing_splits_are_named_in_a_warning(capsys):
    """misread/dimpled_ball.step (scripts/build_fixtures.py) holds one solid of 23 faces, a sphere face with 22
    holes among them. OCCT's STEP reader heals that face into its holes as faces of their own and drops
    the rest (43 faces, 21 solids, 6% of the area left): nothing is refused, since a split can also be harmless,
    but the first warning says what the healing did; a file read as it is written has no such warning."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    loaded = load_shape(FIXTURES / "misread" / "dimpled_ball.step")
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(loaded.shape, props)
    assert props.Mass() < 0.1 * 5741.3  # the shape as OCCT read it: the ball's own area is 5741.3
    assert loaded.warnings[0].startswith("OCCT's shape healing read the file's 23 faces as 43 and its 1 solid "
                                         "as 21: it split faces the file holds whole")
    assert not any("shape healing" in w for w in load_shape(FIXTURES / "bracket.step").warnings)
    assert main(["info", str(FIXTURES / "misread" / "dimpled_ball.step")]) == 0
    assert "warning: OCCT's shape healing read the file's 23 faces as 43" in capsys.readouterr().err


def test_missing_reference_without_lost_faces_is_still_refused(tmp_path):
    # the cut removes only the representation context: every face transfers, but the file is damaged
    path = cut(FIXTURES / "cylinder.step", tmp_path / "cyl.step", 0.9)
    msg = error_of(path)
    assert "no face or solid measurably lost" in msg and "missing from the file" in msg
    assert load_shape(path, allow_partial=True).warnings[0].startswith("partial transfer: ")


def test_truncated_garbage_and_empty_say_which(tmp_path):
    data = (FIXTURES / "bracket.step").read_bytes()
    header = data[: data.index(b"DATA;")]
    cases = {
        "truncated.step": data[: len(data) // 2],
        "garbage.step": header + b"DATA;\nthis is not an entity @#$%\nENDSEC;\nEND-ISO-10303-21;\n",
        "nodata.step": header + b"DATA;\nENDSEC;\nEND-ISO-10303-21;\n",
        "zero.step": b"",
        "nostep.step": b"hello\n",
        "syntax.step": header + b"DATA;\n#1=CARTESIAN_POINT('',(0.,0.,0.));\n#2=FOO(;;;\nENDSEC;\nEND-ISO-10303-21;\n",
    }
    expected = {"truncated.step": "truncated STEP file", "garbage.step": "corrupt STEP file (nothing in its DATA",
                "nodata.step": "empty STEP file", "zero.step": "empty file (0 bytes)",
                "nostep.step": "not a STEP file", "syntax.step": "corrupt STEP file (OCCT: syntax error)"}
    for name, content in cases.items():
        (tmp_path / name).write_bytes(content)
        msg = error_of(tmp_path / name)
        assert msg.startswith(f"{tmp_path / name}: ") and expected[name] in msg, msg


def test_a_cut_that_crashes_occt_is_one_clean_error(tmp_path, capfd):
    # OCCT's transfer segfaults on this cut of cylinder.step; the read runs in a child process
    path = cut(FIXTURES / "cylinder.step", tmp_path / "cyl60.step", 0.6)
    msg = error_of(path, allow_partial=True)
    assert msg.startswith(f"{path}: damaged STEP file: OCCT crashed transferring it (signal SIGSEGV)")
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def square_face_step(*, vector_is_a_direction: bool) -> str:
    """A 10 x 10 planar face as an open shell in a STEP file of our own; with ``vector_is_a_direction``
    the LINE of its first edge names a DIRECTION where STEP wants a VECTOR (a writer's slip that OCCT's
    load check passes and its transfer dereferences: a segmentation fault in OCCT 7.9 and 8.0)."""
    corners, steps = [(0, 0), (10, 0), (10, 10), (0, 10)], [(1, 0), (0, 1), (-1, 0), (0, -1)]
    data = ["#1=APPLICATION_CONTEXT('automotive_design');", "#2=CARTESIAN_POINT('',(0.,0.,0.));",
            "#3=DIRECTION('',(0.,0.,1.));", "#4=DIRECTION('',(1.,0.,0.));", "#5=AXIS2_PLACEMENT_3D('',#2,#3,#4);",
            "#6=PLANE('',#5);"]
    n, points, uses = 10, [], []
    for x, y in corners:
        data += [f"#{n}=CARTESIAN_POINT('',({x}.,{y}.,0.));", f"#{n + 1}=VERTEX_POINT('',#{n});"]
        points.append(n)
        n += 2
    for k, (dx, dy) in enumerate(steps):
        start, end = points[k], points[(k + 1) % 4]
        vector = n if vector_is_a_direction and k == 0 else n + 1
        data += [f"#{n}=DIRECTION('',({dx}.,{dy}.,0.));", f"#{n + 1}=VECTOR('',#{n},10.);",
                 f"#{n + 2}=LINE('',#{start},#{vector});",
                 f"#{n + 3}=EDGE_CURVE('',#{start + 1},#{end + 1},#{n + 2},.T.);",
                 f"#{n + 4}=ORIENTED_EDGE('',*,*,#{n + 3},.T.);"]
        uses.append(f"#{n + 4}")
        n += 5
    data += [f"#{n}=EDGE_LOOP('',({','.join(uses)}));", f"#{n + 1}=FACE_OUTER_BOUND('',#{n},.T.);",
             f"#{n + 2}=ADVANCED_FACE('',(#{n + 1}),#6,.T.);", f"#{n + 3}=OPEN_SHELL('',(#{n + 2}));",
             f"#{n + 4}=SHELL_BASED_SURFACE_MODEL('',(#{n + 3}));",
             "#100=PRODUCT_CONTEXT('',#1,'mechanical');", "#101=PRODUCT('p','p','',(#100));",
             "#102=PRODUCT_DEFINITION_FORMATION('','',#101);",
             "#103=PRODUCT_DEFINITION_CONTEXT('part definition',#1,'design');",
             "#104=PRODUCT_DEFINITION('','',#102,#103);", "#105=PRODUCT_DEFINITION_SHAPE('','',#104);",
             "#106=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));",
             "#107=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));",
             "#108=(NAMED_UNIT(*)SI_UNIT($,.STERADIAN.)SOLID_ANGLE_UNIT());",
             "#109=UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-07),#106,'distance_accuracy_value','');",
             "#110=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#109))"
             "GLOBAL_UNIT_ASSIGNED_CONTEXT((#106,#107,#108))REPRESENTATION_CONTEXT('',''));",
             f"#111=MANIFOLD_SURFACE_SHAPE_REPRESENTATION('',(#{n + 4}),#110);",
             "#112=SHAPE_DEFINITION_REPRESENTATION(#105,#111);"]
    return ("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('p','',(''),(''),'','','');\n"
            "FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n"
            + "\n".join(data) + "\nENDSEC;\nEND-ISO-10303-21;\n")


@pytest.mark.parametrize("how", ["fork", "fork, polled", "new child"])
def test_a_file_whose_transfer_crashes_occt_is_one_clean_error(tmp_path, capfd, monkeypatch, how):
    """OCCT's load check passes the file and its transfer crashes: every reading runs in another
    process (a fork of this one, waited for on a pidfd or, without one, polled; where forking is unsafe
    a new child), so the caller gets one line instead of dying. The sound twin loads the same way."""
    from cadedge.occt import isolate

    monkeypatch.setattr(isolate, "can_fork", lambda: how != "new child")
    if how == "fork, polled":
        monkeypatch.delattr(os, "pidfd_open", raising=False)
    bad, good = tmp_path / "bad.step", tmp_path / "good.step"
    bad.write_text(square_face_step(vector_is_a_direction=True))
    good.write_text(square_face_step(vector_is_a_direction=False))
    msg = error_of(bad)
    assert msg == f"{bad}: malformed STEP file: OCCT crashed transferring it (signal SIGSEGV), though its load " \
                  "check found nothing wrong"
    grid = cadedge.refine_shape(good, ald=1e-2)
    assert len(grid.edges) == 4 and grid.faces == 1
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert main(["refine", str(bad), "-o", str(tmp_path / "bad.json")]) == 2
    err = capfd.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "OCCT crashed transferring it (signal SIGSEGV)" in err[0]
    assert not (tmp_path / "bad.json").exists()


def test_cli_refine_refuses_then_allows(tmp_path, capsys):
    path = cut(FIXTURES / "spline_prism.step", tmp_path / "prism.step", 0.9)
    out = tmp_path / "o.json"
    assert main(["refine", str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"cadedge refine: error: {path}: partial transfer refused: ")
    assert not out.exists()
    assert main(["refine", str(path), "--allow-partial", "-o", str(out), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert f"cadedge refine: {path}: warning: partial transfer: " in err and "of 6 faces" in err
    doc = json.loads(out.read_text())
    assert doc["summary"]["edges"] > 0  # the faces left still bound every edge


def test_cli_info_and_mesh_refuse_then_allow(tmp_path, capsys):
    pytest.importorskip("gmsh")
    # the prism, not the bracket: the bracket's cut leaves a face gmsh cannot import, whose retries cost
    # four times the mesh of the rest, and this test is about the refusal and the warning
    path = cut(FIXTURES / "spline_prism.step", tmp_path / "p.step", 0.9)
    assert main(["info", str(path)]) == 2
    assert "partial transfer refused" in capsys.readouterr().err
    assert main(["info", str(path), "--allow-partial"]) == 0
    assert f"cadedge info: {path}: warning: partial transfer: " in capsys.readouterr().err
    out = tmp_path / "m.msh"
    assert main(["mesh", str(path), "--ald", "1e-2", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "partial transfer refused" in err[0] and not out.exists()
    main(["mesh", str(path), "--ald", "1e-2", "--allow-partial", "-o", str(out), "--quiet"])
    assert f"cadedge mesh: {path}: warning: partial transfer: " in capsys.readouterr().err


def test_batch_fails_a_partial_file_unless_allowed(tmp_path):
    pytest.importorskip("distributed")
    from cadedge.batch import run_batch

    src = tmp_path / "in"
    src.mkdir()
    cut(FIXTURES / "spline_prism.step", src / "prism.step", 0.9)
    (src / "good.step").write_bytes((FIXTURES / "cylinder.step").read_bytes())
    report = run_batch([src], tmp_path / "out", ald=1e-2, workers=1)
    status = {Path(r.input).name: r for r in report.results}
    assert status["good.step"].status == "ok" and status["prism.step"].status == "failed"
    assert "partial transfer refused" in status["prism.step"].error
    again = run_batch([src], tmp_path / "out", ald=1e-2, workers=1, allow_partial=True)
    status = {Path(r.input).name: r for r in again.results}
    assert status["prism.step"].status == "ok"
    assert any(w.startswith("partial transfer: ") for w in status["prism.step"].warnings)


@pytest.mark.skipif(not CORPUS_STEP, reason=f"no third-party STEP corpus at {CORPUS} (set CADEDGE_CORPUS)")
@pytest.mark.parametrize("i", range(len(CORPUS_STEP)), ids=[p.name for p in CORPUS_STEP])
def test_cut_corpus_files_are_never_taken_whole(tmp_path, i):
    """Every corpus file cut short at 90% and re-closed (every other one inside an entity) is refused
    with one line: never a silent success, never a crash. One test per file, so that pytest-xdist
    spreads them (each cut file is transferred in a child process)."""
    src = CORPUS_STEP[i]
    path = cut(src, tmp_path / f"{src.stem}.step", 0.9, mid_entity=bool(i % 2))
    msg = error_of(path)
    assert msg.startswith(f"{path}: ") and any(
        k in msg for k in ("partial transfer refused", "corrupt STEP file", "damaged STEP file")), msg
