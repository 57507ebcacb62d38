"""Shape benchmark: cadedge target mode against OCCT, gmsh and the per-edge sampled DP optimum.

    python scripts/bench.py [--eps 1e-2 1e-3 1e-4] [--quick] [--file PATH ...] [--no-gmsh] [--no-dp]
                            [--json OUT.json] [--from-json OUT.json] [--write] [--startup [REPEATS]]
                            [--batch [ROUNDS]]

For every model (the STEP corpus, found as ``scripts/corpus_path.py`` says, and ``fixtures/``; ``--quick`` a small subset)
and every ``eps``, in one process on the same loaded shape (STEP reading excluded everywhere):

- **cadedge**: ``refine_shape(shape, ald=eps)`` timed with ``time.perf_counter`` (topology included).
- **OCCT**: ``GCPnts_TangentialDeflection`` on every non-degenerate edge's ``BRepAdaptor_Curve``, with
  one angular deflection for the whole model found by bisection (log scale) as the largest that makes
  every edge meet ``eps``; the curvature (chordal) deflection is fixed at 1e100 so only the angle
  decides (an arc-length deficit is a matter of turning angle, not of size). *OCCT s* is one pass over
  all edges at the tuned angle; the tuning time is reported separately.
- **gmsh**: the same STEP file imported with ``gmsh.model.occ.importShapes``, 1-D mesh with
  ``Mesh.MeshSizeFromCurvature = N`` (elements per 2 pi), all other size sources off and
  ``Mesh.MinimumCurvePoints = Mesh.MinimumCirclePoints = 2``; ``N`` bisected as the smallest that
  makes every curve meet ``eps`` against ``gmsh.model.occ.getMass`` (its length). *gmsh s* is one
  ``generate(1)`` at the tuned ``N``.
- **DP**: the per-edge sampled optimum (``cadedge.yardsticks.optimum.sampled_optimum``), the fewest segments
  reaching ``(1 - eps) L`` with ``L`` OCCT's length; lines count 1 without sampling.

The achieved ALD of an edge is ``1 - polyline length / L``, ``L = GCPnts_AbscissaPoint::Length`` with
tolerance 1e-12 (the default one is off by a few 1e-6, which matters at eps 1e-4).
Degenerate edges are left out everywhere. A row passes when cadedge's worst edge meets ``eps``, its
segments are at most OCCT's and at most 1.10x the DP optimum, and its time is at most 3x one OCCT
pass. *time/tuning* puts cadedge's time against OCCT's whole tuning instead (what it costs OCCT to
reach the same per-model guarantee); it is reported, not judged.
``--startup`` first measures, per model, fresh-process ``cadedge info`` and ``cadedge refine --ald 1e-3``
against a Python that only imports OCP and reads the file (``scripts/startup.py``; targets 1.15x and 1.3x).
``--batch`` last runs ``cadedge batch``'s throughput over the corpus with one and two workers, ROUNDS
interleaved rounds (default 3), the shortest *run s* kept (``scripts/bench_batch.py``; target 3: two
workers at least 1.7x one, at most 10% per file beyond read + refine + write); it prints its table.
``--write`` puts the tables and figures into ``docs/performance.md`` / ``docs/figures/``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.GCPnts import GCPnts_AbscissaPoint, GCPnts_TangentialDeflection

from corpus_path import require_corpus, step_files

from cadedge.atomic import atomic_path, atomic_write_bytes
from cadedge.grid import polyline_length
from cadedge.occt.edgecurve import EdgeCurve
from cadedge.occt.reader import load_shape
from cadedge.occt.shape import refine_shape
from cadedge.occt.topology import Topology
from cadedge.yardsticks.optimum import sampled_optimum

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "fixtures"
DOC = ROOT / "docs" / "performance.md"
FIGURES = ROOT / "docs" / "figures"
BEGIN, END = "<!-- bench:begin -->", "<!-- bench:end -->"
STARTUP_BEGIN, STARTUP_END = "<!-- startup:begin -->", "<!-- startup:end -->"
QUICK = ("live-clones__gmsh__cube_filet.stp", "LLNL__axom_data__sliced_cylinder.step", "cylinder.step",
         "helix_wire.step")
DP_LIMIT, TIME_LIMIT = 1.10, 3.0
HUGE = 1e100
LENGTH_TOL = 1e-12  # GCPnts_AbscissaPoint's default tolerance leaves lengths off by a few 1e-6


def files(quick: bool) -> list[Path]:
    out = step_files(require_corpus())
    out += sorted(FIXTURES.glob("*.step"))
    return [p for p in out if p.name in QUICK] if quick else out


class Model:
    """A loaded shape with its non-degenerate edges, their adaptors and OCCT lengths."""

    def __init__(self, path: Path):
        self.path = path
        self.loaded = load_shape(path)
        topo = Topology(self.loaded.shape)
        self.ids = [i for i in range(len(topo.edges)) if not topo.is_degenerate(i)]
        self.edges = [topo.edges[i] for i in self.ids]
        self.kinds = [topo.curve_type(i) for i in self.ids]
        self.adaptors = [BRepAdaptor_Curve(e) for e in self.edges]
        self.lengths = np.array([GCPnts_AbscissaPoint.Length_s(a, LENGTH_TOL) for a in self.adaptors])


def run_cadedge(model: Model, eps: float) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        sg = refine_shape(model.loaded.shape, ald=eps)
        seconds = time.perf_counter() - t0
    edges = [sg.edges[i] for i in model.ids]
    lengths = np.array([e.length for e in edges])
    segs = sum(e.segments for e in edges)
    return dict(segments=int(segs), ald=float(np.max(1.0 - lengths / model.lengths)), seconds=seconds,
                evaluations=int(sum(e.evaluations for e in edges)),
                per_edge=[int(e.segments) for e in edges])


def occt_pass(model: Model, angle: float) -> tuple[list[int], float]:
    """Segments per edge and the worst ALD for one TangentialDeflection pass at ``angle``."""
    segs, worst = [], 0.0
    for ad, length in zip(model.adaptors, model.lengths):
        td = GCPnts_TangentialDeflection(ad, angle, HUGE, 2)
        n = td.NbPoints()
        pts = np.array([td.Value(k).Coord() for k in range(1, n + 1)])
        segs.append(n - 1)
        if length > 0:
            worst = max(worst, 1.0 - polyline_length(pts) / length)
    return segs, worst


def run_occt(model: Model, eps: float) -> dict:
    t0 = time.perf_counter()
    guess = math.sqrt(24.0 * eps)  # a chord turning by angle a misses about a**2 / 24 of an arc
    lo, hi = guess / 64.0, min(guess * 4.0, 3.0)  # lo meets eps, hi does not (checked below)
    best = None
    for a in (hi, lo):
        segs, worst = occt_pass(model, a)
        if worst <= eps:
            best = (a, segs, worst)
            break
    if best is not None and best[0] == lo:
        for _ in range(24):
            mid = math.sqrt(lo * hi)
            segs, worst = occt_pass(model, mid)
            if worst <= eps:
                lo, best = mid, (mid, segs, worst)
            else:
                hi = mid
            if hi / lo < 1.002:
                break
    tuning = time.perf_counter() - t0
    if best is None:
        return dict(segments=None, ald=None, seconds=None, tuning=tuning, angle=None, per_edge=None)
    angle = best[0]
    t0 = time.perf_counter()
    for edge in model.edges:  # the timed pass: what a user of the tuned angle pays, adaptors included
        td = GCPnts_TangentialDeflection(BRepAdaptor_Curve(edge), angle, HUGE, 2)
        for k in range(1, td.NbPoints() + 1):
            td.Value(k)
    seconds = time.perf_counter() - t0
    return dict(segments=int(sum(best[1])), ald=float(best[2]), seconds=seconds, tuning=tuning, angle=angle,
                per_edge=[int(s) for s in best[1]])


def run_dp(model: Model, eps: float) -> dict:
    t0 = time.perf_counter()
    total = 0
    for edge, kind, length in zip(model.edges, model.kinds, model.lengths):
        if kind == "Line":
            total += 1
            continue
        curve = EdgeCurve(edge)
        total += sampled_optimum(curve, curve.domain, (1.0 - eps) * float(length))
    return dict(segments=int(total), seconds=time.perf_counter() - t0)


class Gmsh:
    """gmsh's curvature-driven 1-D mesh of a STEP file, tuned to ``eps``."""

    def __init__(self, path: Path):
        import gmsh

        self.gmsh = gmsh
        gmsh.initialize(["-noenv"], readConfigFiles=False)
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(path.stem)
        gmsh.model.occ.importShapes(str(path))
        gmsh.model.occ.synchronize()
        lengths = {t: gmsh.model.occ.getMass(1, t) for _, t in gmsh.model.getEntities(1)}
        size = math.dist(*np.reshape(gmsh.model.getBoundingBox(-1, -1), (2, 3)))
        self.lengths = {t: v for t, v in lengths.items() if v > 1e-9 * size}  # degenerate curves left out
        self.curves = list(self.lengths)
        for name, value in (("Mesh.MeshSizeFromPoints", 0), ("Mesh.MeshSizeExtendFromBoundary", 0),
                            ("Mesh.MeshSizeMax", HUGE), ("Mesh.MeshSizeMin", 0),
                            ("Mesh.MinimumCurvePoints", 2), ("Mesh.MinimumCirclePoints", 2)):
            gmsh.option.setNumber(name, value)

    def mesh(self, n: int) -> tuple[int, float, float]:
        """Segments, worst ALD and seconds of one 1-D mesh at ``n`` elements per 2 pi."""
        g = self.gmsh
        g.model.mesh.clear()
        g.option.setNumber("Mesh.MeshSizeFromCurvature", n)
        t0 = time.perf_counter()
        g.model.mesh.generate(1)
        seconds = time.perf_counter() - t0
        tags, coords, _ = g.model.mesh.getNodes()
        xyz = np.zeros((int(tags.max()) + 1, 3))
        xyz[tags] = np.asarray(coords).reshape(-1, 3)
        segs, worst = 0, 0.0
        for t in self.curves:
            _, _, nodes = g.model.mesh.getElements(1, t)
            pairs = np.asarray(nodes[0], dtype=np.int64).reshape(-1, 2)
            segs += len(pairs)
            poly = float(np.linalg.norm(xyz[pairs[:, 1]] - xyz[pairs[:, 0]], axis=1).sum())
            worst = max(worst, 1.0 - poly / self.lengths[t])
        return segs, worst, seconds

    def tune(self, eps: float) -> dict:
        t0 = time.perf_counter()
        lo, hi = 1, 1
        while hi <= 1 << 16:  # doubling until eps is met, then bisection on the integer N
            if self.mesh(hi)[1] <= eps:
                break
            lo, hi = hi, 2 * hi
        else:
            return dict(segments=None, ald=None, seconds=None, tuning=time.perf_counter() - t0, n=None)
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if self.mesh(mid)[1] <= eps:
                hi = mid
            else:
                lo = mid
        segs, worst, seconds = self.mesh(hi)  # the tuned mesh afresh, timed on its own
        return dict(segments=segs, ald=worst, seconds=seconds, tuning=time.perf_counter() - t0, n=hi,
                    curves=len(self.curves))

    def close(self) -> None:
        self.gmsh.finalize()


