"""Start-up benchmark: what a user waits for, in fresh processes, against reading the STEP file alone.

    python scripts/startup.py [--repeats 5] [--file PATH ...]

For every model (the corpus and ``fixtures/``), each command in its own fresh process:

- **read**: a Python that imports OCP and reads and transfers the STEP file (``STEPControl_Reader``:
  ``ReadFile``, ``TransferRoots``, ``OneShape``), the plain script the targets are measured against;
- **info**: ``cadedge info FILE``;
- **refine**: ``cadedge refine FILE --ald 1e-3 -o OUT.json``;
- **read0**: the same plain read, but importing OCP with the garbage collector off and then frozen, as
  the ``cadedge`` console script does (``cadedge/cli/_startup.py``). It is not a target's baseline;
  against it the ratios show what cadedge's own work costs, the collector's share aside.

After one untimed warm-up of each (the file in the page cache, bytecode written as an installed
package has it), every repeat runs the four commands of a model once, in an order rotated from repeat
to repeat, so a change of the machine's load falls on all of them alike. The time of a command is
its CPU time (user + system, ``getrusage`` of the child): on a machine whose cores are shared, wall
time mostly measures the wait for a core. Contention only ever adds CPU time (caches and memory
bandwidth shared with other jobs), so besides the **median** of the repeats, which is the figure
judged against the targets (*info/read* <= 1.15, *refine/read* <= 1.3), the table gives the ratio of
the **minima**, the least-disturbed run of each command. Wall-time medians are kept in the JSON rows.
``scripts/bench.py --startup`` runs this and adds the table to its output.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from corpus_path import find_corpus, step_files

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "fixtures"
INFO_LIMIT, REFINE_LIMIT = 1.15, 1.3
_READ = ("import sys\n"
         "{off}from OCP.STEPControl import STEPControl_Reader\n{on}"
         "reader = STEPControl_Reader()\n"
         "assert int(reader.ReadFile(sys.argv[1])) == 1\n"
         "reader.TransferRoots()\n"
         "reader.OneShape()\n")
READ = _READ.format(off="", on="")
READ_FROZEN = _READ.format(off="import gc\ngc.disable()\n", on="gc.freeze()\ngc.enable()\n")
ENTRY = "import sys; from cadedge.cli import entry; sys.argv[0] = 'cadedge'; entry()"
KINDS = ("read", "info", "refine", "read0")


def files() -> list[Path]:
    return step_files(find_corpus()) + sorted(FIXTURES.glob("*.step"))


def cadedge_command() -> list[str]:
    """The installed console script beside this Python, else the same entry point through ``-c``."""
    script = shutil.which("cadedge", path=str(Path(sys.executable).parent))
    return [script] if script else [sys.executable, "-c", ENTRY]


def _cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _env() -> dict[str, str]:
    """This environment, but with bytecode caching on, as an installed package has it."""
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def timed(cmd: list[str]) -> tuple[float, float]:
    """(wall, CPU) seconds of one run of ``cmd``."""
    c0, t0 = _cpu(), time.perf_counter()
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=_env())
    seconds, cpu = time.perf_counter() - t0, _cpu() - c0
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {done.returncode}: {done.stderr.strip()[-300:]}")
    return seconds, cpu


def commands(path: Path, out: str) -> dict[str, list[str]]:
    cad = cadedge_command()
    return {"read": [sys.executable, "-c", READ, str(path)], "info": cad + ["info", str(path)],
            "refine": cad + ["refine", str(path), "--ald", "1e-3", "-o", out],
            "read0": [sys.executable, "-c", READ_FROZEN, str(path)]}


def measure(path: Path, repeats: int) -> dict:
    """CPU and wall seconds of each command on ``path``, ``repeats`` rounds, and the ratios to the read."""
    with tempfile.TemporaryDirectory() as tmp:
        cmds = commands(path, str(Path(tmp) / "grid.json"))
        for cmd in cmds.values():
            timed(cmd)  # untimed warm-up: the file in the page cache, bytecode written
        runs: dict[str, list[tuple[float, float]]] = {k: [] for k in KINDS}
        for r in range(repeats):
            for kind in KINDS[r % len(KINDS):] + KINDS[:r % len(KINDS)]:
                runs[kind].append(timed(cmds[kind]))
    cpu = {k: [c for _, c in v] for k, v in runs.items()}
    med = {k: statistics.median(v) for k, v in cpu.items()}
    low = {k: min(v) for k, v in cpu.items()}
    wall = {k: statistics.median(w for w, _ in v) for k, v in runs.items()}
    return dict(model=path.name, repeats=repeats, cpu=cpu, cpu_median=med, cpu_min=low, wall_median=wall,
                info=med["info"] / med["read"], refine=med["refine"] / med["read"],
                info_min=low["info"] / low["read"], refine_min=low["refine"] / low["read"],
                info_own=med["info"] / med["read0"], refine_own=med["refine"] / med["read0"],
                wall_info=wall["info"] / wall["read"], wall_refine=wall["refine"] / wall["read"])


HEADER = ("| model | read CPU s | **info/read** | **refine/read** | min: info/read | min: refine/read "
          "| info/read0 | refine/read0 | wall: info/read | wall: refine/read | misses |")
RULE = "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"


def misses(r: dict) -> list[str]:
    """The targets the judged figures (CPU medians) miss."""
    return [m for m, bad in ((f"info>{INFO_LIMIT}x", r["info"] > INFO_LIMIT),
                             (f"refine>{REFINE_LIMIT}x", r["refine"] > REFINE_LIMIT)) if bad]


def format_row(r: dict) -> str:
    return (f"| {r['model']} | {r['cpu_median']['read']:.2f} | {r['info']:.2f} | {r['refine']:.2f} "
            f"| {r['info_min']:.2f} | {r['refine_min']:.2f} | {r['info_own']:.2f} | {r['refine_own']:.2f} "
            f"| {r['wall_info']:.2f} | {r['wall_refine']:.2f} | {', '.join(misses(r)) or 'ok'} |")


def table(rows: list[dict]) -> str:
    ok = sum(not misses(r) for r in rows)
    worst = {k: max(r[k] for r in rows) for k in ("info", "refine", "info_min", "refine_min", "info_own",
                                                   "refine_own", "wall_info", "wall_refine")}
    total = ("| **worst** | | " + " | ".join(f"{worst[k]:.2f}" for k in worst)
             + f" | {ok}/{len(rows)} ok |")
    return "\n".join([HEADER, RULE] + [format_row(r) for r in rows] + [total])


def run(paths: list[Path], repeats: int, echo: bool = True) -> list[dict]:
    rows = []
    if echo:
        print(HEADER)
        print(RULE)
    for path in paths:
        rows.append(measure(path, repeats))
        if echo:
            print(format_row(rows[-1]), flush=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--file", type=Path, nargs="+", help="these STEP files instead of corpus + fixtures")
    ap.add_argument("--json", type=Path, help="also write the rows (every run's CPU time) as JSON")
    args = ap.parse_args(argv)
    rows = run(args.file or files(), args.repeats)
    print(table(rows).splitlines()[-1])
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0 if not any(misses(r) for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
