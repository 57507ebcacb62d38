"""Robustness benchmark of ``cadedge mesh``: every corpus file, fixture and hard model at several ALDs.

Each run is ``mesh_shape(model, ald=EPS, mode=MODE, output=<tmp>.msh, timeout=T)`` in its own Python
process (``--one``), itself under an outer time limit: gmsh is already isolated by cadedge, so the outer
limit only catches a hang or crash that *reached the caller* (counted, and a target of 0). Per run:
the exit code the CLI would give (0 ok, 1 faces failed / crash / timeout, 2 bad input), faces meshed of
total, hangs and crashes cadedge contained, the minimum angle, the share of triangles under 10 degrees,
the time, whether the hard timeout ended it, and the lines on its stderr that do not name the file
(native OCCT or gmsh output, tracebacks: ``cadedge mesh`` would print them unnamed). Results are appended to a JSON-lines file as they finish (a long run can be stopped and
its table still made), then printed as the markdown table of docs/mesh.md:

    python scripts/bench_mesh.py --ald 1e-1 1e-2 1e-3 --jsonl bench_mesh.jsonl
    python scripts/bench_mesh.py --table bench_mesh.jsonl      # the table of an earlier (partial) run

Models: the third-party corpus (``$CADEDGE_CORPUS``, else the corpus folder next to the repository, as
in the tests), the fixtures with faces, and the hard models of ``scripts/hard_models.py`` (written to a
temporary folder).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from corpus_path import find_corpus, step_files  # noqa: E402

#: The fixture with loose edges only: `mesh` rightly calls it bad input (no faces), so it is not a run.
NO_FACES = {"helix_wire.step"}


def default_models(hard_dir: Path) -> list[tuple[str, Path]]:
    """(group, path) of every corpus file, fixture with faces and hard model (written into ``hard_dir``)."""
    import hard_models

    corpus = step_files(find_corpus())
    fixtures = sorted(p for p in (ROOT / "fixtures").glob("*.step") if p.name not in NO_FACES)
    hard = [hard_models.write_model(name, hard_dir) for name in hard_models.NAMES]
    return [("corpus", p) for p in corpus] + [("fixture", p) for p in fixtures] + [("hard", p) for p in hard]


def one(path: Path, ald: float, mode: str, timeout: float) -> dict:
    """Mesh one model in this process; the record of the run."""
    from cadedge.errors import CadedgeError, InputError
    from cadedge.mesh import mesh_shape

    t0 = time.perf_counter()
    rec = {"model": path.name, "ald": ald, "mode": mode}
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings(record=True):  # as the CLI: recorded
        try:
            r = mesh_shape(path, ald=ald, mode=mode, output=Path(tmp) / "out.msh", timeout=timeout)
        except CadedgeError as exc:
            rec.update(exit=2 if isinstance(exc, InputError) else 1, error=str(exc), seconds=time.perf_counter() - t0)
            return rec
        written = r.output is not None and r.output.exists()
    faces = r.grid.faces
    failed = {f.face for f in r.failures}
    contained = [n for n in r.notes if "hung" in n or "crashed" in n] + ([r.error] if r.error else [])
    rec.update(exit=0 if r.ok else 1, faces=faces, meshed=faces - len(failed), written=written,
               contained=len(contained), contained_what=contained[:3], error=r.error,
               hard_timeout=any("was stopped" in n for n in r.notes),
               failures=[f.line() for f in r.failures][:5],
               min_angle=r.check.min_angle_deg if r.check else None,
               under10=100 * r.check.small_angle_share if r.check else None,
               triangles=len(r.triangles), check_ok=bool(r.check and r.check.ok),
               seconds=time.perf_counter() - t0)
    return rec


def geo(path: Path, ald: float, timeout: float) -> dict:
    """The ``.geo`` spacing export meshed by the ``gmsh`` executable (``gmsh part.geo -2``) under ``timeout``."""
    from cadedge.mesh import mesh_shape

    exe = str(Path(sys.executable).with_name("gmsh"))  # the gmsh wheel's launcher, run by this Python
    rec = {"model": path.name, "ald": ald, "mode": "geo"}
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        mesh_shape(path, ald=ald, output=Path(tmp) / "part.geo")
        cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        try:
            done = subprocess.run([sys.executable, exe, "part.geo", "-2", "-o", "part.msh"], cwd=tmp,
                                  capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            rec.update(exit=None, escaped=f"gmsh part.geo -2: no result within {timeout:g} s",
                       seconds=time.perf_counter() - t0)
            return rec
        errors = [ln for ln in done.stdout.splitlines() + done.stderr.splitlines() if "Error" in ln]
        cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)  # gmsh's own CPU time: the machine may be loaded
        rec.update(exit=done.returncode, written=(Path(tmp) / "part.msh").exists(), error="; ".join(errors[:2]),
                   seconds=time.perf_counter() - t0,
                   gmsh_cpu=cpu1.ru_utime + cpu1.ru_stime - cpu0.ru_utime - cpu0.ru_stime)
        if rec["written"]:
            rec.update(_msh_faces(Path(tmp) / "part.msh"))
    return rec


def _msh_faces(path: Path) -> dict:
    """Faces (surface entities) of a .msh and how many carry triangles; min angle and % under 10 degrees."""
    import gmsh
    import numpy as np

    from cadedge.mesh.check import check_triangles
    from cadedge.mesh.readback import read_mesh

    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        surfaces = [t for _, t in gmsh.model.getEntities(2)]
        raw = read_mesh(surfaces)
    finally:
        gmsh.finalize()
    check = check_triangles(raw.nodes, raw.triangles)
    return {"faces": len(surfaces), "meshed": len(np.unique(raw.triangle_surfaces)),
            "min_angle": check.min_angle_deg, "under10": 100 * check.small_angle_share,
            "triangles": len(raw.triangles)}


def run_isolated(path: Path, ald: float, mode: str, timeout: float) -> dict:
    """:func:`one` in a child Python under an outer limit; an escape past cadedge's own limits is recorded."""
    cmd = [sys.executable, __file__, "--one", str(path), "--ald", repr(ald), "--mode", mode,
           "--timeout", repr(timeout)]
    t0 = time.perf_counter()
    outer = 2 * timeout + 300  # refinement and start-up on a loaded machine, plus cadedge's own limit
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=outer)
    except subprocess.TimeoutExpired:
        return {"model": path.name, "ald": ald, "mode": mode, "exit": None, "escaped": f"hang past {outer:g} s",
                "seconds": time.perf_counter() - t0}
    lines = [ln for ln in done.stdout.splitlines() if ln.startswith("{")]
    if done.returncode != 0 or not lines:
        tail = (done.stderr.strip().splitlines() or [""])[-1][:200]
        return {"model": path.name, "ald": ald, "mode": mode, "exit": None,
                "escaped": f"caller died with code {done.returncode}: {tail}", "seconds": time.perf_counter() - t0}
    rec = json.loads(lines[-1])
    # what reached stderr outside cadedge's own lines (native OCCT or gmsh output, tracebacks): the CLI would
    # print it too, without the input file's name
    stray = [ln for ln in done.stderr.splitlines() if ln.strip() and path.name not in ln]
    rec.update(stray_stderr=len(stray), stray_what=stray[:3])
    return rec