def bench(paths: list[Path], eps_list: list[float], *, use_gmsh: bool, use_dp: bool) -> list[dict]:
    rows = []
    # Load what a first call loads once per process (the compiled kernels, numpy's lazy modules), as
    # OCCT's libraries are loaded before its first pass too: a sphere is refined untimed.
    refine_shape(Model(FIXTURES / "sphere.step").loaded.shape, ald=1e-2)
    for path in paths:
        model = Model(path)
        gm = Gmsh(path) if use_gmsh else None
        try:
            for eps in eps_list:
                row = dict(model=path.name, edges=len(model.ids), eps=eps,
                           cadedge=run_cadedge(model, eps), occt=run_occt(model, eps))
                row["gmsh"] = gm.tune(eps) if gm is not None else None
                row["dp"] = run_dp(model, eps) if use_dp else None
                rows.append(row)
                print(format_row(row), flush=True)
        finally:
            if gm is not None:
                gm.close()
    return rows


def verdict(row: dict) -> tuple[bool, list[str]]:
    c, o, d = row["cadedge"], row["occt"], row["dp"]
    miss = []
    if c["ald"] > row["eps"]:
        miss.append("ALD")
    if o["segments"] is not None and c["segments"] > o["segments"]:
        miss.append("seg>OCCT")
    if d is not None and c["segments"] > DP_LIMIT * d["segments"]:
        miss.append("seg>1.1DP")
    if o["seconds"] is not None and c["seconds"] > TIME_LIMIT * max(o["seconds"], 1e-9):
        miss.append("time>3xOCCT")
    return not miss, miss


