"""Time ``cadedge mesh`` on large parts in one gmsh process and in several at once (``--workers``).

Each run is ``cadedge mesh MODEL --ald EPS --workers N --timeout T -o <tmp>.msh --report <tmp>.json`` in
its own process, one after the other (the runs must not share the CPUs they are timed on). Per run: the
wall-clock seconds, the faces meshed of all, the triangles, the worst face's area deficit, the smallest
angle and the share of triangles under 20 degrees (from the report), and whether the joined mesh passed
the watertight check (exit code 0). Printed as the markdown table of docs/mesh.md:

    python scripts/large_models.py large
    python scripts/bench_mesh_workers.py large/plate_225.step:1e-3 large/heat_sink.step:1e-2 --workers 1 2

A model's parts are ``PATH:EPS``; ``--timeout`` (default 900) lets the one-process runs finish too.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run(path: str, eps: float, workers: int, timeout: float) -> dict:
    """One ``cadedge mesh`` run in a child process; its record."""
    with tempfile.TemporaryDirectory() as tmp:
        report = Path(tmp) / "report.json"
        cmd = [sys.executable, "-m", "cadedge", "mesh", path, "--ald", str(eps), "--workers", str(workers),
               "--timeout", str(timeout), "--quiet", "-o", str(Path(tmp) / "mesh.msh"), "--report", str(report)]
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True,
                              env={**os.environ, "PYTHONPATH": str(ROOT)})
        seconds = time.perf_counter() - t0
        rec = {"model": Path(path).stem, "eps": eps, "workers": workers, "seconds": seconds, "exit": proc.returncode}
        if report.exists():
            data = json.loads(report.read_text())
            faces = data["faces"]
            rec.update(faces=len(faces), meshed=sum(1 for f in faces if f["triangles"]), triangles=data["triangles"],
                       worst=data["worst_area_deficit"], min_angle=data["min_angle"], below_20=data["below_20"])
        else:
            rec["error"] = (proc.stderr.strip().splitlines() or ["no report"])[-1]
    return rec


def row(rec: dict, base: dict | None) -> str:
    if "faces" not in rec:
        return f"| {rec['model']} | {rec['eps']:g} | {rec['workers']} | {rec['seconds']:.0f} | {rec.get('error')} |||||"
    speed = f"{base['seconds'] / rec['seconds']:.2f}x" if base else ""
    return (f"| {rec['model']} | {rec['eps']:g} | {rec['workers']} | {rec['seconds']:.0f} | {speed} | "
            f"{rec['meshed']}/{rec['faces']} | {rec['triangles']} | {rec['worst']:.2g} | {rec['min_angle']:.1f} | "
            f"{100 * rec['below_20']:.2f} | {rec['exit']} |")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("models", nargs="+", metavar="PATH:EPS")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--timeout", type=float, default=900.0)
    args = ap.parse_args(argv)
    print("| model | EPS | workers | s | speed-up | faces meshed | triangles | worst face | min angle | % < 20 deg "
          "| exit |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for spec in args.models:
        path, _, eps = spec.rpartition(":")
        base = None
        for workers in args.workers:
            rec = run(path, float(eps), workers, args.timeout)
            base = base or rec
            print(row(rec, base if workers != args.workers[0] else None), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
