"""Start-up benchmark: what a user waits for, in fresh processes, against reading the STEP file alone.

    python scripts/startup.py [--repeats 5] [--file PATH ...]

For every model (the corpus and ``fixtures/``), side by side in one run, each in a fresh process:

- **read**: a Python that imports OCP and reads and transfers the STEP file (``STEPControl_Reader``:
  ``ReadFile``, ``TransferRoots``, ``OneShape``), the least any tool built on OCP can cost;
- **info**: ``cadedge info FILE``;
- **refine**: ``cadedge refine FILE --ald 1e-3 -o OUT.json``.

After one untimed warm-up of each (the file in the page cache, bytecode written as an installed
package has it), the three commands of a model run in turn, ``--repeats`` times, and the median wall
time of each is kept, so a load on the machine falls on all three alike. The CPU time of each (user + system, from
``getrusage``) is reported beside it: it hardly changes with the machine's load. Targets: *info/read* <= 1.15 and
*refine/read* <= 1.3. ``scripts/bench.py --startup`` runs this and adds the table to its output.
"""

from __future__ import annotations

import argparse
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
READ = ("import sys\n"
        "from OCP.STEPControl import STEPControl_Reader\n"
        "reader = STEPControl_Reader()\n"
        "assert int(reader.ReadFile(sys.argv[1])) == 1\n"
        "reader.TransferRoots()\n"
        "reader.OneShape()\n")
ENTRY = "import sys; from cadedge.cli import entry; sys.argv[0] = 'cadedge'; entry()"


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
    """(wall, CPU) seconds of one run of ``cmd``; CPU time depends less on the machine's load."""
    c0, t0 = _cpu(), time.perf_counter()
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=_env())
    seconds, cpu = time.perf_counter() - t0, _cpu() - c0
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {done.returncode}: {done.stderr.strip()[-300:]}")
    return seconds, cpu


def measure(path: Path, repeats: int) -> dict:
    """Median wall seconds of read, info and refine on ``path``, run in turn ``repeats`` times."""
    cad = cadedge_command()
    with tempfile.TemporaryDirectory() as tmp:
        out = str(Path(tmp) / "grid.json")
        commands = {"read": [sys.executable, "-c", READ, str(path)], "info": cad + ["info", str(path)],
                    "refine": cad + ["refine", str(path), "--ald", "1e-3", "-o", out]}
        walls: dict[str, list[float]] = {k: [] for k in commands}
        cpus: dict[str, list[float]] = {k: [] for k in commands}
        for cmd in commands.values():
            timed(cmd)  # untimed warm-up: the file in the page cache, bytecode written
        for _ in range(repeats):
            for kind, cmd in commands.items():
                w, c = timed(cmd)
                walls[kind].append(w)
                cpus[kind].append(c)
    row = {k: statistics.median(v) for k, v in walls.items()}
    cpu = {k: statistics.median(v) for k, v in cpus.items()}
    return dict(model=path.name, **row, info_ratio=row["info"] / row["read"], refine_ratio=row["refine"] / row["read"],
                cpu=cpu, info_cpu_ratio=cpu["info"] / cpu["read"], refine_cpu_ratio=cpu["refine"] / cpu["read"])


HEADER = ("| model | read s | info s | refine s | info/read | refine/read | CPU: info/read | CPU: refine/read "
          "| misses |")
RULE = "|---|---:|---:|---:|---:|---:|---:|---:|---|"


def format_row(r: dict) -> str:
    miss = [m for m, bad in (("info>1.15x", r["info_ratio"] > INFO_LIMIT),
                             ("refine>1.3x", r["refine_ratio"] > REFINE_LIMIT)) if bad]
    return (f"| {r['model']} | {r['read']:.2f} | {r['info']:.2f} | {r['refine']:.2f} | {r['info_ratio']:.2f} "
            f"| {r['refine_ratio']:.2f} | {r['info_cpu_ratio']:.2f} | {r['refine_cpu_ratio']:.2f} "
            f"| {', '.join(miss) or 'ok'} |")


def table(rows: list[dict]) -> str:
    ok = sum(format_row(r).endswith("| ok |") for r in rows)
    worst_i = max(r["info_ratio"] for r in rows)
    worst_r = max(r["refine_ratio"] for r in rows)
    worst_ci = max(r["info_cpu_ratio"] for r in rows)
    worst_cr = max(r["refine_cpu_ratio"] for r in rows)
    return "\n".join([HEADER, RULE] + [format_row(r) for r in rows]
                     + [f"| **all** | | | | worst {worst_i:.2f} | worst {worst_r:.2f} | worst {worst_ci:.2f} "
                        f"| worst {worst_cr:.2f} | {ok}/{len(rows)} ok |"])


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
    args = ap.parse_args(argv)
    rows = run(args.file or files(), args.repeats)
    print(table(rows).splitlines()[-1])
    return 0 if all(format_row(r).endswith("| ok |") for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
