"""skelcore.parallel: spans on threads and two computations side by side give what one thread gives;
a cancel or an error on either side reaches the caller, and no thread is left behind."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from skelcore.errors import Cancelled
from skelcore.metrics import topology
from skelcore.parallel import on_threads, polled_streams, side_by_side


def _no_side_thread() -> bool:
    return not [t for t in threading.enumerate() if t.name == "skelscope-side"]


def test_on_threads_runs_every_span_once_and_checks_in_order():
    seen, fractions = [], []
    on_threads(lambda a, b: seen.append((a, b)) or (a, b), [(i, i + 1) for i in range(37)], 3, fractions.append)
    assert sorted(seen) == [(i, i + 1) for i in range(37)]
    assert fractions[0] == 0.0 and fractions[-1] == 1.0 and fractions == sorted(fractions)


def test_side_by_side_returns_both_and_reports_the_side_progress_from_this_thread():
    me = threading.get_ident()
    calls = []

    def checkpoint(f):
        assert threading.get_ident() == me  # callbacks only ever from the caller's thread
        calls.append(f)

    def side(ck):
        for i in range(5):
            time.sleep(0.03)
            ck(i / 4)
        return "side"

    assert side_by_side(lambda ck: (ck(1.0), "main")[1], side, checkpoint) == ("main", "side")
    assert max(calls) <= 1.0 and any(0.5 < f for f in calls) and _no_side_thread()


def test_a_cancel_on_this_thread_stops_the_side_and_an_error_there_comes_here():
    started = threading.Event()
    side_checks = []

    def side(ck):
        started.set()
        while True:
            side_checks.append(1)
            ck(0.5)
            time.sleep(0.005)

    def main(ck):
        started.wait(5)
        raise Cancelled("stop")

    with pytest.raises(Cancelled):
        side_by_side(main, side)
    assert side_checks and _no_side_thread()

    def broken(ck):
        raise ValueError("side failed")

    with pytest.raises(ValueError, match="side failed"):
        side_by_side(lambda ck: 1, broken)
    assert _no_side_thread()


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
