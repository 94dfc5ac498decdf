"""Python's cyclic garbage collection run on the GUI thread while a window is open.

The automatic collection runs in whichever thread allocates past a threshold: the engine's worker
thread too. A collection there that frees a Qt object left in a reference cycle (a closed window's
helper) runs Qt's disconnect in that thread, under a Qt lock, and waits for the interpreter lock,
while the GUI thread, holding the interpreter lock, waits in a destructor for the same Qt lock: the
window never answers again. While a window is open the automatic collection is off and a timer on
the GUI thread collects the generations whose thresholds were passed, as the interpreter would
(docs/guide/viewer.md, "Opening data", **Threads**).
"""

from __future__ import annotations

import gc

import shiboken6
from PySide6 import QtCore

__all__ = ["GuiCollector", "CollectorHold", "gui_collector", "COLLECT_INTERVAL_MS"]

#: how often the GUI thread looks at the collector's counts (a generation-0 collection takes well
#: under a millisecond)
COLLECT_INTERVAL_MS = 200


class GuiCollector(QtCore.QObject):
    """Counts the windows that need collection on the GUI thread: the first :meth:`acquire` turns
    the automatic collection off and starts the timer, the last :meth:`release` restores it."""

    def __init__(self, interval_ms: int = COLLECT_INTERVAL_MS) -> None:
        super().__init__()
        self._users = 0
        self._was_enabled = False
        self._timer = QtCore.QTimer(self)
        self._timer.setInterval(int(interval_ms))
        self._timer.timeout.connect(self.collect_due)

    @property
    def users(self) -> int:
        """The windows holding it (the automatic collection is off while there is one)."""
        return self._users

    def acquire(self) -> None:
        if self._users == 0:
            self._was_enabled = gc.isenabled()
            gc.disable()
            self._timer.start()
        self._users += 1

    def release(self) -> None:
        if self._users == 0:
            return
        self._users -= 1
        if self._users == 0:
            if shiboken6.isValid(self._timer):  # not at the process's end, Qt's objects already gone
                self._timer.stop()
            if self._was_enabled:
                gc.enable()

    def collect_due(self) -> int:
        """Collect the oldest generation whose count passed its threshold (none: nothing); the
        number of objects freed."""
        counts, thresholds = gc.get_count(), gc.get_threshold()
        for generation in (2, 1, 0):
            if thresholds[generation] and counts[generation] > thresholds[generation]:
                return gc.collect(generation)
        return 0


_collector: GuiCollector | None = None


def gui_collector() -> GuiCollector:
    """The process's one collector, made on first use (on the GUI thread: its timer lives there)."""
    global _collector
    if _collector is None:
        _collector = GuiCollector()
    return _collector


class CollectorHold:
    """One window's share of :func:`gui_collector`, taken at once and given back once (at the window's
    close, else when it is destroyed); holds no reference to the window."""

    def __init__(self) -> None:
        self.held = True
        gui_collector().acquire()

    def release(self, *_: object) -> None:
        if self.held:
            self.held = False
            gui_collector().release()
