"""Big evaluations in a child process: Cancel and quit are a kill, and the
window never waits for the engine's GIL.

In a thread, a 1M-point evaluation held the GIL in long numpy and scipy calls (1.1-1.4 s between two
checkpoints in topology, centeredness and smoothness, measured in the viewer, docs/performance.md 10), so
Cancel took up to 1.5 s to reach the engine and every Qt callback into Python (event filters,
overridden virtuals) waited for the worker: the File menu opened 2 s after the click. A child
process shares no GIL with the window; killing it ends the work at once, wherever it is.

The child is ``python -m skelscope.engine_process READ_FD WRITE_FD`` (no Qt: it imports only skelcore), at
a lower CPU priority than the window. It reads one job, ``(kind, kwargs)``, and writes
``("progress", fraction, stage)``, ``("stages", names)`` and then ``("result", value)`` or
``("error", exception, traceback)``; it exits when the job is done or the window's end of the job
pipe closes (the window quit or died), so no child outlives its window.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import threading
import traceback
from multiprocessing.connection import Connection
from typing import Any, Callable

__all__ = ["JOBS", "start_child", "NICE"]

NICE = 5
"""How much lower the child's CPU priority is than the window's: on two busy cores the window's
event loop still gets its turns while the engine computes."""


def _evaluate(progress: Callable[[float, str], None], on_stages: Callable[[tuple[str, ...]], None],
              cancel: Callable[[], bool], **kwargs: Any) -> Any:
    from skelcore.stages import evaluate

    cloud = kwargs.pop("cloud")
    ev = evaluate(cloud, progress=progress, cancel=cancel, on_stages=on_stages, **kwargs)
    import numpy as np

    if ev.cloud is cloud or (ev.cloud.shape == cloud.shape and np.array_equal(ev.cloud, cloud)):
        ev.cloud = None  # the window has it already: not sent back (24 MB per million points)
    return ev


JOBS: dict[str, Callable[..., Any]] = {"evaluate": _evaluate}
"""What a child can run, by name (the window sends the name, not code)."""


def start_child() -> tuple[subprocess.Popen, Connection, Connection]:
    """A new child process; (process, connection to send its job on, connection to read it from)."""
    job_r, job_w = os.pipe()
    msg_r, msg_w = os.pipe()
    env = dict(os.environ)
    # the child imports this tree's skelcore and app, however the window's process found them
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env["PYTHONPATH"] = os.pathsep.join([root, *[p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]])
    try:
        proc = subprocess.Popen([sys.executable, "-m", "skelscope.engine_process", str(job_r), str(msg_w)],
                                pass_fds=(job_r, msg_w), env=env, stdin=subprocess.DEVNULL, close_fds=True)
    finally:
        os.close(job_r)
        os.close(msg_w)
    return proc, Connection(job_w, readable=False), Connection(msg_r, writable=False)


def _child(job_fd: int, msg_fd: int) -> int:
    try:
        os.nice(NICE)
    except OSError:
        pass
    inbox = Connection(job_fd, writable=False)
    out = Connection(msg_fd, readable=False)
    try:
        kind, kwargs = inbox.recv()
    except (EOFError, OSError):
        return 0
    lock = threading.Lock()

    def send(message: tuple) -> None:
        with lock:
            out.send(message)

    def watch_window() -> None:  # the window closed its end: nobody waits for this result
        try:
            inbox.recv()
        except (EOFError, OSError):
            pass
        os._exit(0)

    threading.Thread(target=watch_window, name="skelscope-engine-watch", daemon=True).start()
    last = [-1.0, ""]

    def progress(fraction: float, stage: str) -> None:
        # throttled to visible steps (Orange3's habit), a new stage at once
        if stage != last[1] or fraction - last[0] >= 0.005 or fraction >= 1.0:
            last[0], last[1] = fraction, stage
            send(("progress", float(fraction), str(stage)))

    try:
        result = JOBS[kind](progress, lambda names: send(("stages", tuple(names))), lambda: False, **kwargs)
        payload = pickle.dumps(("result", result), protocol=pickle.HIGHEST_PROTOCOL)
    except BaseException as exc:  # noqa: BLE001 - every failure is reported to the window
        tb = traceback.format_exc()
        try:
            pickle.dumps(exc)
        except Exception:  # noqa: BLE001 - an exception that does not pickle goes as its text
            exc = RuntimeError(f"{type(exc).__name__}: {exc}")
        send(("error", exc, tb))
        return 0
    with lock:
        out.send_bytes(payload)
    return 0


if __name__ == "__main__":
    sys.exit(_child(int(sys.argv[1]), int(sys.argv[2])))
