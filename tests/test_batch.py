"""cadedge.batch: inputs and names, the SQLite index, and run_batch on a real dask LocalCluster with
the real refine task on real STEP files (fixtures/ and the third-party corpus), including a worker that
dies mid-run, a hung task, and reruns that resume."""

from __future__ import annotations

import json
import os
import shutil
import sqlite3
import sys
from pathlib import Path

import pytest

from batch_tasks import (CRASH_STEM, HANG_STEM, crash_or_refine, hang_or_refine, local_cluster, probe_and_refine,
                         unpublishable_refine,
                         wait_for_workers)
from cadedge.batch import INDEX_NAME, WORKER_DIED, BatchIndex, expand_inputs, output_names, run_batch
from cadedge.errors import InputError
from cadedge.exporters.json import validate

pytest.importorskip("distributed")

from conftest import CORPUS, FIXTURES
SMALL = ["cylinder", "sphere", "open_face", "helix_wire"]
CORPUS_SMALL = ["LLNL__axom_data__sliced_cylinder.step", "CadQuery__cadquery__red_cube_blue_cylinder.step",
                "live-clones__gmsh__mesh_T106_V3.step"]  # the last has loose tolerances: a warning
ALD = 1e-2


@pytest.fixture(scope="module")
def cluster():
    with local_cluster(2) as cluster:
        yield cluster


@pytest.fixture
def scheduler(cluster):
    """The cluster's address once both workers are up (an earlier test may have killed or restarted one)."""
    wait_for_workers(cluster.scheduler_address, 2)
    return cluster.scheduler_address


def copy_fixtures(folder: Path, stems=SMALL) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    return [Path(shutil.copy(FIXTURES / f"{s}.step", folder / f"{s}.step")) for s in stems]


def index_rows(outdir: Path) -> dict[str, tuple]:
    with sqlite3.connect(outdir / INDEX_NAME) as db:
        return {r[0]: r[1:] for r in db.execute("SELECT input, output, status, edges, segments, worst_ald, "
                                               "seconds, error FROM results")}


# --- inputs and names (no cluster) -----------------------------------------------------------------

def test_expand_files_folders_globs_dedupe(tmp_path):
    a = copy_fixtures(tmp_path / "a", ["cylinder", "sphere"])
    b = copy_fixtures(tmp_path / "a" / "deep", ["bracket"])
    (tmp_path / "a" / "notes.txt").write_text("not a model")
    upper = Path(shutil.copy(FIXTURES / "open_face.step", tmp_path / "OPEN.STP"))
    got = expand_inputs([str(tmp_path / "a"), str(a[0]), str(tmp_path / "*.STP"), tmp_path / "a" / "**" / "*.step"])
    assert got == [a[0].resolve(), b[0].resolve(), a[1].resolve(), upper.resolve()]  # sorted within a folder


@pytest.mark.parametrize("item, reason", [("missing.step", "no such file or folder"),
                                          ("empty", "folder holds no .step/.stp/.igs/.iges/.brep files"),
                                          ("*.nothing", "pattern matches no .step/.stp/.igs/.iges/.brep files")])
def test_expand_bad_inputs_name_the_item(tmp_path, item, reason):
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match=reason) as info:
        expand_inputs([str(tmp_path / item)])
    assert str(tmp_path / item) in str(info.value)
    with pytest.raises(InputError, match="no inputs"):
        expand_inputs([])


def test_output_names_unique_and_stable(tmp_path):
    p1, p2, p3 = (tmp_path / "x" / "part.step", tmp_path / "y" / "part.step", tmp_path / "z" / "gear.stp")
    names = output_names([p1, p2, p3])
    assert names[p3] == "gear.json"
    assert names[p1] != names[p2] and names[p1].startswith("part-") and names[p2].startswith("part-")
    assert output_names([p2, p1, p3]) == names
    # an input owning a name in the index keeps it; a newcomer with the same stem gets another
    again = output_names([p2], taken={"part.json": str(p1)})
    assert again[p2] == names[p2]
    assert output_names([p1, p3], taken={"part.json": str(p1)}) == {p1: "part.json", p3: "gear.json"}