def _fmt(x, spec: str) -> str:
    return "-" if x is None else format(x, spec)


def table(records: list[dict]) -> list[str]:
    """The markdown table and the totals line."""
    out = ["| group | model | ALD | mode | exit | faces meshed | contained hangs/crashes | min angle | % < 10 deg "
           "| s |", "|---|---|---:|---|---:|---:|---:|---:|---:|---:|"]
    for r in records:
        faces = f"{r['meshed']}/{r['faces']}" if "faces" in r else "-"
        exit_ = r["exit"] if r.get("exit") is not None else f"ESCAPED ({r.get('escaped')})"
        out.append(f"| {r.get('group', '')} | {r['model']} | {r['ald']:g} | {r['mode']} | {exit_} | {faces} | "
                   f"{r.get('contained', 0)} | {_fmt(r.get('min_angle'), '.1f')} | {_fmt(r.get('under10'), '.2f')} | "
                   f"{r['seconds']:.1f} |")
    meshed = sum(r.get("meshed", 0) for r in records)
    total = sum(r.get("faces", 0) for r in records)
    escaped = sum(1 for r in records if r.get("exit") is None)
    exit2 = sum(1 for r in records if r.get("exit") == 2)
    no_mesh = sum(1 for r in records if not r.get("written"))
    contained = sum(r.get("contained", 0) for r in records)
    stray = sum(r.get("stray_stderr", 0) for r in records)
    share = 100.0 * meshed / total if total else float("nan")
    out.append("")
    out.append(f"{len(records)} runs: faces meshed {meshed}/{total} ({share:.2f}%); exit 0 in "
               f"{sum(1 for r in records if r.get('exit') == 0)}, exit 1 in "
               f"{sum(1 for r in records if r.get('exit') == 1)}, exit 2 in {exit2}; hangs/crashes contained "
               f"{contained}, reaching the caller {escaped}; runs without a mesh {no_mesh}; stderr lines not naming "
               f"the file {stray}")
    return out


