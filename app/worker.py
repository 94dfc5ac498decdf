"""Engine work (evaluate, skeletonize) in a worker thread, with progress, cancel and no stale results.

The job function gets ``progress(fraction, stage)`` and ``cancel()`` and passes them to skelcore,
which checks ``cancel`` at its checkpoints and raises ``Cancelled``. Cancel takes effect in the window
at once: the task is disconnected and whatever it still delivers is dropped, while its thread winds
down at the engine's next checkpoint. The thread is a plain daemon ``threading.Thread`` (not a
``QThread``, whose object destroyed while running aborts the process): closing the window cancels and
detaches every task, and the process exits with a thread still inside numpy (:meth:`TaskRunner.shutdown`
waits a bounded time, for scripts).
Following Orange3's ``concurrent`` helpers, a new task first retires the old one; progress is
throttled to visible steps. Only plain Python objects cross threads: VTK stays on the GUI thread.
Big evaluations run in a child process instead (:class:`ProcessTask`, :mod:`skelscope.engine_process`),
where Cancel is a kill. The stage shown names every stage running side by side (:func:`stage_label`).
"""

from __future__ import annotations

import threading
import time
import traceback
from typing import Any, Callable

from PySide6 import QtCore

from skelcore.errors import Cancelled

__all__ = ["Task", "ProcessTask", "TaskRunner", "SHUTDOWN_WAIT_S", "THREAD_PREFIX", "threads_alive", "stage_label"]

JobFunction = Callable[[Callable[[float, str], None], Callable[[], bool]], Any]

SHUTDOWN_WAIT_S = 1.5
"""How long :meth:`TaskRunner.shutdown` (scripts, the scripted mode, tests) waits, in all, for cancelled
tasks to reach a checkpoint. Closing the window waits for none (it cancels and detaches them)."""


THREAD_PREFIX = "skelscope-task-"


def threads_alive() -> bool:
    """Whether any task thread (of any runner) is still running, e.g. after a bounded shutdown."""
    return any(t.name.startswith(THREAD_PREFIX) and t.is_alive() for t in threading.enumerate())


def stage_label(running: tuple[str, ...] | list[str], reporting: str = "") -> str:
    """The status bar's stage text: every stage running side by side, in the order they started
    (naming only the one that reported last would make the label flip between them)."""
    return " + ".join(running) if running else reporting


class _Reporter:
    """The ``progress(fraction, stage)`` a job gets; ``progress.stages(names)`` reports the stages
    running side by side (pass it as ``skelcore.evaluate(on_stages=...)``)."""

    def __init__(self, task: "Task") -> None:
        self._task = task

    def __call__(self, fraction: float, stage: str) -> None:
        self._task._progress(fraction, stage)

    def stages(self, names: tuple[str, ...]) -> None:
        self._task.stages_running(names)