def test_index_record_replace_and_names(tmp_path):
    with BatchIndex(tmp_path / INDEX_NAME) as index:
        index.record(input="/m/a.step", output="a.json", status="failed", size=3, mtime_ns=7, options="{}",
                     error="GeometryError: bad")
        index.record(input="/m/a.step", output="a.json", status="ok", size=3, mtime_ns=7, options="{}",
                     edges=4, segments=9, worst_ald=1e-3, seconds=0.5)
        row = index.get("/m/a.step")
        assert (row.status, row.edges, row.segments, row.error) == ("ok", 4, 9, None)
        assert index.names() == {"a.json": "/m/a.step"}
        assert index.get("/m/b.step") is None
        with pytest.raises(sqlite3.IntegrityError):
            index.record(input="/m/b.step", output="b.json", status="maybe", size=1, mtime_ns=1, options="{}")


def test_run_batch_rejects_bad_options_before_any_work(tmp_path):
    for kwargs, msg in [({"ald": 0.0}, "ald"), ({"ald": 1.5}, "ald"), ({"timeout": -1}, "timeout"),
                        ({"workers": 0}, "workers"), ({"max_growth": 1.0}, "max_growth"),
                        ({"workers": 2, "scheduler": "tcp://x:1"}, "not both"),
                        ({"ald": None}, "ald must be a number"),
                        ({"min_length": 2.0, "max_length": 1.0}, "min_length 2 exceeds max_length 1"),
                        ({"workers": True}, "workers")]:
        with pytest.raises(InputError, match=msg):
            run_batch([FIXTURES], tmp_path / "out", **kwargs)
    assert not (tmp_path / "out").exists()


# --- real cluster, real refine ---------------------------------------------------------------------

@pytest.mark.corpus
def test_real_refine_on_cluster_with_duplicate_stems(tmp_path, scheduler):
    inputs = copy_fixtures(tmp_path / "one") + copy_fixtures(tmp_path / "two", ["cylinder"])
    out = tmp_path / "out"
    seen = []
    report = run_batch([tmp_path / "one", inputs[-1], *(CORPUS / n for n in CORPUS_SMALL)], out, ald=ALD,
                       scheduler=scheduler, progress=seen.append)
    assert report.all_ok and len(report.ok) == 8, report.failed
    names = [r.output for r in report.results]
    assert len(set(names)) == 8
    assert sum(n.startswith("cylinder-") for n in names) == 2
    rows = index_rows(out)
    assert set(rows) == {str(p.resolve()) for p in [*inputs, *(CORPUS / n for n in CORPUS_SMALL)]}
    for r in report.results:
        doc = json.loads((out / r.output).read_text())
        validate(doc)
        assert doc["summary"]["edges"] == r.edges and doc["summary"]["segments"] == r.segments
        assert doc["summary"]["max_ald_estimate"] <= ALD
        assert rows[r.input][:5] == (r.output, "ok", r.edges, r.segments, r.worst_ald)
    assert [p.done for p in seen] == list(range(9)) and seen[-1].ok == 8 and seen[0].last is None
    warned = {Path(r.input).name: r.warnings for r in report.results if r.warnings}
    assert set(warned) == set(CORPUS_SMALL)  # these third-party files all carry reader warnings
    assert any("tolerance" in w for w in warned[CORPUS_SMALL[-1]])
    with BatchIndex(out / INDEX_NAME) as index:
        assert json.loads(index.get(str(CORPUS / CORPUS_SMALL[-1])).warnings) == list(warned[CORPUS_SMALL[-1]])
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no temporary files left