def _selects(name: str, path: Path, models: list[tuple[str, Path]]) -> bool:
    """``--only NAME``: the model whose file name or stem is NAME if there is one (``sphere`` is not
    ``boxed_sphere``), else every model whose file name contains NAME."""
    if any(name in (p.name, p.stem) for _, p in models):
        return name in (path.name, path.stem)
    return name in path.name


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="*", type=Path, help="STEP files (default: corpus, fixtures, hard models)")
    parser.add_argument("--ald", type=float, nargs="+", default=[1e-1, 1e-2, 1e-3])
    parser.add_argument("--mode", nargs="+", default=["nodes"], choices=["nodes", "sizes", "geo"],
                        help="geo: the .geo export meshed by `gmsh part.geo -2` (gmsh's own process)")
    parser.add_argument("--timeout", type=float, default=300.0, help="cadedge mesh --timeout per run")
    parser.add_argument("--jsonl", type=Path, help="append each run's record here as it finishes")
    parser.add_argument("--table", type=Path, help="print the table of an earlier run's JSON lines and stop")
    parser.add_argument("--only", nargs="+", metavar="NAME",
                        help="run only these default models: a file name or stem selects that model, anything else "
                        "every model whose file name contains it (e.g. T106)")
    parser.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        run = geo if args.mode[0] == "geo" else lambda p, a, t: one(p, a, args.mode[0], t)
        print(json.dumps(run(args.models[0], args.ald[0], args.timeout)))
        return 0
    if args.table:
        records = [json.loads(ln) for ln in args.table.read_text().splitlines() if ln.strip()]
        print("\n".join(table(records)))
        return 0
    with tempfile.TemporaryDirectory(prefix="hard-models-") as hard:
        models = [("", p) for p in args.models] if args.models else default_models(Path(hard))
        if args.only:
            models = [(g, p) for g, p in models if any(_selects(n, p, models) for n in args.only)]
        records = []
        for ald in args.ald:
            for mode in args.mode:
                for group, path in models:
                    rec = run_isolated(path, ald, mode, args.timeout)
                    rec["group"] = group
                    records.append(rec)
                    if args.jsonl:
                        with open(args.jsonl, "a") as f:
                            f.write(json.dumps(rec) + "\n")
                    print(table([rec])[2], flush=True)
    print("\n".join(table(records)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
