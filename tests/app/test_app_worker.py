"""The worker: results arrive on the GUI thread, Cancel stops at the next checkpoint, a newer run
makes an older one's result never land, exceptions become a failure signal."""

from __future__ import annotations

import threading
import time

import pytest

from skelscope.worker import TaskRunner
from skelcore.errors import Cancelled

pytestmark = pytest.mark.gui


def _slow_job(steps: int = 400, result: object = "done"):
    def job(progress, cancel):
        for i in range(steps):
            if cancel():
                raise Cancelled("stop")
            progress(i / steps, "counting")
            time.sleep(0.005)
        return result

    return job


def test_result_and_progress_arrive_on_the_gui_thread(qtbot):
    runner = TaskRunner()
    seen = {}
    progress = []
    runner.progressed.connect(lambda f, s: progress.append((f, s, threading.current_thread() is threading.main_thread())))
    runner.succeeded.connect(lambda name, r: seen.update(name=name, result=r, main=threading.current_thread() is threading.main_thread()))
    with qtbot.waitSignal(runner.finished, timeout=20000):
        runner.start(_slow_job(40, result=42), "count")
    assert seen == {"name": "count", "result": 42, "main": True}
    assert progress and all(main for _, _, main in progress)
    assert progress[0][1] == "counting"
    assert not runner.running


def test_cancel_stops_the_task_and_no_result_lands(qtbot):
    runner = TaskRunner()
    results = []
    runner.succeeded.connect(lambda name, r: results.append(r))
    task = runner.start(_slow_job(100000), "long")
    qtbot.waitUntil(lambda: task.isRunning(), timeout=5000)
    with qtbot.waitSignal(runner.cancelled, timeout=10000) as blocker:
        runner.cancel()
    assert blocker.args == ["long"]
    assert task.wait(10000)
    qtbot.wait(50)
    assert results == [] and not runner.running


def test_starting_a_new_run_drops_the_old_runs_result(qtbot):
    runner = TaskRunner()
    results = []
    runner.succeeded.connect(lambda name, r: results.append((name, r)))
    # The old job ignores cancel and finishes anyway: its result must still never land.
    old = runner.start(lambda progress, cancel: (time.sleep(0.3), "stale")[1], "old")
    with qtbot.waitSignal(runner.finished, timeout=20000):
        runner.start(_slow_job(5, result="fresh"), "new")
    assert old.wait(10000)
    qtbot.wait(100)
    assert results == [("new", "fresh")]


def test_an_exception_in_the_job_becomes_a_failure_signal(qtbot):
    runner = TaskRunner()

    def job(progress, cancel):
        raise RuntimeError("boom in the worker")

    with qtbot.waitSignal(runner.failed, timeout=10000) as blocker:
        runner.start(job, "bad")
    name, exc, tb = blocker.args
    assert name == "bad" and isinstance(exc, RuntimeError) and "boom in the worker" in tb
    qtbot.waitUntil(lambda: not runner.running, timeout=5000)