def _num(x, fmt: str = "{}") -> str:
    return "-" if x is None else fmt.format(x)


HEADER = ("| model | edges | eps | cadedge seg | OCCT seg | gmsh seg | DP seg | seg/OCCT | seg/DP | cadedge ALD "
          "| OCCT ALD | gmsh ALD | cadedge s | OCCT s (tune s) | gmsh s | time/OCCT | time/tuning | evals/seg | misses |")
RULE = "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"


def format_row(row: dict) -> str:
    c, o, g, d = row["cadedge"], row["occt"], row["gmsh"] or {}, row["dp"] or {}
    ok, miss = verdict(row)
    r_o = c["segments"] / o["segments"] if o.get("segments") else None
    r_d = c["segments"] / d["segments"] if d.get("segments") else None
    r_t = c["seconds"] / o["seconds"] if o.get("seconds") else None
    r_tune = c["seconds"] / o["tuning"] if o.get("tuning") else None
    return (f"| {row['model']} | {row['edges']} | {row['eps']:g} | {c['segments']} | {_num(o['segments'])} "
            f"| {_num(g.get('segments'))} | {_num(d.get('segments'))} | {_num(r_o, '{:.3f}')} | {_num(r_d, '{:.3f}')} "
            f"| {c['ald']:.2e} | {_num(o['ald'], '{:.2e}')} | {_num(g.get('ald'), '{:.2e}')} | {c['seconds']:.3f} "
            f"| {_num(o['seconds'], '{:.3f}')} ({_num(o['tuning'], '{:.1f}')}) | {_num(g.get('seconds'), '{:.3f}')} "
            f"| {_num(r_t, '{:.1f}')} | {_num(r_tune, '{:.2f}')} | {c['evaluations'] / max(c['segments'], 1):.1f} | {'ok' if ok else ', '.join(miss)} |")


