"""Independent pieces of a stage on both cores: spans of work on a thread pool, checkpoints in order.

The compiled kernels release the GIL, and so do numpy's sorts, gathers and BLAS products on large arrays,
so threads share the cores without processes (no pickling, no copies).  Every span is computed exactly
as alone, so the results do not depend on the number of threads.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from typing import Callable

from .geometry import Checkpoint, no_checkpoint

__all__ = ["on_threads"]


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
