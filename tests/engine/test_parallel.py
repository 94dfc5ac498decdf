"""skelcore.parallel: spans on threads and two computations side by side give what one thread gives;
a cancel or an error on either side reaches the caller, and no thread is left behind."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from skelcore.errors import Cancelled
from skelcore.parallel import GraphTask, on_threads, polled_streams, run_graph


def _no_lane_thread() -> bool:
    return not [t for t in threading.enumerate() if t.name.startswith("skelscope-lane")]


def test_on_threads_runs_every_span_once_and_checks_in_order():
    seen, fractions = [], []
    on_threads(lambda a, b: seen.append((a, b)) or (a, b), [(i, i + 1) for i in range(37)], 3, fractions.append)
    assert sorted(seen) == [(i, i + 1) for i in range(37)]
    assert fractions[0] == 0.0 and fractions[-1] == 1.0 and fractions == sorted(fractions)


def test_run_graph_runs_tasks_side_by_side_after_what_they_need():
    both = threading.Barrier(2, timeout=5)  # two tasks must run at the same time to pass it
    order = []

    def step(name, value, meet=False):
        def fn():
            if meet:
                both.wait()
            order.append(name)
            return value

        return GraphTask(name, fn, () if name != "c" else ("a", "b"))

    tasks = [step("a", 1, meet=True), step("b", 2, meet=True), step("c", 3)]
    assert run_graph(tasks, workers=2) == {"a": 1, "b": 2, "c": 3}
    assert order[-1] == "c" and _no_lane_thread()
    # one worker: the list order, on this thread
    me = threading.get_ident()
    seen = []
    run_graph([GraphTask(n, lambda n=n: seen.append((n, threading.get_ident()))) for n in "xyz"], workers=1)
    assert seen == [("x", me), ("y", me), ("z", me)]
    with pytest.raises(ValueError, match="every 'after'"):
        run_graph([GraphTask("a", lambda: 1, ("nope",))])


def test_run_graph_stops_every_task_at_the_first_error_and_raises_it():
    stop = threading.Event()
    checks = []

    def long_task():
        while True:  # a stage polling its checkpoint
            checks.append(1)
            if stop.is_set():
                raise Cancelled("stopped beside a failure")
            time.sleep(0.005)

    def broken():
        while not checks:
            time.sleep(0.005)
        raise ValueError("stage failed")

    ran = []
    tasks = [GraphTask("long", long_task), GraphTask("broken", broken),
             GraphTask("later", lambda: ran.append(1), ("broken",))]
    with pytest.raises(ValueError, match="stage failed"):
        run_graph(tasks, workers=2, on_error=stop.set)
    assert stop.is_set() and not ran and _no_lane_thread()


def _no_stream_thread() -> bool:
    return not [t for t in threading.enumerate() if t.name.startswith("skelscope-stream")]


def test_polled_streams_run_every_span_and_report_progress_from_this_thread():
    me = threading.get_ident()
    done = np.zeros(6, np.int64)
    stop = np.zeros(1, np.int32)
    fractions = []

    def span(i):
        for _ in range(4):
            time.sleep(0.01)
            done[i] += 1

    def checkpoint(f):
        assert threading.get_ident() == me
        fractions.append(f)

    polled_streams(span, [(i,) for i in range(6)], 2, checkpoint, lambda: done.sum() / 24, stop, poll=0.005)
    assert done.tolist() == [4] * 6 and stop[0] == 0
    assert fractions[0] == 0.0 and fractions[-1] == 1.0 and fractions == sorted(fractions) and len(fractions) > 3
    assert _no_stream_thread()


def test_a_cancel_sets_the_stop_flag_and_waits_for_the_streams_and_an_error_in_one_stops_the_others():
    stop = np.zeros(1, np.int32)
    returned = []

    def span(i):  # like the kernel: works until the stop flag is set
        while not stop[0]:
            time.sleep(0.002)
        returned.append(i)

    calls = [0]

    def cancel_at_second(f):
        calls[0] += 1
        if calls[0] == 2:
            raise Cancelled("stop")

    with pytest.raises(Cancelled):
        polled_streams(span, [(0,), (1,)], 2, cancel_at_second, lambda: 0.0, stop, poll=0.01)
    assert stop[0] == 1 and sorted(returned) == [0, 1] and _no_stream_thread()

    stop[0] = 0

    def failing(i):
        if i == 1:
            raise ValueError("bad span")
        while not stop[0]:
            time.sleep(0.002)

    with pytest.raises(ValueError, match="bad span"):
        polled_streams(failing, [(0,), (1,)], 2, lambda f: None, lambda: 0.0, stop, poll=0.01)
    assert stop[0] == 1 and _no_stream_thread()


def _spans_beside(busy_lane: bool, monkeypatch) -> tuple[int, int]:
    """(most spans of a stage's streams running at once while the other lane ran a stage, most at all):
    two cores, a stage waiting on 24 streams of 20 ms and, when ``busy_lane``, a stage of 0.15 s beside
    it on the other lane, started once the streams have."""
    import skelcore.parallel as parallel

    monkeypatch.setattr(parallel.os, "cpu_count", lambda: 2)
    lock = threading.Lock()
    running, most, most_beside = [0], [0], [0]
    other_busy, streaming = threading.Event(), threading.Event()

    def span(i: int) -> None:
        streaming.set()
        with lock:
            running[0] += 1
            most[0] = max(most[0], running[0])
            if other_busy.is_set():
                most_beside[0] = max(most_beside[0], running[0])
        time.sleep(0.02)
        with lock:
            running[0] -= 1

    def kernel_stage() -> None:
        polled_streams(span, [(i,) for i in range(24)], None, lambda f: None, lambda: 0.0, np.zeros(1, np.int32))

    def python_stage() -> None:
        streaming.wait(5.0)
        other_busy.set()
        time.sleep(0.15)
        other_busy.clear()

    tasks = [GraphTask("kernel", kernel_stage)] + ([GraphTask("python", python_stage)] if busy_lane else [])
    run_graph(tasks, 2)
    return most_beside[0], most[0]


def test_a_kernels_streams_take_the_cores_the_other_lane_leaves_free(monkeypatch):
    """parallel.Cores: while the other lane runs a stage, one stream runs; once it is done, two."""
    beside, most = _spans_beside(True, monkeypatch)
    assert beside == 1 and most == 2
    assert _spans_beside(False, monkeypatch) == (0, 2)
    assert _no_lane_thread()


def test_a_lanes_first_task_holds_its_core_before_any_stream_starts(monkeypatch):
    """run_graph hands each lane its first task and core before any runs: a lane whose thread starts
    late still finds its core, not both taken by the other lane's streams."""
    import skelcore.parallel as parallel

    monkeypatch.setattr(parallel.os, "cpu_count", lambda: 2)

    class LateThread(threading.Thread):
        def run(self):
            if self.name.startswith("skelscope-lane"):
                time.sleep(0.1)  # the helper lane begins after the other lane's streams have
            super().run()

    monkeypatch.setattr(parallel.threading, "Thread", LateThread)
    python_started = threading.Event()
    waited_out = []

    def span(i: int) -> None:
        if not python_started.wait(2.0):  # a stream waits for the Python stage to begin
            waited_out.append(i)

    def kernel_stage() -> None:
        polled_streams(span, [(i,) for i in range(4)], None, lambda f: None, lambda: 0.0, np.zeros(1, np.int32))

    run_graph([GraphTask("kernel", kernel_stage), GraphTask("python", python_started.set)], 2)
    assert waited_out == []
    assert _no_lane_thread()


def _search_threads(beside_streams: bool, monkeypatch) -> tuple[set, int]:
    """(the threads that ran a ball-tree search's pieces other than its lane's own, the free cores after):
    two cores, the search on a run_graph lane, with another lane's kernel streams holding the other core
    when ``beside_streams``."""
    import skelcore.parallel as parallel
    from skelcore.geometry import no_checkpoint
    from skelcore.metrics import ball_tree

    monkeypatch.setattr(parallel.os, "cpu_count", lambda: 2)
    monkeypatch.setattr(ball_tree.os, "cpu_count", lambda: 2)
    streaming, searched = threading.Event(), threading.Event()
    ran, lane_of_search, free_after = set(), [], []

    def span(i: int) -> None:
        streaming.set()
        searched.wait(5.0)

    def kernel_stage() -> None:
        polled_streams(span, [(0,)], None, lambda f: None, lambda: 0.0, np.zeros(1, np.int32))

    def piece(lo: int, hi: int) -> None:
        ran.add(threading.get_ident())
        time.sleep(2e-5 * (hi - lo))

    def search_stage() -> None:
        if beside_streams:
            streaming.wait(5.0)
        lane_of_search.append(threading.get_ident())
        ball_tree._chunked(piece, 3 * ball_tree.THREAD_ROWS, no_checkpoint)
        free_after.append(parallel._lane.cores._free)
        searched.set()

    run_graph(([GraphTask("kernel", kernel_stage)] if beside_streams else []) + [GraphTask("search", search_stage)], 2)
    return ran - set(lane_of_search), free_after[0]


def test_a_stages_own_pool_takes_only_the_cores_its_lane_finds_free(monkeypatch):
    """parallel.pool_width: beside another lane's streams a ball tree's search runs on its lane alone; with
    the other core free it takes it for a pool of two and gives it back; off a lane, every core."""
    import skelcore.parallel as parallel

    others, free = _search_threads(True, monkeypatch)
    assert others == set() and free == 0  # the streams' core, the search's lane
    others, free = _search_threads(False, monkeypatch)
    assert len(others) >= 1 and free == 1  # the lane's core held, the taken one given back
    with parallel.pool_width(None) as width:
        assert width == 2
    assert _no_lane_thread()
