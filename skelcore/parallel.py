"""Independent pieces of work on both cores: spans of a stage on a thread pool (checkpoints in order),
the independent stages of an evaluation side by side (``run_graph``), polled compiled kernels.

The compiled kernels release the GIL, and so do numpy's sorts, gathers and BLAS products on large arrays,
so threads share the cores without processes (no pickling, no copies).  Every span is computed exactly
as alone, so the results do not depend on the number of threads.
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Callable, Iterator

from .geometry import Checkpoint, no_checkpoint

__all__ = ["on_threads", "GraphTask", "run_graph", "polled_build", "polled_streams", "Cores", "pool_width"]


def on_threads(
    fn: Callable, spans: list, workers: int | None = None, checkpoint: Checkpoint = no_checkpoint,
    done: Callable | None = None,
) -> None:
    """``fn(*span)`` for every span on ``workers`` threads (None = all cores), a checkpoint after each
    in order; ``done(span, result)`` stores a result.  A short queue: a cancel stops within about one
    span per worker."""
    workers = max(1, int(workers or os.cpu_count() or 1))
    store = done or (lambda span, result: None)
    checkpoint(0.0)
    if workers == 1 or len(spans) <= 1:
        for i, span in enumerate(spans):
            store(span, fn(*span))
            checkpoint((i + 1) / len(spans))
        return
    with ThreadPoolExecutor(max_workers=workers) as pool:
        pending: list = []
        it = iter(spans)
        try:
            for span in it:
                pending.append((span, pool.submit(fn, *span)))
                if len(pending) >= 2 * workers:
                    break
            finished = 0
            while pending:
                span, fut = pending.pop(0)
                store(span, fut.result())
                finished += 1
                checkpoint(finished / len(spans))
                nxt = next(it, None)
                if nxt is not None:
                    pending.append((nxt, pool.submit(fn, *nxt)))
        finally:
            for _, fut in pending:
                fut.cancel()


class Cores:
    """The cores shared by the lanes of a :func:`run_graph` and the compiled streams their stages start.

    A lane holds a core while it runs a task; a stage that waits on its streams (:func:`polled_streams`)
    lends its lane's core to them, and each stream takes a core per span, never while a lane waits for
    one.  So the compiled kernel runs on the cores the Python stages (which hold the GIL) leave free and
    on every core once none is left to run: two of those stages side by side share one core's worth of
    GIL, while the kernel beside them loses nothing (docs/performance.md 3).
    """

    def __init__(self, n: int):
        self._free = n
        self._lanes_waiting = 0
        self._cond = threading.Condition()

    def take(self, lane: bool) -> None:
        with self._cond:
            self._lanes_waiting += lane
            try:
                while self._free == 0 or (not lane and self._lanes_waiting):
                    self._cond.wait()
                self._free -= 1
            finally:
                self._lanes_waiting -= lane

    def give(self, n: int = 1) -> None:
        with self._cond:
            self._free += n
            self._cond.notify_all()

    def take_free(self, most: int) -> int:
        """Up to ``most`` of the free cores, taken at once (none while a lane waits for one): how many."""
        with self._cond:
            got = 0 if self._lanes_waiting else max(0, min(most, self._free))
            self._free -= got
            return got


# the Cores of the run_graph lane this thread is (unset outside run_graph: streams take every core)
_lane = threading.local()


@dataclass(frozen=True)
class GraphTask:
    """One piece of work for :func:`run_graph`: ``fn()`` once every task named in ``after`` is done."""

    name: str
    fn: Callable[[], object]
    after: tuple[str, ...] = ()


def run_graph(tasks: list[GraphTask], workers: int | None = None, on_error: Callable[[], None] | None = None) -> dict:
    """Every task's result by name, the tasks run on ``workers`` threads (None = all cores; this thread
    is one of them), each thread taking the first task in list order whose ``after`` tasks are done.

    For the independent stages of an evaluation (docs/performance.md 6.2): the long compiled ones first,
    the others beside them.  Each thread's first task is handed out, its core taken, before any starts:
    a compiled stage's streams then take only the cores no lane holds, and a lane started a moment later
    does not wait for one of its spans (on the hammer the Python stages started a stream span, ~13 ms,
    late: docs/performance.md 3, "The hammer's Python stages, cut").  At the first error
    ``on_error()`` is called (it should make the running tasks' checkpoints raise), no new task starts,
    every thread is joined and that first error is re-raised here.  A task's result does not depend on
    which thread ran it.
    """
    names = [t.name for t in tasks]
    if len(set(names)) != len(names) or any(a not in names for t in tasks for a in t.after):
        raise ValueError("run_graph: task names must be unique and every 'after' must name a task")
    workers = max(1, min(len(tasks), int(workers or os.cpu_count() or 1)))
    cores = Cores(max(workers, os.cpu_count() or 1))
    results: dict = {}
    started: set = set()
    done: set = set()
    errors: list = []
    cond = threading.Condition()

    def next_task() -> GraphTask | None:
        with cond:
            while not errors and len(started) < len(tasks):
                for t in tasks:
                    if t.name not in started and all(a in done for a in t.after):
                        started.add(t.name)
                        return t
                cond.wait()
            return None

    def first_tasks() -> list:
        """The first ready tasks in list order, one per thread (None: no task ready for it yet), each
        started and holding its core."""
        firsts = []
        for _ in range(workers):
            ready = next((t for t in tasks if t.name not in started and all(a in done for a in t.after)), None)
            if ready is not None:
                started.add(ready.name)
                cores.take(lane=True)
            firsts.append(ready)
        return firsts

    def work(first: GraphTask | None) -> None:
        _lane.cores = cores
        try:
            lane(first)
        finally:
            _lane.cores = None

    def lane(first: GraphTask | None) -> None:
        task = first
        if first is not None and errors:  # another lane failed before this one started: not begun
            cores.give()
            return
        while task is not None or (task := next_task()) is not None:
            if task is not first:
                cores.take(lane=True)
            first = None
            try:
                value = task.fn()
            except BaseException as exc:  # the first error wins; the others stop at a checkpoint
                with cond:
                    errors.append(exc)
                    cond.notify_all()
                if on_error is not None:
                    on_error()
                return
            finally:
                cores.give()
            with cond:
                results[task.name] = value
                done.add(task.name)
                cond.notify_all()
            task = None

    firsts = first_tasks()
    helpers = [threading.Thread(target=work, args=(firsts[i],), name=f"skelscope-lane-{i}", daemon=True)
               for i in range(1, workers)]
    for th in helpers:
        th.start()
    try:
        work(firsts[0])
    finally:
        for th in helpers:
            th.join()
    if errors:
        raise errors[0]
    return results


@contextmanager
def pool_width(workers: int | None) -> Iterator[int]:
    """The threads a stage's own pool of compiled pieces may use: ``workers`` (None: every core), but on a
    :func:`run_graph` lane its own core and the free ones it takes for the while (given back at the end),
    as the compiled streams take them. A pool as wide as the machine beside another lane's kernel
    streams put three threads on two cores: a pruned branch's update at 100k spent 12 ms more CPU
    with it (thread starts, hand-overs; docs/performance.md 6.10, "The second lane's pools")."""
    want = max(1, int(workers or os.cpu_count() or 1))
    cores = getattr(_lane, "cores", None)
    if cores is None or want == 1:
        yield want
        return
    got = cores.take_free(want - 1)
    try:
        yield 1 + got
    finally:
        cores.give(got)


def polled_build(build: Callable, n: int, checkpoint: Checkpoint, name: str, threaded_from: int = 65536,
                 progress: Callable[[], float] | None = None):
    """``build(stop)`` of a compiled kernel (which releases the GIL) in a thread while this one calls the
    checkpoint every 50 ms (with ``progress()``, else 0); a cancel sets ``stop`` (an int32 array the kernel
    reads), waits for the build to return and re-raises.  Below ``threaded_from`` points the build takes a
    few ms: no thread."""
    import numpy as np

    stop = np.zeros(1, np.int32)
    if n <= threaded_from:
        return build(stop)
    result: list = []
    worker = threading.Thread(target=lambda: result.append(build(stop)), name=name, daemon=True)
    worker.start()
    try:
        while worker.is_alive():
            worker.join(0.05)
            checkpoint(progress() if progress is not None else 0.0)
    except BaseException:
        stop[0] = 1
        worker.join()
        raise
    return result[0]



def polled_streams(
    fn: Callable, spans: list, workers: int | None, checkpoint: Checkpoint, progress: Callable[[], float],
    stop, poll: float = 0.05,
) -> None:
    """``fn(*span)`` for every span on ``workers`` threads (None = all cores), while this thread calls
    ``checkpoint(progress())`` every ``poll`` s.

    For compiled code that releases the GIL, keeps state from one item to the next inside a span (so
    spans should be long) and returns early once ``stop[0]`` is set: a cancel (or any error) raised by
    the checkpoint sets it, waits for the threads and is re-raised; an error in a span is re-raised here
    after the others have stopped.  Only this thread calls ``checkpoint``.
    """
    if not spans:
        return
    workers = max(1, min(len(spans), int(workers or os.cpu_count() or 1)))
    checkpoint(progress())
    cores = getattr(_lane, "cores", None)
    if cores is None:
        _streams(fn, spans, workers, checkpoint, progress, stop, poll)
        return

    def gated(*span):
        cores.take(lane=False)
        try:
            return fn(*span)
        finally:
            cores.give()

    cores.give()  # this lane only polls: its core is the streams'
    try:
        _streams(gated, spans, workers, checkpoint, progress, stop, poll)
    finally:
        cores.take(lane=True)


def _streams(fn: Callable, spans: list, workers: int, checkpoint: Checkpoint, progress: Callable[[], float],
             stop, poll: float) -> None:
    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="skelscope-stream") as pool:
        futures = [pool.submit(fn, *span) for span in spans]
        try:
            pending = set(futures)
            while pending:
                finished, pending = wait(pending, timeout=poll, return_when=FIRST_EXCEPTION)
                for fut in finished:
                    fut.result()  # an error in a span: raised here
                checkpoint(progress())
        except BaseException:
            stop[0] = 1
            for fut in futures:
                fut.cancel()
            wait(futures)
            raise
