"""One progress bar and one cancel button for stages that may run side by side: each stage's fraction
weighted by its cost (the catalogue's weights) into one overall fraction, throttled, and ``cancel``
checked at every checkpoint (STYLE.md: napari's and Orange3's habits)."""

from __future__ import annotations

import threading
import time
from typing import Callable

from ..errors import Cancelled

__all__ = ["Progress", "StageProgress"]

Progress = Callable[[float, str], None]


class StageProgress:
    """Turns per-stage fractions into one overall fraction; checks ``cancel`` at every call.

    Stages may run side by side on several threads (:func:`skelcore.parallel.run_graph`): the caller's
    ``progress`` is called under a lock (never from two threads at once) with the weighted sum of every
    stage's fraction, and once :meth:`abort` has been called (a stage failed or was cancelled) every
    checkpoint raises, so the stages beside it stop too.  ``weights``: relative cost by stage name.
    ``on_stages(names)`` is called (under the same lock) whenever the set of running stages changes,
    with every stage running side by side in the order they started: a label naming only the stage
    that reported last would flip between them."""

    def __init__(self, weights: dict[str, float], progress: Progress | None, cancel: Callable[[], bool] | None,
                 on_stages: Callable[[tuple[str, ...]], None] | None = None):
        total = sum(weights[n] for n in weights) or 1.0
        self._size = {n: weights[n] / total for n in weights}
        self._done = {n: 0.0 for n in weights}
        self._progress = progress
        self._cancel = cancel
        self._aborted = threading.Event()
        self._lock = threading.Lock()
        self._last = -1.0
        self._last_stage = ""
        self._on_stages = on_stages
        self.running: tuple[str, ...] = ()  # the stages running now, in the order they started
        self.timings: dict[str, float] = {}

    def abort(self) -> None:
        self._aborted.set()

    def _stop_if_asked(self, stage: str) -> None:
        if self._aborted.is_set() or (self._cancel is not None and self._cancel()):
            raise Cancelled(f"cancelled during {stage}")

    def checkpoint(self, stage: str) -> Callable[[float], None]:
        def check(fraction: float) -> None:
            self._stop_if_asked(stage)
            if self._progress is not None:
                with self._lock:
                    self._stop_if_asked(stage)  # a stage beside may have been cancelled while this one waited
                    self._done[stage] = max(self._done[stage], min(max(fraction, 0.0), 1.0))
                    overall = sum(self._size[n] * f for n, f in self._done.items())
                    # throttled (Orange3's habit), but a new stage is shown at once: the label names
                    # the stage that reported last
                    if stage != self._last_stage or overall - self._last >= 0.005 or fraction >= 1.0:
                        overall = min(max(overall, self._last), 1.0)  # never back (or past 1) by a rounding error
                        self._last = overall
                        self._last_stage = stage
                        self._progress(overall, stage)

        return check

    def between(self, what: str) -> Callable[[float], None]:
        """A checkpoint for work between stages (the trust checks): cancel only, no progress."""

        def check(_fraction: float) -> None:
            if self._cancel is not None and self._cancel():
                raise Cancelled(f"cancelled during {what}")

        return check

    def _set_running(self, stage: str, on: bool) -> None:
        with self._lock:
            running = tuple(s for s in self.running if s != stage) + ((stage,) if on else ())
            if running != self.running:
                self.running = running
                if self._on_stages is not None and not self._aborted.is_set():
                    self._on_stages(running)

    def run(self, stage: str, fn, *args, **kwargs):
        """``fn(*args, checkpoint=..., **kwargs)`` as stage ``stage``: checked at its start and end, timed."""
        check = self.checkpoint(stage)
        self._set_running(stage, True)
        try:
            check(0.0)
            t0 = time.perf_counter()
            out = fn(*args, checkpoint=check, **kwargs)
            self.timings[stage] = time.perf_counter() - t0
            check(1.0)
        finally:
            self._set_running(stage, False)
        return out
