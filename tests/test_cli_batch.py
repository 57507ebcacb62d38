"""``cadedge batch`` end to end through ``cadedge.cli.main``: the embedded LocalCluster, an existing
scheduler whose workers are killed mid-run, reruns, exit codes and one-line errors."""

from __future__ import annotations

import io
import os
import shutil
import signal
import threading
import time

import pytest

from batch_tasks import local_cluster, wait_for_workers
from cadedge.batch import WORKER_DIED, BatchProgress, FileResult
from cadedge.cli import main
from cadedge.cli.batch import BatchBar

pytest.importorskip("distributed")

from conftest import CORPUS, FIXTURES
#: Inputs slow enough (reading and refining about a second each) that both workers are busy with them at once.
SLOW = [CORPUS / "LLNL__axom_data__boxed_sphere.step", CORPUS / "live-clones__gmsh__917_fusee.stp"]


def one_line(text: str) -> str:
    lines = text.strip().splitlines()
    assert len(lines) == 1, text
    return lines[0]


@pytest.mark.parametrize("args, words", [
    (["nope.step"], ["nope.step", "no such file or folder"]),
    (["EMPTY"], ["EMPTY", "folder holds no .step/.stp/.igs/.iges/.brep files"]),
    (["*.nothing"], ["*.nothing", "pattern matches no"]),
    ([str(FIXTURES / "sphere.step"), "--ald", "0"], ["--ald", "greater than 0"]),
    ([str(FIXTURES / "sphere.step"), "--workers", "0"], ["workers", "at least 1"]),
    ([str(FIXTURES / "sphere.step"), "--timeout", "-5"], ["timeout must be positive", "-5"]),
    ([str(FIXTURES / "sphere.step"), "--workers", "2", "--scheduler", "tcp://127.0.0.1:9"], ["not allowed"]),
])
def test_bad_usage_exit_2_with_one_line(tmp_path, capsys, monkeypatch, args, words):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "EMPTY").mkdir()
    assert main(["batch", *args, "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    line = err.strip().splitlines()[-1]
    assert all(w in line for w in words), err
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_embedded_cluster_failed_input_then_rerun(tmp_path, capsys):
    folder = tmp_path / "models"
    folder.mkdir()
    for name in ("cylinder", "sphere", "two_solids"):
        shutil.copy(FIXTURES / f"{name}.step", folder / f"{name}.step")
    (folder / "broken.stp").write_text("not STEP at all\n")
    out = tmp_path / "out"
    assert main(["batch", str(folder), "-o", str(out), "--ald", "1e-2", "--workers", "2"]) == 1
    cap = capsys.readouterr()
    assert "4 inputs: 3 ok, 1 failed" in cap.out
    assert one_line(cap.err).startswith(f"failed: {folder.resolve() / 'broken.stp'}: InputError")
    assert sorted(p.name for p in out.iterdir()) == ["cylinder.json", "index.sqlite", "sphere.json", "two_solids.json"]

    assert main(["batch", str(folder), "-o", str(out), "--ald", "1e-2", "--workers", "2"]) == 1
    cap = capsys.readouterr()
    assert "skipped 3 finished inputs" in cap.out and "retry them with --retry-failed" in cap.out
    assert "0 ok, 0 failed, 3 skipped" in cap.out and cap.err == ""

    shutil.copy(FIXTURES / "open_face.step", folder / "broken.stp")
    assert main(["batch", str(folder), "-o", str(out), "--ald", "1e-2", "--workers", "1"]) == 0
    cap = capsys.readouterr()
    assert "skipped 3 finished inputs" in cap.out and "1 ok, 0 failed" in cap.out
    assert (out / "broken.json").is_file()


def _kill_busy_workers(address: str, stop: threading.Event, killed: list) -> None:
    """Once both workers are running a task, SIGKILL both worker processes: only processes this one started
    (a pid that is not, this test's own or a stranger's, is put in ``killed`` as an error instead)."""
    import psutil
    from distributed import Client

    with Client(address) as client:
        pids = client.run(os.getpid)
        while not stop.is_set():
            busy = [w for w, keys in client.processing().items() if keys]
            if len(busy) == 2:
                ours = {p.pid for p in psutil.Process().children(recursive=True)}
                for w in busy:
                    if pids[w] not in ours:
                        killed.append(f"{w}: pid {pids[w]} is not a child of the test's process")
                        continue
                    os.kill(pids[w], signal.SIGKILL)
                    killed.append(w)
                return
            time.sleep(0.02)


@pytest.mark.corpus
def test_existing_scheduler_workers_killed_mid_run_then_retry(tmp_path, capsys):
    small = [FIXTURES / "sphere.step", FIXTURES / "open_face.step"]
    out = tmp_path / "out"
    args = ["batch", *map(str, SLOW + small), "-o", str(out), "--ald", "1e-2"]
    with local_cluster(2) as cluster:
        stop, killed = threading.Event(), []
        killer = threading.Thread(target=_kill_busy_workers, args=(cluster.scheduler_address, stop, killed))
        killer.start()
        try:
            code = main([*args, "--scheduler", cluster.scheduler_address])
        finally:
            stop.set()
            killer.join()
        cap = capsys.readouterr()
        assert len(killed) == 2 and all(" " not in w for w in killed), killed  # both killed, both ours
        assert code == 1
        assert "4 inputs: 2 ok, 2 failed" in cap.out
        assert {line for line in cap.err.splitlines()} == {f"failed: {p}: {WORKER_DIED}" for p in SLOW}

        wait_for_workers(cluster.scheduler_address, 2)  # the nannies restart both
        assert main([*args, "--scheduler", cluster.scheduler_address, "--retry-failed"]) == 0
        cap = capsys.readouterr()
        assert "skipped 2 finished inputs" in cap.out and "2 ok, 0 failed" in cap.out
    assert len(list(out.glob("*.json"))) == 4


def test_progress_bar_counts_done_and_failed():
    err, out = io.StringIO(), io.StringIO()
    bar = BatchBar(out=out, err=err, enabled=True)
    bar(BatchProgress(total=2, done=0, ok=0, failed=0, skipped=5, skipped_failed=0))
    bar(BatchProgress(2, 1, 1, 0, 5, 0, FileResult("/m/a.step", "a.json", "ok")))
    bar(BatchProgress(2, 2, 1, 1, 5, 0, FileResult("/m/b.step", "b.json", "failed", error="GeometryError: x")))
    bar.close()
    assert out.getvalue() == "skipped 5 finished inputs\n"
    text = err.getvalue()
    assert "failed: /m/b.step: GeometryError: x" in text
    assert "2/2" in text and "done=1, failed=1" in text
