"""Where a repair's time goes (docs/repair.md "Where the time goes, phase by phase"): CPU seconds of the
process (all threads, ``time.process_time``) and the number of times each phase ran, so that a run
says what it spent without a profiler: the first evaluation, each candidate's first look, the whole
updates of those that pass it (their defects), the proposals, the re-centrings' cross-sections and
the last Evaluation's real-scan trust checks (when its update left them out, ``screen.whole_update``).
It only reads the clock: no decision of the repair depends on it."""

from __future__ import annotations

import time
from contextlib import contextmanager
from typing import Iterator

__all__ = ["PHASES", "PhaseClock"]

#: the phases timed, in the order a round meets them
PHASES = ("first evaluation", "proposals", "re-centring cuts", "first look", "whole update", "scan checks")


class PhaseClock:
    """CPU seconds and counts per phase of :data:`PHASES`."""

    def __init__(self) -> None:
        self.cpu = dict.fromkeys(PHASES, 0.0)
        self.count = dict.fromkeys(PHASES, 0)

    @contextmanager
    def phase(self, name: str) -> Iterator[None]:
        """Time the ``with`` block as ``name`` (one more run of it)."""
        t0 = time.process_time()
        try:
            yield
        finally:
            self.cpu[name] += time.process_time() - t0
            self.count[name] += 1

    def table(self) -> dict[str, dict[str, float | int]]:
        """``{phase: {"cpu": seconds rounded to 0.01, "n": runs}}``."""
        return {k: {"cpu": round(self.cpu[k], 2), "n": self.count[k]} for k in PHASES}
