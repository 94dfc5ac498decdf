"""Independent pieces of a stage on both cores: spans of work on a thread pool, checkpoints in order.

The compiled kernels release the GIL, and so do numpy's sorts, gathers and BLAS products on large arrays,
so threads share the cores without processes (no pickling, no copies).  Every span is computed exactly
as alone, so the results do not depend on the number of threads.
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait
from typing import Callable, TypeVar

from .errors import Cancelled
from .geometry import Checkpoint, no_checkpoint

A = TypeVar("A")
B = TypeVar("B")

__all__ = ["on_threads", "side_by_side", "polled_build", "polled_streams"]


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


def side_by_side(
    main: Callable[[Checkpoint], A], side: Callable[[Checkpoint], B], checkpoint: Checkpoint = no_checkpoint,
    split: float = 0.5, poll: float = 0.05,
) -> tuple[A, B]:
    """``(main(ck), side(ck2))`` with ``side`` on a second thread while ``main`` runs on this one.

    Only this thread calls ``checkpoint`` (callers' callbacks need not be thread-safe): ``main``'s
    progress maps to [0, split], then, while this thread waits for ``side`` (polling every ``poll`` s),
    ``side``'s own progress to [split, 1].  A cancel raised here stops ``side`` at its next checkpoint
    and is re-raised once it has; an error in ``side`` is re-raised here.  Both are computed exactly as
    one after the other, so the results do not depend on it.
    """
    stop = threading.Event()
    side_done = [0.0]
    box: dict = {}

    def side_checkpoint(fraction: float) -> None:
        side_done[0] = fraction
        if stop.is_set():
            raise Cancelled("cancelled")

    def run_side() -> None:
        try:
            box["value"] = side(side_checkpoint)
        except BaseException as exc:  # handed to the caller's thread
            box["error"] = exc

    worker = threading.Thread(target=run_side, name="skelscope-side", daemon=True)
    worker.start()
    try:
        first = main(lambda f: checkpoint(split * f))
        while worker.is_alive():
            worker.join(poll)
            checkpoint(split + (1.0 - split) * min(max(side_done[0], 0.0), 1.0))
    except BaseException:
        stop.set()
        worker.join()
        raise
    if "error" in box:
        raise box["error"]
    return first, box["value"]


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