def test_a_summary_is_in_hand_when_its_task_is_done(tmp_path, scheduler):
    """The worker logs the summary as an event ahead of the task's end: no fetch from the worker needed."""
    from distributed import Client, wait

    from cadedge.batch import refine_task
    from cadedge.batch.runner import _publishing

    got = {}
    options = {"ald": ALD, "min_length": None, "max_length": None, "max_growth": None}
    with Client(scheduler) as client:
        client.subscribe_topic("cadedge-test-summary",
                               lambda event: got.update({event[1]["key"]: event[1]}))
        future = client.submit(_publishing, refine_task, "cadedge-test-summary", "one-key",
                               str(FIXTURES / "cylinder.step"), str(tmp_path / "c.json"), options,
                               pure=False, key="one-key")
        wait([future])
        assert got["one-key"]["summary"]["edges"] == 3  # recorded before the future turned done
        assert future.result()["segments"] == got["one-key"]["summary"]["segments"]


def test_a_summary_that_cannot_travel_as_an_event_is_fetched(tmp_path, scheduler):
    inputs = copy_fixtures(tmp_path / "in", ["cylinder", "sphere"])
    report = run_batch(inputs, tmp_path / "out", ald=ALD, scheduler=scheduler, task=unpublishable_refine)
    assert report.all_ok and sorted(r.edges for r in report.results) == [3, 3]


def test_worker_killed_mid_run_fails_that_input_only(tmp_path, scheduler):
    copy_fixtures(tmp_path / "in")
    shutil.copy(FIXTURES / "sphere.step", tmp_path / "in" / f"{CRASH_STEM}.step")
    out = tmp_path / "out"
    report = run_batch([tmp_path / "in"], out, ald=ALD, scheduler=scheduler, task=crash_or_refine)
    by_stem = {Path(r.input).stem: r for r in report.results}
    assert by_stem[CRASH_STEM].status == "failed" and by_stem[CRASH_STEM].error == WORKER_DIED
    assert {s for s, r in by_stem.items() if r.status == "ok"} == set(SMALL)
    assert not report.all_ok
    row = index_rows(out)[by_stem[CRASH_STEM].input]
    assert (row[1], row[-1]) == ("failed", WORKER_DIED)
    assert not (out / by_stem[CRASH_STEM].output).exists()


def _warm_workers(scheduler: str, folder: Path) -> None:
    """Run the refiner once on every worker: one restarted by an earlier test starts cold, and on a
    loaded machine its first import of OCP and cadedge alone can outlast the 10 s limit below."""
    from distributed import Client

    from cadedge.batch import refine_task

    options = {"ald": ALD, "min_length": None, "max_length": None, "max_growth": None}
    with Client(scheduler) as client:
        client.run(refine_task, str(FIXTURES / "cylinder.step"), str(folder / "warm.json"), options)


def test_hung_task_times_out_and_the_rest_finish(tmp_path, scheduler):
    _warm_workers(scheduler, tmp_path)
    copy_fixtures(tmp_path / "in", ["cylinder", "sphere"])
    shutil.copy(FIXTURES / "sphere.step", tmp_path / "in" / f"{HANG_STEM}.step")
    report = run_batch([tmp_path / "in"], tmp_path / "out", ald=ALD, scheduler=scheduler, timeout=10,
                       task=hang_or_refine)
    by_stem = {Path(r.input).stem: r for r in report.results}
    hung = by_stem.pop(HANG_STEM)
    assert hung.status == "failed" and hung.error.startswith("timed out after 10 s"), hung.error
    assert "worker restarted" in hung.error
    assert all(r.status == "ok" for r in by_stem.values()) and len(by_stem) == 2
    # the restarted worker takes work again
    again = run_batch([tmp_path / "in" / "cylinder.step"], tmp_path / "out2", ald=ALD, scheduler=scheduler)
    assert again.all_ok