class Task(QtCore.QObject):
    """One run of a job function in a daemon thread; its signals are emitted from that thread and
    queued to the GUI thread (the object lives there)."""

    progressed = QtCore.Signal(float, str)
    succeeded = QtCore.Signal(object)
    failed = QtCore.Signal(object, str)  # exception, formatted traceback
    aborted = QtCore.Signal()
    finished = QtCore.Signal()

    def __init__(self, fn: JobFunction, name: str = "task", parent: QtCore.QObject | None = None) -> None:
        super().__init__(parent)
        self.fn = fn
        self.name = name
        self._cancel = threading.Event()
        self._done = threading.Event()
        self._last = (-1.0, "")
        self._running: tuple[str, ...] = ()
        self.stage = ""  # the stages running now (``stage_label``), as the job reported them last
        self._thread = threading.Thread(target=self.run, name=f"{THREAD_PREFIX}{name}", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def cancel(self) -> None:
        self._cancel.set()

    def is_cancelled(self) -> bool:
        return self._cancel.is_set()

    def isRunning(self) -> bool:  # noqa: N802 - QThread's name, kept for callers
        return self._thread.is_alive() and not self._done.is_set()

    def isFinished(self) -> bool:  # noqa: N802
        return self._done.is_set()

    def wait(self, ms: int | None = None) -> bool:
        """Block until the job has returned (at most ``ms`` milliseconds); True when it has."""
        return self._done.wait(None if ms is None else ms / 1000.0)

    def _progress(self, fraction: float, stage: str) -> None:
        last_fraction, last_label = self._last
        label = stage_label(self._running, str(stage))
        self.stage = label
        if label != last_label or fraction - last_fraction >= 0.005 or fraction >= 1.0:
            self._last = (fraction, label)
            self.progressed.emit(float(fraction), label)

    def stages_running(self, names: tuple[str, ...]) -> None:
        """The job's engine reports the stages running side by side (``evaluate(on_stages=...)``)."""
        self._running = tuple(names)
        if names:
            self._progress(max(self._last[0], 0.0), names[-1])

    def _failed(self, exc: BaseException) -> None:
        """A failure is a dialog (``failed``), unless the run was cancelled: then no result at all."""
        if self._cancel.is_set():
            self.aborted.emit()
        else:
            self.failed.emit(exc, traceback.format_exc())

    def run(self) -> None:  # worker thread
        try:
            try:
                result = self.fn(_Reporter(self), self._cancel.is_set)
            except Cancelled:
                self.aborted.emit()
            except BaseException as exc:  # noqa: BLE001 - every failure becomes a dialog, never a crash
                self._failed(exc)
            else:
                if self._cancel.is_set():
                    self.aborted.emit()  # cancelled after the last checkpoint: still no result
                else:
                    self.succeeded.emit(result)
        finally:
            self._done.set()
            try:
                self.finished.emit()
            except RuntimeError:  # the GUI side is gone (process exiting)
                pass


class ProcessTask(Task):
    """A job of :data:`skelscope.engine_process.JOBS` in a child process, with :class:`Task`'s signals.

    A thread of this process sends the job and reads the child's messages (so neither a 50 MB job nor
    a 150 MB result blocks the window); Cancel kills the child, which stops the work at once, in any
    stage. The thread then sees the pipe close and reports the abort."""

    def __init__(self, kind: str, kwargs: dict[str, Any], name: str = "task",
                 restore: Callable[[Any], Any] | None = None, parent: QtCore.QObject | None = None) -> None:
        super().__init__(lambda progress, cancel: None, name, parent)
        self.kind, self.kwargs = kind, kwargs
        self._restore = restore or (lambda result: result)
        self._proc: Any = None
        self._proc_lock = threading.Lock()
        self.pid: int | None = None

    def cancel(self) -> None:
        self._cancel.set()
        with self._proc_lock:
            if self._proc is not None and self._proc.poll() is None:
                self._proc.kill()

    def run(self) -> None:  # reader thread
        from .engine_process import start_child

        try:
            with self._proc_lock:
                if self._cancel.is_set():
                    raise Cancelled("cancelled before the engine started")
                self._proc, send, receive = start_child()
                self.pid = self._proc.pid
            try:
                send.send((self.kind, self.kwargs))
                self.kwargs = {}
                while True:
                    message = receive.recv()
                    if message[0] == "progress":
                        self._progress(message[1], message[2])
                    elif message[0] == "stages":
                        self.stages_running(message[1])
                    elif message[0] == "result":
                        if self._cancel.is_set():
                            raise Cancelled("cancelled")
                        self.succeeded.emit(self._restore(message[1]))
                        break
                    else:  # ("error", exception, traceback)
                        if self._cancel.is_set():
                            raise Cancelled("cancelled")
                        self.failed.emit(message[1], message[2])
                        break
            except (EOFError, OSError, BrokenPipeError):
                if self._cancel.is_set():
                    raise Cancelled("cancelled") from None
                code = self._proc.wait()
                self.failed.emit(RuntimeError(f"the engine process ended unexpectedly (exit status {code})"), "")
            finally:
                send.close()
                receive.close()
                if self._proc.poll() is None:
                    self._proc.kill()
                self._proc.wait()
        except Cancelled:
            self.aborted.emit()
        except BaseException as exc:  # noqa: BLE001 - every failure becomes a dialog, never a crash
            self._failed(exc)
        finally:
            try:  # emitted before ``wait()`` returns: once the window has waited, this thread touches no Qt object
                self.finished.emit()
            except RuntimeError:
                pass
            self._done.set()


class TaskRunner(QtCore.QObject):
    """Runs one task at a time; the GUI connects to these signals, which only the current task feeds."""

    started = QtCore.Signal(str)
    progressed = QtCore.Signal(float, str)
    succeeded = QtCore.Signal(str, object)  # task name, result
    failed = QtCore.Signal(str, object, str)  # task name, exception, traceback
    cancelled = QtCore.Signal(str)
    finished = QtCore.Signal(str)  # after any of succeeded / failed / cancelled

    def __init__(self, parent: QtCore.QObject | None = None) -> None:
        super().__init__(parent)
        self._current: Task | None = None
        self._retired: set[Task] = set()  # cancelled tasks still winding down (kept alive until done)

    @property
    def running(self) -> bool:
        return self._current is not None

    @property
    def current_name(self) -> str | None:
        return None if self._current is None else self._current.name

    def start(self, fn: JobFunction, name: str = "task") -> Task:
        """Cancel and disconnect any running task, then start ``fn`` in a new thread."""
        return self._launch(Task(fn, name))

    def start_process(self, kind: str, kwargs: dict[str, Any], name: str = "task",
                      restore: Callable[[Any], Any] | None = None) -> Task:
        """Like :meth:`start`, for a job of :data:`skelscope.engine_process.JOBS` run in a child process
        (``restore(result)`` runs in this process before ``succeeded``)."""
        return self._launch(ProcessTask(kind, kwargs, name, restore))

    def _launch(self, task: Task) -> Task:
        self._retire_current()
        name = task.name
        task.progressed.connect(self._on_progress)
        task.succeeded.connect(self._on_success)
        task.failed.connect(self._on_failure)
        task.aborted.connect(self._on_abort)
        self._current = task
        self.started.emit(name)
        task.start()
        return task

    def cancel(self) -> None:
        """Ask the current task to stop at its next checkpoint; ``cancelled`` follows when it has."""
        if self._current is not None:
            self._current.cancel()

    def discard(self) -> None:
        """Cancel the current task and drop whatever it would still deliver (inputs changed)."""
        self._retire_current()

    def _retire_current(self) -> None:
        task = self._current
        if task is None:
            return
        self._current = None
        task.cancel()
        for signal in (task.progressed, task.succeeded, task.failed, task.aborted):
            try:
                signal.disconnect()
            except (RuntimeError, TypeError):
                pass
        self._keep_until_finished(task)
        self.cancelled.emit(task.name)

    def wait_all(self, ms: int = 5000) -> bool:
        """Block until every thread has ended, at most ``ms`` milliseconds in all; True when they have."""
        deadline = time.monotonic() + ms / 1000.0
        ok = True
        for task in [*self._retired, *([self._current] if self._current else [])]:
            ok = task.wait(max(0.0, deadline - time.monotonic()) * 1000.0) and ok
        return ok

    def shutdown(self, wait_s: float = SHUTDOWN_WAIT_S) -> bool:
        """Cancel the current task and wait at most ``wait_s`` for every thread to end (quitting).
        False when one is still inside an engine call without a checkpoint: it is a daemon thread,
        so the process still exits."""
        self._retire_current()
        return self.wait_all(int(wait_s * 1000))

    @property
    def alive(self) -> bool:
        """Any thread (current or retired) still running."""
        return any(t.isRunning() for t in [*self._retired, *([self._current] if self._current else [])])

    @property
    def stage(self) -> str:
        """The stage the current task reported last ('' when none)."""
        return "" if self._current is None else self._current.stage

    def _is_current(self) -> bool:
        return self.sender() is self._current and self._current is not None

    @QtCore.Slot(float, str)
    def _on_progress(self, fraction: float, stage: str) -> None:
        if self._is_current():
            self.progressed.emit(fraction, stage)

    @QtCore.Slot(object)
    def _on_success(self, result: object) -> None:
        if self._is_current():
            task = self._end()
            self.succeeded.emit(task.name, result)
            self.finished.emit(task.name)

    @QtCore.Slot(object, str)
    def _on_failure(self, exc: object, tb: str) -> None:
        if self._is_current():
            task = self._end()
            self.failed.emit(task.name, exc, tb)
            self.finished.emit(task.name)

    @QtCore.Slot()
    def _on_abort(self) -> None:
        if self._is_current():
            task = self._end()
            self.cancelled.emit(task.name)
            self.finished.emit(task.name)

    def _end(self) -> Task:
        task = self._current
        assert task is not None
        self._current = None
        self._keep_until_finished(task)
        return task

    def _keep_until_finished(self, task: Task) -> None:
        # Held until its thread ends, so its signals' object outlives the thread.
        self._retired.add(task)
        task.finished.connect(lambda t=task: self._retired.discard(t))
        if task.isFinished():
            self._retired.discard(task)
