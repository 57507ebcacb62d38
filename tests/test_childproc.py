"""cadedge.childproc: a child started with child_env() that calls die_with_parent() ends with its caller,
through the kernel's parent-death signal or, where that is missing, the thread watching the parent."""

import subprocess
import sys

import pytest

psutil = pytest.importorskip("psutil")

from conftest import ROOT  # noqa: E402

CHILD = ("import sys, time, cadedge.childproc as c\n"
         "if sys.argv[1] == 'thread': c.PR_SET_PDEATHSIG = -1  # prctl refuses it: the watching thread\n"
         "c.die_with_parent()\n"
         "print('armed', flush=True)\n"
         "time.sleep(120)\n")
PARENT = ("import subprocess, sys, time\n"
          "from cadedge.childproc import child_env\n"
          "child = subprocess.Popen([sys.executable, '-c', sys.argv[1], sys.argv[2]], env=child_env(),\n"
          "                         stdout=subprocess.PIPE, text=True)\n"
          "assert child.stdout.readline().strip() == 'armed'\n"
          "print(child.pid, flush=True)\n"
          "time.sleep(120)\n")


@pytest.mark.parametrize("how", ["prctl", "thread"])
def test_a_child_ends_with_its_caller(how):
    parent = subprocess.Popen([sys.executable, "-c", PARENT, CHILD, how], cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        child = psutil.Process(int(parent.stdout.readline()))
        assert child.is_running()
        parent.kill()
        parent.wait(timeout=30)
        child.wait(timeout=30)  # psutil.TimeoutExpired: the child outlived its caller
    finally:
        parent.kill()


def test_without_a_named_parent_nothing_happens(monkeypatch):
    from cadedge.childproc import PARENT_ENV, die_with_parent

    monkeypatch.delenv(PARENT_ENV, raising=False)
    die_with_parent()  # the test process goes on
