"""Compare ``cadedge.mesh.mesh_shape`` with gmsh meshing the same STEP file with its own edge meshing.

Per model: triangles, minimum angle, seconds, watertight (cadedge's check on both meshes), for

- cadedge: ``mesh_shape(path, ald=ALD)`` (refinement included in the time; edge grids imposed);
- gmsh: ``gmsh.open(path)`` then ``generate(2)`` with curvature-based sizes at the same deficit
  (``Mesh.MeshSizeFromCurvature`` = segments per full circle giving that ALD, ``2 pi / sqrt(24 ALD)``)
  and ``Mesh.MeshSizeMax`` = the largest cadedge edge spacing, so both aim at comparable sizes.

Prints a markdown table (the one in docs/mesh.md):

    python scripts/bench_mesh.py --ald 1e-2 --timeout 300

gmsh alone runs in a child process with a time limit (a hang or crash costs one row).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import gmsh
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cadedge.errors import CadedgeError  # noqa: E402
from cadedge.mesh import mesh_shape  # noqa: E402
from cadedge.mesh.check import check_triangles  # noqa: E402

from corpus_path import require_corpus, step_files  # noqa: E402


def default_models() -> list[Path]:
    """Four fixtures and every corpus file (the table in docs/mesh.md)."""
    fixtures = [ROOT / "fixtures" / f"{n}.step" for n in ("bracket", "cylinder", "sphere", "two_solids")]
    return fixtures + step_files(require_corpus())


def gmsh_own(path: Path, ald: float, max_size: float) -> dict:
    """gmsh alone: its STEP import, its edge meshing, curvature sizes for the same ALD."""
    t0 = time.perf_counter()
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", math.ceil(2 * math.pi / math.sqrt(24 * ald)))
        gmsh.option.setNumber("Mesh.MeshSizeMax", max_size)
        gmsh.open(str(path))
        error = ""
        try:
            gmsh.model.mesh.generate(2)
        except Exception as exc:  # gmsh's bare Exception: record it, measure what was meshed
            error = str(exc).splitlines()[0][:60]
        tags, coords, _ = gmsh.model.mesh.getNodes()
        tris = []
        for _, s in gmsh.model.getEntities(2):
            tris.append(np.asarray(gmsh.model.mesh.getElementsByType(2, s)[1], dtype=np.int64).reshape(-1, 3))
    finally:
        gmsh.finalize()
    seconds = time.perf_counter() - t0
    tags = np.asarray(tags, dtype=np.int64)
    lookup = np.zeros(tags.max() + 1, dtype=np.int64)
    lookup[tags] = np.arange(len(tags))
    tri = lookup[np.vstack(tris)] if tris else np.zeros((0, 3), dtype=np.int64)
    check = check_triangles(np.asarray(coords).reshape(-1, 3), tri)
    return {"triangles": len(tri), "min_angle": check.min_angle_deg, "seconds": seconds,
            "watertight": _closed(check), "error": error}


def gmsh_own_isolated(path: Path, ald: float, max_size: float, timeout: float) -> dict:
    """:func:`gmsh_own` in a child process, so a gmsh hang or crash costs one row, not the run."""
    cmd = [sys.executable, __file__, "--gmsh-only", str(path), "--ald", repr(float(ald)),
           "--max-size", repr(float(max_size))]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"triangles": "-", "min_angle": float("nan"), "seconds": timeout, "watertight": "-",
                "error": f"no result within {timeout:g} s"}
    if done.returncode != 0:
        return {"triangles": "-", "min_angle": float("nan"), "seconds": float("nan"), "watertight": "-",
                "error": f"gmsh exited with {done.returncode}"}
    return json.loads(done.stdout.strip().splitlines()[-1])


def _closed(check) -> str:
    closed = sum(s.watertight for s in check.shells)
    return f"{closed}/{len(check.shells)}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="*", type=Path, help="STEP files (default: four fixtures and the corpus)")
    parser.add_argument("--ald", type=float, default=1e-2)
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds allowed to gmsh alone per model")
    parser.add_argument("--gmsh-only", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--max-size", type=float, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.gmsh_only:
        print(json.dumps(gmsh_own(args.models[0], args.ald, args.max_size)))
        return 0
    print(f"ALD {args.ald:g}; gmsh Mesh.MeshSizeFromCurvature = "
          f"{math.ceil(2 * math.pi / math.sqrt(24 * args.ald))}; times include STEP reading\n")
    print("| model | cadedge triangles | min angle | s | closed shells | check | gmsh triangles | min angle | s "
          "| closed shells |")
    print("|---|---:|---:|---:|---:|---|---:|---:|---:|---:|")
    for path in args.models or default_models():
        t0 = time.perf_counter()
        try:
            r = mesh_shape(path, ald=args.ald)
        except CadedgeError as exc:
            print(f"| {path.name} | error: {exc} | | | | | | | | |")
            continue
        ours_s = time.perf_counter() - t0
        spacing = max(max(e.segment_lengths) for e in r.grid.edges if not e.degenerate)
        theirs = gmsh_own_isolated(path, args.ald, spacing, args.timeout)
        verdict = "ok" if r.ok else f"{len(r.failures)} faces failed" if r.failures else "FAILED"
        note = f" ({theirs['error']})" if theirs["error"] else ""
        print(f"| {path.name} | {len(r.triangles)} | {r.check.min_angle_deg:.1f} | {ours_s:.1f} | "
              f"{_closed(r.check)} | {verdict} | {theirs['triangles']} | {theirs['min_angle']:.1f} | "
              f"{theirs['seconds']:.1f} | {theirs['watertight']}{note} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
