"""Run a :class:`~cadedge.mesh.worker.MeshJob` in a child process under a watchdog.

The child (``python -m cadedge.mesh.worker``, in its own session so a terminal's Ctrl-C reaches only the
caller) writes a progress line before each step and each face attempt. The watchdog here kills it when

- one face attempt runs longer than ``face_timeout`` of the child's CPU time (up to
  :data:`MAX_BOUND_WEIGHT` times that for faces with many boundary segments, :func:`attempt_bound`; or
  :data:`WALL_SLACK` times it on the clock, for a child that hangs without computing): that (face,
  strategy) is marked as hung and a new child runs the job again without it (the face goes on to the
  next strategy with other sizes: the other algorithms on the same sizes tend to hang as well, and finer
  sizes take longer still; and within :data:`RETRY_SHARE` of the bound). CPU time,
  because on a loaded machine a face that takes 20 s alone takes several times that on the clock. A batch
  of first attempts that hangs or crashes is done again face by face, except the first attempt of the
  face gmsh was meshing when it stopped (the child's standard output, ``trace``, holds gmsh's progress
  through each batch: :func:`cadedge.mesh.worker.trace_culprit`); faces meshed again finer for the
  surface target or by the worker's re-check (``refine F1 F2 ...``) that hang or crash are kept as they
  were first meshed;
- the child dies (a segfault, an abort, the memory limit): the attempt it was in is marked as crashed,
  and likewise a new child carries on; a crash outside any face attempt fails the job with the reason;
- the whole job passes ``timeout``: the faces the children had meshed (each child appends every face it
  meshes to a file as it goes) are delivered, nodes merged by exact coordinates, with the other faces
  failing "no result within ... s" (and the mesh written with meshio, since gmsh did not get to it); with
  no face meshed the job fails with that reason.

A new child replays what the progress file says the killed one achieved: each face starts at the
strategy that meshed it, and attempts that failed are not tried again. After :data:`SOFT_SHARE` of the
timeout the child starts no new attempts (the faces left fail with "out of time"), and an attempt still
running at :data:`KILL_SHARE` of it is killed and the job ends there with the faces the children
delivered (a new child's first attempt would be killed in turn: a heat sink at 1e-3 went through 12
restarts that way and ended with none of its 81 meshed faces). A slow model ends with a partial mesh and
the unfinished faces named, not with nothing; so does a job out of restarts. Faces an earlier child
delivered that the last one did not mesh again are added to its mesh. The face optimiser, which improves
meshed faces, may go on past the soft deadline up to :data:`FINISH_SHARE`.

A large job may be split (``workers``, :mod:`cadedge.mesh.shards`): its faces are meshed in several
children at once, each under its own watchdog and restarts as above, all within the one ``timeout``;
their meshes are joined by node coordinates and written with meshio. Faces meshed again after them, on
an edge another shard changed, get the same shares of the time then left, where later than the job's own.

The caller gets a :class:`~cadedge.mesh.worker.JobResult` in every case, never an exception from gmsh;
hangs and crashes that cost a face are in ``result.notes`` and in that face's attempts. On
``KeyboardInterrupt`` the child is killed before the interrupt goes on.
"""

from __future__ import annotations

import os
import pickle
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from ..atomic import atomic_path
from ..childproc import child_env
from .delivered import Delivered, delivered, read_deliveries, with_earlier_faces, write_meshio
from .strategies import STRATEGIES
from .worker import JobResult, MeshJob, empty_result, trace_culprit

