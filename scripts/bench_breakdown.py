"""Where ``refine_shape``'s time goes, per phase, against one OCCT pass at the tuned angle.

    python scripts/bench_breakdown.py [--eps 1e-3] [--repeats 7] [--cpu] [--all | --file PATH ...]

For each model (default: the corpus's two largest, ``917_fusee`` and ``boxed_sphere``; ``--all``: every
corpus model, with a total), OCCT's angle is tuned as ``scripts/bench.py`` does; then, interleaved
``--repeats`` times so that a load on the machine falls on all alike, and reported as medians of wall
time, or with ``--cpu`` of the process's CPU time (``time.process_time``: on a machine shared with other
jobs, wall time mostly measures the wait for a core):

- **OCCT**: one ``GCPnts_TangentialDeflection`` pass at that angle over every non-degenerate edge
  (adaptors included), as *OCCT s* in ``scripts/bench.py``;
- **refine_shape**: the whole call on the loaded shape, as *cadedge s* there;
- its phases, each run again on its own: **topology** (``Topology``), of which **dump** (OCCT writing the
  shape and ``cadedge/_shapedump.c`` parsing it, ``shapedump.read``) is also timed alone; **edge table**
  (every edge's curve row, its length and the check against OCCT, ``EdgeTable``), of which **check** is the
  table's time less that of a table built without its check on a fresh topology (so it includes the OCCT
  edges and adaptors only the check builds) and **lengths** (``cadedge/_lengths.c``'s quadrature on the rows
  it integrates: ellipses, hyperbolas, splines) is timed alone; and **compiled refine** (``refine_table`` on all
  rows); **rest** is the whole call minus topology, table and compiled refine (the tolerance scan, the
  per-edge grid objects, vertex spacings).
"""

from __future__ import annotations

import argparse
import contextlib
import statistics
import time
from pathlib import Path

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.GCPnts import GCPnts_TangentialDeflection
from OCP.GeomAbs import GeomAbs_Circle, GeomAbs_Line

import bench
import corpus_path
from corpus_path import require_corpus

from cadedge import kernels
from cadedge.occt import shapedump
from cadedge.occt.edgetable import EdgeTable, refine_table
from cadedge.occt.shape import refine_shape
from cadedge.occt.topology import Topology

LARGEST = ("live-clones__gmsh__917_fusee.stp", "LLNL__axom_data__boxed_sphere.step")
PHASES = ("OCCT", "refine_shape", "topology", "dump", "edge table", "unchecked table", "lengths", "compiled refine")


@contextlib.contextmanager
def _unchecked():
    """EdgeTable without its check against OCCT (to time the check by difference)."""
    check = EdgeTable._check
    EdgeTable._check = lambda self: None
    try:
        yield
    finally:
        EdgeTable._check = check


def breakdown(path: Path, eps: float, repeats: int, clock=time.perf_counter) -> tuple[int, dict[str, float]]:
    model = bench.Model(path)
    angle = bench.run_occt(model, eps)["angle"]
    shape = model.loaded.shape
    refine_shape(shape, ald=eps)  # untimed: what a first call loads
    times: dict[str, list[float]] = {k: [] for k in PHASES}

    def timed(name, fn):
        t0 = clock()
        out = fn()
        times[name].append(clock() - t0)
        return out

    def occt():
        for edge in model.edges:
            td = GCPnts_TangentialDeflection(BRepAdaptor_Curve(edge), angle, bench.HUGE, 2)
            for k in range(1, td.NbPoints() + 1):
                td.Value(k)

    for _ in range(repeats):
        timed("OCCT", occt)
        timed("refine_shape", lambda: refine_shape(shape, ald=eps))
        topo = timed("topology", lambda: Topology(shape))
        timed("dump", lambda: shapedump.read(shape))
        rows = topo.non_degenerate()
        table = timed("edge table", lambda: EdgeTable(topo.edges, rows, topo.dump))
        fresh = Topology(shape)  # its OCCT edges not built yet, as in a refine_shape call
        with _unchecked():
            timed("unchecked table", lambda: EdgeTable(fresh.edges, rows, fresh.dump))
        curved = [r for r, kind in enumerate(table.kinds) if kind not in (GeomAbs_Line, GeomAbs_Circle)]
        timed("lengths", lambda: kernels.edge_lengths(table.kind, table.gofs, table.ints, table.gdata, table.hofs,
                                                      table.hdata, table.domain, curved))
        n = len(table)
        ends = np.zeros((n, 3))
        timed("compiled refine", lambda: refine_table(table, slice(0, n), np.full(n, eps), ends, ends))
    med = {k: statistics.median(v) for k, v in times.items()}
    unchecked = med.pop("unchecked table")
    rest = med["refine_shape"] - med["topology"] - med["edge table"] - med["compiled refine"]
    order = ("OCCT", "refine_shape", "topology", "dump", "edge table", "check", "lengths", "compiled refine", "rest")
    med = {**med, "check": med["edge table"] - unchecked, "rest": rest}
    return len(model.edges), {k: med[k] for k in order}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--eps", type=float, default=1e-3)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--cpu", action="store_true", help="CPU time of the process instead of wall time")
    which = ap.add_mutually_exclusive_group()
    which.add_argument("--all", action="store_true", help="every corpus model, and the totals")
    which.add_argument("--file", nargs="+", type=Path, help="these STEP files instead of the two largest corpus models")
    args = ap.parse_args()
    paths = args.file or (corpus_path.step_files(require_corpus()) if args.all
                          else [require_corpus() / name for name in LARGEST])
    clock = time.process_time if args.cpu else time.perf_counter
    print(f"| model | phase | ms ({'CPU' if args.cpu else 'wall'}) | us/edge | x OCCT pass |")
    print("|---|---|---:|---:|---:|")
    totals: dict[str, float] = {}
    for path in paths:
        edges, med = breakdown(path, args.eps, args.repeats, clock)
        for name, seconds in med.items():
            totals[name] = totals.get(name, 0.0) + seconds
            label = f"{path.name} ({edges} edges)" if name == "OCCT" else ""
            print(f"| {label} | {name} | {seconds * 1e3:.1f} | {seconds / edges * 1e6:.1f} | "
                  f"{seconds / med['OCCT']:.2f} |", flush=True)
    if len(paths) > 1:
        for name, seconds in totals.items():
            print(f"| {'**total**' if name == 'OCCT' else ''} | {name} | {seconds * 1e3:.1f} | | "
                  f"{seconds / totals['OCCT']:.2f} |")


if __name__ == "__main__":
    main()
