"""An edit's scoring in two phases (docs/guide/viewer.md "Editing the curve skeleton"): the four metrics
first (``Evaluation.update(..., diagnostics=False)``: the curve recoloured, the Summary's scores), then
the curve's coverage, defects and missing parts (``Evaluation.complete_update``) in a second worker task,
``DEFECTS_TASK``. Until the second lands the shown evaluation is partial (:func:`defects_pending`): the
Defects dock says :data:`UPDATING`, no undo step, A/B view or mark keeps it; a further edit cancels it.
"""

from __future__ import annotations

import threading
from typing import Any, Callable

__all__ = ["DEFECTS_TASK", "UPDATE_LOCK", "UPDATING", "defects_pending", "scores_job", "defects_job"]

#: the second phase's worker task
DEFECTS_TASK = "defects"
#: what the Defects dock and the Summary say while it runs
UPDATING = "defects updating…"
UPDATE_LOCK = threading.Lock()  # Evaluation.update runs one at a time (they share the evaluation's caches)

Job = Callable[[Callable[[float, str], None], Callable[[], bool]], Any]


def defects_pending(ev: Any) -> bool:
    """``ev`` is an edit's first phase: the curve's coverage and defects are not in it yet."""
    return bool(getattr(ev, "diagnostics_left_out", ()))


def scores_job(base: Any, curve: Any) -> Job:
    """The first phase: ``base`` updated to ``curve``, the four metrics only."""

    def job(progress: Callable[[float, str], None], cancel: Callable[[], bool]) -> Any:
        from skelcore.errors import Cancelled

        progress(0.0, "scoring the edited curve")
        # one update at a time: a dropped one (an edit came meanwhile) may still run to its end in its
        # thread and shares the evaluation's caches; the next waits for it here, not in the window
        with UPDATE_LOCK:
            if cancel():
                raise Cancelled("the edited curve's scoring was cancelled")
            return base.update(curve, diagnostics=False)

    return job


def defects_job(partial: Any, start: threading.Event | None = None) -> Job:
    """The second phase: ``partial`` with the curve's coverage, defects and missing parts, once
    ``start`` is set (the first phase's frame painted: the two would share the interpreter's lock)."""

    def job(progress: Callable[[float, str], None], cancel: Callable[[], bool]) -> Any:
        from skelcore.errors import Cancelled

        progress(0.0, "finding the edited curve's defects")
        while start is not None and not start.wait(0.005):
            if cancel():
                raise Cancelled("the edited curve's defects were cancelled")
        with UPDATE_LOCK:
            if cancel():
                raise Cancelled("the edited curve's defects were cancelled")
            return partial.complete_update(cancel)

    return job