#: Default bound on one mesh job (all faces, all retries, restarts included), in seconds.
DEFAULT_TIMEOUT = 300.0
#: One face attempt may take at most this share of the job's timeout before it counts as hung.
FACE_SHARE = 0.2
#: Share of the timeout after which the child starts no new face attempts.
SOFT_SHARE = 0.6
#: Share of the timeout at which a running face attempt is killed (the replay gets the rest).
KILL_SHARE = 0.7
#: Share of the timeout after which the child's optional steps stop (the face optimiser, which also runs
#: past :data:`SOFT_SHARE`: a model whose meshing used the soft deadline still gets its worst faces
#: optimised); the rest is for the re-check, reading the mesh back and writing it.
FINISH_SHARE = 0.85
#: A face attempt that computes little (a child blocked, not busy) counts as hung after this many times
#: ``face_timeout`` on the clock.
WALL_SLACK = 3.0
#: Restarts after hung or crashed face attempts, at most.
MAX_RESTARTS = 12
_POLL = 0.05
#: The child's standard output in its job folder: gmsh's progress through each batch of faces (see
#: :func:`cadedge.mesh.worker.trace_culprit`).
TRACE = "trace"
#: A job's private folder: this prefix, the caller's pid, a dash (see :func:`_remove_orphaned_folders`).
FOLDER_PREFIX = "cadedge-mesh-"
#: Progress lines that mark work the watchdog bounds: one face attempt, a batch of them, a finer re-mesh.
_ATTEMPT_LINES = ("face ", "batch ", "refine ")
#: An attempt's bound grows with the boundary segments of the faces it meshes, past this many (gmsh's
#: time grows with them: the 900-hole plate's faces with the holes have 74 464 each at 1e-3 and took
#: 40-50 s of CPU against the default 60 s bound, and one was stopped as hung when run beside other
#: work), to at most :data:`MAX_BOUND_WEIGHT` times ``face_timeout``.
SEGMENTS_PER_BOUND = 40_000
MAX_BOUND_WEIGHT = 3.0


def face_segments(grid) -> dict[int, int]:
    """Face id -> boundary segments: each edge's grid segments, once for every face it bounds."""
    out: dict[int, int] = {}
    for e in grid.edges:
        if not e.degenerate:
            for f in e.faces:
                out[f] = out.get(f, 0) + max(len(e.points) - 1, 0)
    return out


def attempt_bound(line: str, face_timeout: float, segments: dict[int, int]) -> float:
    """The bound on the attempt that progress ``line`` (``face F K``, ``batch F...``, ``refine F...``)
    announces: ``face_timeout``, times the faces' boundary segments over :data:`SEGMENTS_PER_BOUND`
    where that is more than 1, at most :data:`MAX_BOUND_WEIGHT` times."""
    words = line.split()
    faces = words[1:2] if words[:1] == ["face"] else words[1:]
    n = sum(segments.get(int(w), 0) for w in faces if w.isdigit())
    return face_timeout * min(max(1.0, n / SEGMENTS_PER_BOUND), MAX_BOUND_WEIGHT)


#: A face that has hung gmsh once gets this share of the bound on its later attempts: a face that hangs
#: one strategy tends to hang the others, and one that meshes does so in seconds. An ABC-dataset part
#: (OCCT's bug32596_abc_0_13.step) has a B-spline face that hung every strategy tried, 60 s each: at ALD
#: 1e-2 it hung three (its batch, then two alone) and 4 of the 99 faces failed, two of them out of time;
#: with the batch's hang pinned on it and 15 s for each later one, it hung three in 105 s, was meshed by
#: the fourth, and every face was meshed.
RETRY_SHARE = 0.25


def retry_share(line: str, skip: dict[int, dict[int, str]]) -> float:
    """:data:`RETRY_SHARE` for the attempt progress ``line`` (``face F K``) announces if face ``F`` hung
    an earlier attempt (its ``skip`` reasons), else 1."""
    words = line.split()
    if words[:1] != ["face"] or len(words) < 2 or not words[1].isdigit():
        return 1.0
    hung = any(r.startswith("hung") for r in skip.get(int(words[1]), {}).values())
    return RETRY_SHARE if hung else 1.0


@dataclass
class _Run:
    result: JobResult | None
    status: str  # "ok", "hung", "late" (past KILL_SHARE), "crashed", "timeout"
    last: str  # the last progress line
    detail: str