def totals(rows: list[dict]) -> list[str]:
    """One line per eps. Ratios to OCCT sum only the rows where OCCT met eps at some angle (the others
    are counted in the model column as "n without OCCT")."""
    out = []
    for eps in sorted({r["eps"] for r in rows}, reverse=True):
        rs = [r for r in rows if r["eps"] == eps]
        with_occt = [r for r in rs if r["occt"]["segments"] is not None]

        def tot(side: str, key: str, among: list[dict] = rs) -> float:
            return sum((r[side] or {}).get(key) or 0 for r in among)

        cs, ds, gs = tot("cadedge", "segments"), tot("dp", "segments"), tot("gmsh", "segments")
        cs_o, os_ = tot("cadedge", "segments", with_occt), tot("occt", "segments", with_occt)
        ct, ct_o = tot("cadedge", "seconds"), tot("cadedge", "seconds", with_occt)
        ot, tt = tot("occt", "seconds", with_occt), tot("occt", "tuning", with_occt)
        missing = f" ({len(rs) - len(with_occt)} without OCCT)" if len(with_occt) < len(rs) else ""
        ratio = lambda a, b, fmt: _num(a / b if b else None, fmt)  # noqa: E731
        out.append(f"| **total**{missing} | {sum(r['edges'] for r in rs)} | {eps:g} | {cs} | {os_} | {gs or '-'} "
                   f"| {ds or '-'} | {ratio(cs_o, os_, '{:.3f}')} | {ratio(cs, ds, '{:.3f}')} | | | | {ct:.2f} "
                   f"| {ot:.3f} | | {ratio(ct_o, ot, '{:.1f}')} | {ratio(ct_o, tt, '{:.2f}')} | "
                   f"| {sum(verdict(r)[0] for r in rs)}/{len(rs)} ok |")
    return out