def test_rerun_skips_finished_retries_failed_redoes_changed(tmp_path, scheduler):
    inputs = copy_fixtures(tmp_path / "in", ["cylinder", "sphere", "open_face"])
    bad = tmp_path / "in" / "bad.step"
    bad.write_text("ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n")
    out = tmp_path / "out"
    first = run_batch([tmp_path / "in"], out, ald=ALD, scheduler=scheduler)
    assert len(first.ok) == 3 and [Path(r.input).name for r in first.failed] == ["bad.step"]
    assert first.failed[0].error and "bad.step" in first.failed[0].error
    assert list(first.phases) == ["plan", "start", "run", "close"]
    assert all(s >= 0 for s in first.phases.values()) and sum(first.phases.values()) <= first.seconds

    second = run_batch([tmp_path / "in"], out, ald=ALD, scheduler=scheduler)
    assert (len(second.skipped), len(second.skipped_failed), second.results) == (3, 1, [])
    assert not second.all_ok
    assert list(second.phases) == ["plan"]  # nothing due: no cluster, no scheduler reached

    retried = run_batch([tmp_path / "in"], out, ald=ALD, scheduler=scheduler, retry_failed=True)
    assert [Path(r.input).name for r in retried.results] == ["bad.step"] and len(retried.skipped) == 3

    shutil.copy(FIXTURES / "helix_wire.step", bad)            # the bad input is fixed
    (out / "sphere.json").unlink()                            # an output went missing
    os.utime(inputs[0], ns=(1, 1))                            # an input changed (mtime)
    fixed = run_batch([tmp_path / "in"], out, ald=ALD, scheduler=scheduler)
    assert fixed.all_ok
    assert sorted(Path(r.input).name for r in fixed.results) == ["bad.step", "cylinder.step", "sphere.step"]
    assert fixed.skipped == [str(inputs[2].resolve())]

    finer = run_batch([tmp_path / "in"], out, ald=ALD / 2, scheduler=scheduler)  # new options redo all
    assert len(finer.ok) == 4 and not finer.skipped
    assert all(json.loads((out / r.output).read_text())["options"]["ald"] == ALD / 2 for r in finer.results)

    inputs[2].write_text("no longer a STEP file\n")            # an input breaks: its old output goes
    broken = run_batch([tmp_path / "in"], out, ald=ALD / 2, scheduler=scheduler)
    assert [Path(r.input).name for r in broken.failed] == ["open_face.step"]
    assert not (out / "open_face.json").exists() and (out / "cylinder.json").exists()


def test_unreachable_scheduler_is_an_input_error(tmp_path):
    import dask

    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}), \
            pytest.raises(InputError, match="cannot connect to dask scheduler tcp://127.0.0.1:9"):
        run_batch([FIXTURES / "sphere.step"], tmp_path / "out", scheduler="tcp://127.0.0.1:9")


def test_scheduler_without_workers_is_an_input_error(tmp_path):
    import dask

    with local_cluster(0) as empty, dask.config.set({"distributed.comm.timeouts.connect": "2s"}), \
            pytest.raises(InputError, match="has no workers"):
        run_batch([FIXTURES / "sphere.step"], tmp_path / "out", scheduler=empty.scheduler_address)


@pytest.mark.skipif(sys.platform == "win32", reason="no fork server on Windows")
def test_embedded_workers_fork_from_a_server_holding_occt_frozen(tmp_path):
    """The embedded cluster's workers fork from a server that imported OCCT and the task once, with the
    collector off and then frozen (cadedge.batch.preload): a worker holds them before its first file."""
    inputs = copy_fixtures(tmp_path / "in", ["sphere"])
    report = run_batch(inputs, tmp_path / "out", ald=ALD, workers=1, task=probe_and_refine)
    assert report.all_ok, report.results
    probe = json.loads((tmp_path / "out" / "sphere.probe").read_text())
    assert probe["ocp"] and probe["frozen"] > 100_000
    assert probe["blas_threads"] == os.environ.get("OPENBLAS_NUM_THREADS", "1")