def _signal_name(code: int) -> str:
    try:
        return signal.Signals(-code).name
    except ValueError:
        return f"signal {-code}"


def _exit_reason(code: int, stderr: str) -> str:
    if code < 0:
        name = _signal_name(code)
        hint = " (likely out of memory)" if name == "SIGKILL" else ""
        return f"gmsh crashed ({name}{hint})"
    tail = [ln for ln in stderr.strip().splitlines() if ln.strip()][-1:]
    return f"the mesh process exited with code {code}" + (f": {tail[0][:200]}" if tail else "")


def _cpu_seconds(pid: int) -> float | None:
    """CPU time (user + system) of process ``pid`` so far; None where ``/proc`` does not tell."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            fields = f.read().rsplit(b")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


class _Tail:
    """A child's progress file as it grows: :meth:`new` gives the complete lines appended since its last
    call, and ``last`` is the last complete line so far (the step under way, for the watchdog)."""

    def __init__(self, path: str):
        self.path, self.offset, self.last = path, 0, ""

    def new(self) -> list[str]:
        try:
            with open(self.path, "rb") as f:
                f.seek(self.offset)
                data = f.read()
        except OSError:
            return []
        end = data.rfind(b"\n") + 1
        self.offset += end
        lines = data[:end].decode(errors="replace").splitlines()
        if lines:
            self.last = lines[-1]
        return lines


def _read(path: str) -> str:
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            return f.read()
    except OSError:
        return ""


def _progress(path: str) -> list[str]:
    return _read(path).splitlines()


def _learn(lines: list[str], skip: dict[int, dict[int, str]], known_ok: dict[int, int]) -> None:
    """What a killed child achieved, from its progress lines: strategies that meshed or failed each face."""
    for line in lines:
        words = line.split(" ", 4)
        if words[0] != "result" or len(words) < 4:
            continue
        face, k = int(words[1]), int(words[2])
        if words[3] == "ok":
            known_ok[face] = k
        else:
            skip.setdefault(face, {})[k] = words[4] if len(words) > 4 else "failed"


@dataclass
class _Limits:
    """A job's time bounds: ``deadline`` and ``kill_at`` on ``time.monotonic()`` (see the module doc), and
    the faces' boundary segments that scale an attempt's bound (:func:`attempt_bound`)."""

    deadline: float
    kill_at: float
    timeout: float
    face_timeout: float
    segments: dict[int, int]


def _run_child(job: MeshJob, tmp: str, limits: _Limits, progress: Callable[[str], None] | None = None,
               stop: threading.Event | None = None) -> _Run:
    job_path, result_path, progress_path = (os.path.join(tmp, n) for n in ("job.pkl", "result.pkl", "progress"))
    for p in (result_path, progress_path):
        if os.path.exists(p):
            os.remove(p)
    with open(job_path, "wb") as f:
        pickle.dump(job, f, protocol=pickle.HIGHEST_PROTOCOL)
    env = child_env()
    with open(os.path.join(tmp, "stderr"), "w+") as err, open(os.path.join(tmp, TRACE), "w") as out:
        proc = subprocess.Popen([sys.executable, "-m", "cadedge.mesh.worker", job_path, result_path, progress_path,
                                 os.path.join(tmp, "faces")],
                                stdin=subprocess.DEVNULL, stdout=out, stderr=err, env=env,
                                start_new_session=True)
        last, since, cpu_since, bound = "", time.monotonic(), 0.0, limits.face_timeout
        tail = _Tail(progress_path)
        try:
            while True:
                try:
                    code = proc.wait(timeout=_POLL)
                    break
                except subprocess.TimeoutExpired:
                    pass
                finally:
                    for line in tail.new():
                        if progress is not None:
                            progress(line)
                if stop is not None and stop.is_set():
                    raise KeyboardInterrupt  # another thread was interrupted: the child is killed below
                now = time.monotonic()
                line = tail.last
                cpu = _cpu_seconds(proc.pid)
                if line != last:
                    last, since, cpu_since = line, now, cpu or 0.0
                    bound = attempt_bound(line, limits.face_timeout, limits.segments) * retry_share(line, job.skip)
                if now > limits.deadline:
                    return _Run(None, "timeout", last, "")
                busy = now - since if cpu is None else cpu - cpu_since
                if line.startswith(_ATTEMPT_LINES) and (busy > bound or now - since > WALL_SLACK * bound):
                    return _Run(None, "hung", last, f"hung: no result within {bound:.3g} s")
                if line.startswith(_ATTEMPT_LINES) and now > limits.kill_at:
                    return _Run(None, "late", last, "not finished: out of time (timeout)")
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        tail.new()
        last = tail.last
        err.seek(0)
        stderr = err.read()
    if code == 0 and os.path.exists(result_path):
        with open(result_path, "rb") as f:
            return _Run(pickle.load(f), "ok", last, "")
    return _Run(None, "crashed", last, _exit_reason(code, stderr))


def run_isolated(job: MeshJob, *, output: Path | None = None, timeout: float = DEFAULT_TIMEOUT,
                 face_timeout: float | None = None, progress: Callable[[str], None] | None = None,
                 workers: int = 1, started: float | None = None) -> JobResult:
    """Run ``job`` in a child process (see the module doc); the mesh goes to ``output`` if anything meshed.

    ``face_timeout`` defaults to :data:`FACE_SHARE` of ``timeout``. ``progress(line)``, if given, gets every
    progress line of the children as it comes (see :mod:`cadedge.mesh.worker`), and ``restart EVENT``
    before a new child carries on (:class:`cadedge.mesh.status.MeshStatus` puts them in words).
    ``output`` is written atomically and only when the result has triangles; ``job.output`` is set here
    to a file in a private folder. With ``workers`` over 1, a large ``nodes`` job's faces are meshed in
    up to that many children at once, each under its own watchdog, and their meshes joined (see
    :mod:`cadedge.mesh.shards`; the mesh is then written with meshio, as for a stopped job). ``started``
    (``time.monotonic()``), if given, is when the job began (the caller's steps before it count against
    ``timeout``: every deadline above counts from there; see :mod:`cadedge.mesh.jobclock`).
    """
    from .shards import plan

    face_timeout = face_timeout or FACE_SHARE * timeout
    now = time.monotonic()
    t0 = now if started is None else min(started, now)
    segments = face_segments(job.grid)
    limits = _Limits(deadline=t0 + timeout, kill_at=t0 + KILL_SHARE * timeout, timeout=timeout,
                     face_timeout=face_timeout, segments=segments)
    job.deadline = time.time() - (now - t0) + SOFT_SHARE * timeout
    job.finish_by = time.time() - (now - t0) + FINISH_SHARE * timeout
    if now >= limits.kill_at:  # the caller's steps used the time: a child's first attempt would be killed
        return _failed(f"out of time: reading the shape and preparing its grids took {now - t0:.3g} s, past "
                       f"{KILL_SHARE:.0%} of --timeout ({timeout:g} s); gmsh was not started", [])
    job.attempt_bound = face_timeout
    _remove_orphaned_folders()
    if job.mode != "nodes" or job.faces is not None:
        job.copies = {}
    shards = plan(job.grid, workers, segments, leave=frozenset(job.copies)) \
        if job.mode == "nodes" and job.faces is None else [job.faces]
    with tempfile.TemporaryDirectory(prefix=f"{FOLDER_PREFIX}{os.getpid()}-") as tmp:
        if len(shards) > 1 or job.copies:
            return _run_shards(job, shards, tmp, output, limits, progress)
        return _supervise(job, tmp, output, limits, progress)


def _supervise(job: MeshJob, tmp: str, output: Path | None, limits: _Limits,
               progress: Callable[[str], None] | None, stop: threading.Event | None = None) -> JobResult:
    """Run ``job`` in children in folder ``tmp`` until one finishes, the restarts run out or the time does
    (see the module doc); ``stop``, once set, kills the child and raises KeyboardInterrupt here."""
    timeout = limits.timeout
    events: list[str] = []
    skip: dict[int, dict[int, str]] = {k: dict(v) for k, v in job.skip.items()}
    known_ok: dict[int, int] = dict(job.known_ok)
    job.output = os.path.join(tmp, "mesh" + output.suffix.lower()) if output is not None else None
    for _ in range(MAX_RESTARTS + 1):
        job.skip, job.known_ok = skip, known_ok
        if events and progress is not None:
            progress(f"restart {events[-1]}")
        run = _run_child(job, tmp, limits, progress, stop)
        if run.status == "ok":
            result = run.result
            result.notes = events + result.notes
            fuller = with_earlier_faces(result, os.path.join(tmp, "faces"), job, known_ok,
                                        rewrite=output is not None and not result.written)
            if fuller is not None:
                if output is not None:
                    write_meshio(fuller, output)
                return fuller.result
            if output is not None and result.written and len(result.triangles):
                with atomic_path(output) as dst:
                    shutil.copyfile(job.output, dst)
            else:
                result.written = False
            return result
        if run.status in ("timeout", "late"):  # past KILL_SHARE a new child's first attempt is killed too
            reason = f"no result within {timeout:g} s (--timeout)" if run.status == "timeout" else \
                f"out of time: meshing was stopped at {KILL_SHARE:.0%} of --timeout ({timeout:g} s)"
            _learn(_progress(os.path.join(tmp, "progress")), skip, known_ok)
            return _deliver_or_fail(os.path.join(tmp, "faces"), job, known_ok, reason, events, output)
        words = run.last.split()
        if words[:1] == ["batch"] and len(words) == 2:  # a batch of one face: that face's first attempt
            words = ["face", words[1], "0"]
        if words[:1] == ["batch"] and len(words) > 1:
            _learn(_progress(os.path.join(tmp, "progress")), skip, known_ok)
            faces = [int(w) for w in words[1:]]
            job.no_batch |= set(faces)
            culprit = trace_culprit(_read(os.path.join(tmp, TRACE)), faces)
            on = ""
            if culprit is not None:  # its first attempt is done: the next child starts it at the next strategy
                _bar(skip, culprit, 0, run)
                on = f" on face {culprit} ({STRATEGIES[0].name}: gmsh's progress names it)"
            events.append(f"faces {', '.join(words[1:])}: meshing them together in one gmsh call: "
                          f"{run.detail}{on}; they were meshed one by one in a new process")
            continue
        if words[:1] == ["refine"] and len(words) >= 2:  # one face, or several meshed again in one call
            _learn(_progress(os.path.join(tmp, "progress")), skip, known_ok)
            job.no_refine.update(int(w) for w in words[1:])
            what = f"face {words[1]}: meshing it" if len(words) == 2 else \
                f"faces {', '.join(words[1:])}: meshing them together"
            events.append(f"{what} again finer (for the surface target or the re-check) {run.detail}; "
                          f"{'it was' if len(words) == 2 else 'they were'} kept as first meshed")
            continue
        if words[:1] != ["face"] or len(words) != 3:
            where = f" while gmsh was at step '{run.last}'" if run.last else ""
            return _failed(f"{run.detail}{where}", events)
        _learn(_progress(os.path.join(tmp, "progress")), skip, known_ok)
        face, k = int(words[1]), int(words[2])
        _bar(skip, face, k, run)
        events.append(f"face {face}: {run.detail} ({STRATEGIES[k].name}); the other faces went on in a new "
                      "process")
    return _deliver_or_fail(os.path.join(tmp, "faces"), job, known_ok,
                            f"gave up after {MAX_RESTARTS} restarts of the mesh process", events, output)


def _bar(skip: dict[int, dict[int, str]], face: int, k: int, run: _Run) -> None:
    """Record in ``skip`` that strategy ``k`` of ``face`` hung or crashed (``run``); after a hang, also the
    other strategies on the same sizes (the other algorithms tend to hang on them too) and on finer ones
    (they take longer still) that the face has not tried yet. Those it tried are in ``skip`` already
    (:func:`_learn`), so what is barred follows the face's own order (:func:`~.strategies.face_order`):
    a curved face with many holes tries Delaunay first, and a hang there bars Frontal-Delaunay too."""
    barred = skip.setdefault(face, {})
    barred[k] = run.detail
    if run.status == "hung":
        kind = STRATEGIES[k].sizes
        for j, s in enumerate(STRATEGIES):
            if j == k:
                continue
            if s.sizes == kind:
                barred.setdefault(j, f"not tried: {STRATEGIES[k].name} hung on the same sizes")
            elif s.size_factor < min(1.0, STRATEGIES[k].size_factor):  # below the base sizes and the hung ones
                barred.setdefault(j, f"not tried: {STRATEGIES[k].name} hung; finer sizes take longer")


def _deliver_or_fail(path: str, job: MeshJob, known_ok: dict[int, int], reason: str, events: list[str],
                     output: Path | None) -> JobResult:
    """The job ends without a finished child: the faces the children delivered (written to ``output``),
    the others failing with ``reason``; with none delivered the job fails with it."""
    mesh = delivered(path, job, known_ok, reason, events)
    if mesh is None:
        return _failed(reason, events)
    if output is not None:
        write_meshio(mesh, output)
    return mesh.result


def _remove_orphaned_folders() -> None:
    """Remove the job folders of callers that ended without cleaning up (killed outright, or by a signal
    Python does not handle): a hung or killed job leaves its shape, progress and delivered faces there,
    megabytes on a large model. Only this user's folders whose process is gone are touched."""
    root = tempfile.gettempdir()
    try:
        names = [n for n in os.listdir(root) if n.startswith(FOLDER_PREFIX)]
    except OSError:
        return
    for name in names:
        pid = name[len(FOLDER_PREFIX):].split("-", 1)[0]
        path = os.path.join(root, name)
        try:  # (os.getuid first: where it is missing, os.kill(pid, 0) would end the process)
            if not pid.isdigit() or os.stat(path).st_uid != os.getuid() or _alive(int(pid)):
                continue
        except (OSError, AttributeError):  # gone meanwhile, or no uids on this platform
            continue
        shutil.rmtree(path, ignore_errors=True)


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists (a process of another user counts as alive)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def _run_shards(job: MeshJob, shards: list[frozenset[int]], tmp: str, output: Path | None, limits: _Limits,
                progress: Callable[[str], None] | None) -> JobResult:
    """Mesh each shard of ``job``'s faces in its own child at once, each under :func:`_supervise`; mesh
    again the faces on edges another shard changed (see :mod:`cadedge.mesh.shards`); join the meshes and
    write them to ``output``."""
    from concurrent.futures import ThreadPoolExecutor

    from .instances import place, placed_note
    from .shards import ADOPT_ROUNDS, Part, conflicts, drop_faces, faces_text, join, weight

    lock, stop = threading.Lock(), threading.Event()

    def say(line: str) -> None:
        if progress is not None:
            with lock:
                progress(line)

    total = weight(frozenset().union(*shards), limits.segments)

    def run(faces: frozenset[int], adopt: dict, folder: str, late: bool = False) -> Part:
        os.makedirs(folder)
        share = weight(faces, limits.segments) / total
        sub = replace(job, faces=faces, adopt=adopt, skip={k: dict(v) for k, v in job.skip.items()},
                      known_ok=dict(job.known_ok), no_batch=set(job.no_batch), no_refine=set(job.no_refine),
                      share=share)
        bounds = limits
        if late:  # meshing again after the shards: on the time left (see _rest)
            bounds, sub.deadline, sub.finish_by = _rest(limits, job)
        result = _supervise(sub, folder, None, bounds, say, stop)
        return Part(faces=faces, result=result, edges=read_deliveries(os.path.join(folder, "faces"))[1],
                    adopted=frozenset(adopt))

    pool = ThreadPoolExecutor(max_workers=len(shards))
    try:
        futures = [pool.submit(run, s, {}, os.path.join(tmp, f"shard{i}")) for i, s in enumerate(shards)]
        parts = [f.result() for f in futures]
    except BaseException:  # KeyboardInterrupt: every child is killed before it goes on
        stop.set()
        raise
    finally:
        pool.shutdown(wait=True)
    notes = [f"meshed in {len(shards)} processes at once (faces split by boundary segments: "
             f"{', '.join(str(len(s)) for s in shards)} faces)"] if len(shards) > 1 else []
    adopted: dict = {}
    why = "a neighbour meshed in another process changed an edge they share (its strategy split the edge or " \
          "meshed it itself)"
    for rounds in range(ADOPT_ROUNDS + 1):
        adopt, redo, lost = conflicts(job.grid, parts)
        if lost or (redo and rounds == ADOPT_ROUNDS):
            gone = lost | (redo if rounds == ADOPT_ROUNDS else set())
            for p in parts:
                drop_faces(p, gone & p.faces, f"dropped: {why}, and it could not be meshed again on it")
            notes.append(f"{faces_text(gone)}: dropped, {why}, and they could not be meshed again on it")
            redo -= gone
        if not redo:
            break
        adopted.update(adopt)
        for p in parts:
            p.faces = p.faces - redo
        say(f"restart {faces_text(redo)}: meshed again in a new process, on edges "
            f"{', '.join(map(str, sorted(adopt)))} as a neighbour's strategy changed them")
        notes.append(f"{faces_text(redo)}: {why}; meshed again on the changed edge")
        parts.append(run(frozenset(redo), dict(adopted), os.path.join(tmp, f"again{rounds}"), late=True))
    result, lines, line_edges = join(job.grid, parts, job.seams)
    if job.copies:
        say("place")
        left = place(result, lines, line_edges, job.grid, job.copies, job.seams)
        if left:  # their first face was meshed on other boundary nodes: each meshed on its own
            say(f"restart {faces_text(left)}: placed again from faces meshed on other boundary nodes; "
                "meshed on their own in a new process")
            parts.append(run(frozenset(left), dict(adopted), os.path.join(tmp, "copies"), late=True))
            result, lines, line_edges = join(job.grid, parts, job.seams)
            place(result, lines, line_edges, job.grid, {f: c for f, c in job.copies.items() if f not in left},
                  job.seams)
        if (note := placed_note(job.copies, left, result.faces)) is not None:
            notes.append(note)
    result.notes = notes + result.notes
    if output is not None and len(result.triangles):
        write_meshio(Delivered(result, lines, line_edges), output)
    return result


def _rest(limits: _Limits, job: MeshJob) -> tuple[_Limits, float, float]:
    """Bounds for a child that starts now, after the shards: ``limits`` killing it at :data:`KILL_SHARE` of
    the time left to the job's deadline, and its soft deadline and ``finish_by`` (``time.time()``) at
    :data:`SOFT_SHARE` and :data:`FINISH_SHARE` of it; each only where later than the job's own.

    The faces to mesh again on an edge another shard changed are known only once the shards end, and a
    shard's face optimiser may run to :data:`FINISH_SHARE` of the timeout. On the job's own bounds the
    child meshing them again was killed at its first attempt: the RPi DIN mount at 1e-3 (1.07 M
    triangles, 2 cores, 300 s) lost 6 faces that way, which take 6 s to mesh.
    """
    now, wall = time.monotonic(), time.time()
    left = max(limits.deadline - now, 0.0)
    return (replace(limits, kill_at=max(limits.kill_at, now + KILL_SHARE * left)),
            max(job.deadline or 0.0, wall + SOFT_SHARE * left),
            max(job.finish_by or 0.0, wall + FINISH_SHARE * left))


def _failed(reason: str, events: list[str]) -> JobResult:
    result = empty_result(reason)
    result.notes = events
    return result