def plot(rows: list[dict], prefix: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    eps_list = sorted({r["eps"] for r in rows}, reverse=True)
    models = list(dict.fromkeys(r["model"] for r in rows))
    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    x = np.arange(len(models))
    w = 0.8 / len(eps_list)
    for k, eps in enumerate(eps_list):
        by = {r["model"]: r for r in rows if r["eps"] == eps}
        seg = [by[m]["cadedge"]["segments"] / by[m]["occt"]["segments"] if by[m]["occt"]["segments"] else np.nan
               for m in models]
        dp = [by[m]["cadedge"]["segments"] / by[m]["dp"]["segments"] if by[m]["dp"] else np.nan for m in models]
        tim = [by[m]["cadedge"]["seconds"] / by[m]["occt"]["seconds"] if by[m]["occt"]["seconds"] else np.nan
               for m in models]
        axes[0].bar(x + k * w, seg, w, label=f"cadedge/OCCT eps={eps:g}")
        axes[0].plot(x + k * w, dp, "k_", markersize=10)
        axes[1].bar(x + k * w, tim, w, label=f"eps={eps:g}")
    axes[0].axhline(1.0, color="r", lw=0.8)
    axes[0].set_ylabel("segments ratio (bars: /OCCT, black ticks: /DP optimum)")
    axes[1].axhline(TIME_LIMIT, color="r", lw=0.8)
    axes[1].set_yscale("log")
    axes[1].set_ylabel("time ratio cadedge / OCCT (one pass)")
    for ax in axes:
        ax.set_xticks(x + 0.4 - w / 2)
        ax.set_xticklabels([m[:22] for m in models], rotation=60, ha="right", fontsize=7)
        ax.legend(fontsize=7)
    fig.tight_layout()
    main = prefix.with_name(prefix.name + ".png")
    with atomic_path(main) as tmp:
        fig.savefig(tmp, dpi=90, format="png")
    plt.close(fig)

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    for eps in eps_list:
        rs = [r for r in rows if r["eps"] == eps]
        e = [r["edges"] for r in rs]
        axes[0].loglog(e, [r["cadedge"]["seconds"] for r in rs], "o", label=f"cadedge eps={eps:g}")
        axes[0].loglog(e, [r["occt"]["seconds"] or np.nan for r in rs], "x", label=f"OCCT eps={eps:g}")
    axes[0].set_xlabel("non-degenerate edges")
    axes[0].set_ylabel("seconds")
    axes[0].legend(fontsize=7)
    for m in models:
        rs = sorted((r for r in rows if r["model"] == m), key=lambda r: r["eps"])
        axes[1].loglog([r["eps"] for r in rs], [r["cadedge"]["seconds"] for r in rs], "o-", label=m[:22])
    axes[1].set_xlabel("eps")
    axes[1].set_ylabel("cadedge seconds")
    axes[1].legend(fontsize=6)
    fig.tight_layout()
    scaling = prefix.with_name(prefix.name + "_scaling.png")
    with atomic_path(scaling) as tmp:
        fig.savefig(tmp, dpi=90, format="png")
    plt.close(fig)
    return [main, scaling]


def write_doc(table: str, begin: str = BEGIN, end: str = END) -> None:
    text = DOC.read_text()
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    atomic_write_bytes(DOC, (head + begin + "\n" + table + "\n" + end + tail).encode())


def startup_module():
    """scripts/startup.py (fresh-process start-up of ``cadedge info`` / ``refine`` against a plain read)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("cadedge_startup", Path(__file__).with_name("startup.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--eps", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    ap.add_argument("--quick", action="store_true", help="a small subset of models")
    ap.add_argument("--file", type=Path, nargs="+", help="these STEP files instead of corpus + fixtures")
    ap.add_argument("--no-gmsh", action="store_true")
    ap.add_argument("--no-dp", action="store_true")
    ap.add_argument("--json", type=Path, help="also write the raw rows as JSON")
    ap.add_argument("--from-json", type=Path, help="tabulate (and --write) rows saved by --json instead of running")
    ap.add_argument("--write", action="store_true", help="update docs/performance.md and docs/figures/performance*.png")
    ap.add_argument("--startup", type=int, metavar="REPEATS", nargs="?", const=3,
                    help="also the fresh-process start-up table (scripts/startup.py), each command run REPEATS "
                         "times (default 3)")
    ap.add_argument("--batch", type=int, metavar="ROUNDS", nargs="?", const=3,
                    help="also the batch throughput table (scripts/bench_batch.py) over the corpus, ROUNDS "
                         "interleaved rounds of one and two workers (default 3)")
    args = ap.parse_args(argv)
    paths = args.file or files(args.quick)
    startup_table = None
    if args.startup:  # first, while nothing else of this run is resident
        st = startup_module()
        startup_table = st.table(st.run(paths, args.startup))
        print()
    print(HEADER)
    print(RULE)
    if args.from_json:
        rows = json.loads(args.from_json.read_text())
        print("\n".join(format_row(r) for r in rows))
    else:
        rows = bench(paths, args.eps, use_gmsh=not args.no_gmsh, use_dp=not args.no_dp)
    tot = totals(rows)
    print("\n".join(tot))
    table = "\n".join([HEADER, RULE] + [format_row(r) for r in rows] + tot)
    if args.batch:  # fresh processes with their own clusters, after everything else of this run
        print("\ncadedge batch over the corpus, ald 1e-3 (target 3):")
        from bench_batch import table as batch_table  # a sibling, like corpus_path

        for line in batch_table(require_corpus(), 1e-3, [1, 2], args.batch):
            print(line, flush=True)
    if args.json:
        atomic_write_bytes(args.json, json.dumps(rows, indent=1).encode())
    if args.write:
        FIGURES.mkdir(parents=True, exist_ok=True)
        plot(rows, FIGURES / "performance")
        write_doc(table)
        if startup_table is not None:
            write_doc(startup_table, STARTUP_BEGIN, STARTUP_END)
    return 0 if all(verdict(r)[0] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
