"""Frame scheduling for the 3D view: many scene changes, one frame, drawn after Qt's own repaint.

A frame costs tens to hundreds of ms in software GL, so the view never renders per change: it asks
for a frame, and work that should follow the frame (the plots) waits for the paint to be reported.
While frames are held (an edit's scores on their way) the window's other repaints wait too
(:mod:`.paint_hold`).
"""

from __future__ import annotations

import time
import weakref
from typing import Any, Callable

from PySide6 import QtCore

from .paint_hold import WindowPaintHold

__all__ = ["RENDER_DELAY_MS", "FrameScheduler"]

RENDER_DELAY_MS = 10
"""A requested frame is drawn this long after the request: after Qt's own repaint of the widgets the
same change touched, which Qt schedules 5 ms after the change (QT_QPA_UPDATE_IDLE_TIME)."""


class FrameScheduler:
    """Coalesces frame requests for one ``DropInteractor`` and runs callbacks once a frame is painted."""

    def __init__(self, plotter: Any) -> None:
        self.plotter = plotter
        self._pending = False
        self._after_frame: list[Callable[[], None]] = []
        # A timer, not a posted call: Qt runs posted events back to back, before any timer or input,
        # so a frame queued that way would stall the window together with whatever queued it.
        self._timer = QtCore.QTimer()
        self._timer.setSingleShot(True)
        self._timer.setInterval(RENDER_DELAY_MS)
        self._timer.timeout.connect(self._render_now)
        self._held_until = 0.0  # time.monotonic() before which a requested frame waits (hold)
        me = weakref.ref(self)  # no reference cycle: a Qt object is freed where its last reference goes
        self._window_hold = WindowPaintHold(lambda: (s := me()) is not None and s.held)  # the window's repaints wait with the frames
        self._hold_end = QtCore.QTimer()  # a hold that runs out unreleased ends as a release would
        self._hold_end.setSingleShot(True)
        self._hold_end.timeout.connect(self.release)  # (a coarse timer may fire a little early)
        plotter.on_frame = self.frame_done

    def request(self) -> None:
        """Render once, soon, however many scene changes arrive meanwhile (a frame costs tens to
        hundreds of ms in software GL).

        The frame is drawn by a timer started when the current event's handlers are done and firing
        RENDER_DELAY_MS later: after Qt's own repaint of the panels the same change updated, with
        the event loop turning (input, timers) in between, so the two are two short stalls, not one.
        """
        if not self._pending:
            self._pending = True
            # the delay given each time: a frame that waited out a hold restarted the timer with the
            # hold's remainder, which QTimer.start(ms) keeps as its interval
            QtCore.QTimer.singleShot(0, self._timer, lambda: self._timer.start(RENDER_DELAY_MS))

    @property
    def pending(self) -> bool:
        return self._pending

    def after_frame(self, fn: Callable[[], None]) -> None:
        """Call ``fn`` once the pending frame has been painted (at once if none is pending), so work
        that follows a change (the plots) starts after the frame, never in the same event-loop turn."""
        if self._pending:
            if fn not in self._after_frame:
                self._after_frame.append(fn)
        else:
            fn()

    @property
    def held(self) -> bool:
        """A :meth:`hold` is on (neither released nor run out)."""
        return self._held_until > time.monotonic()

    def hold(self, seconds: float) -> None:
        """Requested frames wait at most ``seconds`` (or until :meth:`release`): a change whose
        follow-up is on its way (an edited curve, its scores) makes one frame, not two. The window's
        other repaints wait with them (:mod:`.paint_hold`): each composes the whole window, whose
        CPU the follow-up's computation needs."""
        seconds = max(0.0, float(seconds))
        self._held_until = time.monotonic() + seconds
        self._window_hold.watch(self.plotter.window())
        self._hold_end.start(int(seconds * 1000) + 1)

    def release(self) -> None:
        """End a :meth:`hold`: a pending frame is drawn now (after the usual delay), and the window's
        deferred repaint is asked for (the pending frame's repaint, when there is one)."""
        self._held_until = 0.0
        self._hold_end.stop()
        if self._pending:
            self._timer.start(RENDER_DELAY_MS)
        else:
            self._window_hold.resume()

    def draw_now(self) -> None:
        """Draw the pending frame at once, held or not, before Qt repaints the panels the same change
        updated (an edit's recoloured curve: the frame the user waits for, the panels' text after it;
        docs/performance.md 6.10)."""
        self._held_until = 0.0
        self._hold_end.stop()
        if self._pending:
            self._render_now()  # its repaint paints the window's deferred regions with it
        self._window_hold.resume()

    def _render_now(self) -> None:
        if not self._pending:
            return
        wait = self._held_until - time.monotonic()
        if wait > 0:
            self._timer.start(max(1, int(wait * 1000)))
            return
        if getattr(self.plotter, "_closed", False) or not self.plotter.isVisible():
            self.frame_done()  # nothing to paint: whatever waited for the frame goes ahead
            self._window_hold.resume()
            return
        # A repaint of the view now, not plotter.render() (pyvistaqt's paintGL always renders, so
        # render() followed by the paint it causes would draw every frame twice) and not update()
        # (whose paint Qt would merge with its next repaint of the other widgets). Its paintGL calls
        # frame_done, here or, when Qt defers the repaint, in Qt's next repaint.
        self.plotter.repaint()

    def frame_done(self) -> None:
        """A frame was painted: it shows every change so far, so no other frame is pending."""
        self._timer.stop()
        self._pending = False
        callbacks, self._after_frame = self._after_frame, []
        for fn in callbacks:
            fn()

    def close(self) -> None:
        """Stop scheduling: the plotter no longer reports frames and waiting callbacks are dropped."""
        self.plotter.on_frame = None
        self._timer.stop()
        self._hold_end.stop()
        self._window_hold.close()
        self._after_frame.clear()
