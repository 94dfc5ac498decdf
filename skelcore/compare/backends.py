"""Where the jobs run: in this process (``jobs=1``), on a local process pool (``--jobs N``), or on a
Dask distributed cluster (``--dask tcp://HOST:PORT`` or ``--dask local:N``).

Whatever the backend, only this process writes the store: a worker returns its record and the
driver files it as soon as it arrives, so killing the run loses at most the jobs in flight. Pool
workers are forked from a forkserver that has already imported skelcore (cheap per-job start); on
SIGTERM they kill their skeleton command's process group before dying. Dask workers must see the
same paths as this machine (a shared filesystem) and have skelcore installed.
"""

from __future__ import annotations

import os
import signal
import sys
import time
from dataclasses import dataclass, field
from typing import Any, Callable

from ..errors import SkelInputError
from .jobs import Job, run_job
from .job_store import Store

__all__ = ["Backend", "parse_backend", "RunSummary", "run_jobs", "run_tasks"]


@dataclass(frozen=True)
class Backend:
    """Where the jobs run: ``"serial"`` (this process), ``"pool"`` (``workers`` processes) or
    ``"dask"`` (a scheduler at ``address``, or a LocalCluster of ``workers``); :func:`parse_backend`
    reads the CLI's ``--jobs`` / ``--dask``."""

    kind: str  # "serial", "pool", "dask"
    workers: int = 1
    address: str | None = None  # dask: tcp://host:port, or None for a LocalCluster of `workers`
    processes: bool = True  # LocalCluster: worker processes (False = threads in this process)

    def describe(self) -> str:
        if self.kind == "serial":
            return "serial (this process)"
        if self.kind == "pool":
            return f"process pool of {self.workers}"
        return f"dask {self.address}" if self.address else f"dask LocalCluster of {self.workers}"


def parse_backend(jobs: int | None, dask: str | None) -> Backend:
    """``--jobs N`` / ``--dask ADDR|local:N`` to a Backend (default: a pool of one worker per core)."""
    if dask:
        if dask.startswith("local:"):
            try:
                n = int(dask[6:])
            except ValueError:
                n = 0
            if n < 1:
                raise SkelInputError(f"--dask local:N needs a positive worker count, got {dask!r}")
            return Backend("dask", n)
        if "://" not in dask:
            raise SkelInputError(f"--dask expects tcp://HOST:PORT or local:N, got {dask!r}")
        return Backend("dask", 0, address=dask)
    n = jobs if jobs is not None else (os.cpu_count() or 1)
    return Backend("serial", 1) if n <= 1 else Backend("pool", n)


@dataclass
class RunSummary:
    total: int
    skipped: int
    ok: int = 0
    failed: int = 0
    wall: float = 0.0
    job_seconds: float = 0.0
    backend: str = ""
    records: list[dict[str, Any]] = field(default_factory=list)


class _Bar:
    """tqdm on a terminal (jobs done, failed, ETA); silent otherwise."""

    def __init__(self, total: int, quiet: bool) -> None:
        self.bar = None
        if not quiet and sys.stderr.isatty() and total:
            import shutil

            from tqdm import tqdm

            cols = shutil.get_terminal_size((100, 24)).columns or 100  # a pty may report 0 columns
            self.bar = tqdm(total=total, file=sys.stderr, unit="job", ncols=min(cols, 120), desc="compare")

    def update(self, ok: int, failed: int) -> None:
        if self.bar is not None:
            self.bar.set_postfix(ok=ok, failed=failed, refresh=False)
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _worker_init() -> None:
    """Pool worker: Ctrl-C is the driver's business; SIGTERM unwinds (killing a running command)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)

    def term(signum, frame):  # noqa: ARG001
        raise SystemExit(143)

    signal.signal(signal.SIGTERM, term)


def run_jobs(jobs: list[Job], store: Store, backend: Backend, *, quiet: bool = True, retry_failed: bool = False,
             on_record: Callable[[dict[str, Any]], None] | None = None) -> RunSummary:
    """Run every job whose key is not in the store yet; file each record as it arrives."""
    t0 = time.perf_counter()
    todo = []
    for job in jobs:
        rec = store.get(job.key)
        if rec is None or (retry_failed and rec.get("status") != "ok"):
            todo.append(job)
    summary = RunSummary(total=len(jobs), skipped=len(jobs) - len(todo), backend=backend.describe())
    bar = _Bar(len(todo), quiet)

    def file(rec: dict[str, Any]) -> None:
        store.put(rec)
        rec.pop("arrays", None)
        summary.records.append(rec)
        summary.job_seconds += float(rec.get("seconds") or 0.0)
        if rec["status"] == "ok":
            summary.ok += 1
        else:
            summary.failed += 1
        bar.update(summary.ok, summary.failed)
        if on_record is not None:
            on_record(rec)

    try:
        run_tasks(run_job, todo, backend, file, failed=_failed, key=lambda job: job.key)
    finally:
        bar.close()
        summary.wall = time.perf_counter() - t0
    return summary


def run_tasks(fn: Callable[[Any], dict[str, Any]], tasks: list[Any], backend: Backend,
              on_result: Callable[[dict[str, Any]], None], *, failed: Callable[[Any, str], dict[str, Any]],
              key: Callable[[Any], str]) -> None:
    """Run ``fn(task)`` (a picklable module-level function returning a record) for every task on
    ``backend``; ``on_result(record)`` is called in this process as each arrives. A task whose worker
    dies gets ``failed(task, message)`` instead; ``key(task)`` names it (unique). Used by
    :func:`run_jobs` and ``skelcore bench validity``."""
    if not tasks:
        return
    if backend.kind == "serial":
        for task in tasks:
            on_result(fn(task))
    elif backend.kind == "pool":
        _run_pool(tasks, backend.workers, on_result, fn, failed, key)
    else:
        _run_dask(tasks, backend, on_result, fn, failed, key)


def _run_pool(todo: list[Any], workers: int, file: Callable[[dict[str, Any]], None], fn: Callable[[Any], dict[str, Any]],
              failed: Callable[[Any, str], dict[str, Any]], key: Callable[[Any], str]) -> None:
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed
    from concurrent.futures.process import BrokenProcessPool

    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["skelcore.compare.jobs"])
    ex = ProcessPoolExecutor(max_workers=min(workers, len(todo)), mp_context=ctx, initializer=_worker_init)
    futures = {ex.submit(fn, job): job for job in todo}
    done: set[str] = set()
    broken = False
    try:
        for fut in as_completed(futures):
            try:
                rec = fut.result()
            except BrokenProcessPool:
                broken = True
                break
            done.add(key(futures[fut]))
            file(rec)
    finally:
        if broken:
            ex.shutdown(wait=True, cancel_futures=True)
        else:
            _stop_pool(ex)
    if broken:
        # a worker died (segfault, OOM kill): which job killed it is unknown, so every job not
        # finished runs again alone in a fresh one-worker pool; one that kills that too is failed
        for job in [j for j in todo if key(j) not in done]:
            single = ProcessPoolExecutor(max_workers=1, mp_context=ctx, initializer=_worker_init)
            try:
                rec = single.submit(fn, job).result()
            except BrokenProcessPool:
                rec = failed(job, "the worker process died while running this job")
            finally:
                _stop_pool(single)
            file(rec)


def _failed(job: Job, error: str) -> dict[str, Any]:
    from .jobs import scores_from_doc

    return {"key": job.key, "shape": job.shape.name, "method": job.method.name, "condition": job.condition.name,
            "seed": job.seed, "status": "failed", "error": error, "seconds": 0.0, "scores": scores_from_doc(None)}


def _stop_pool(ex) -> None:
    """Shut the pool down now: pending jobs cancelled, busy workers terminated (SIGTERM)."""
    procs = list((getattr(ex, "_processes", None) or {}).values())
    ex.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        if proc.is_alive():
            proc.terminate()
    for proc in procs:
        proc.join(timeout=5)


def _run_dask(todo: list[Any], backend: Backend, file: Callable[[dict[str, Any]], None], fn: Callable[[Any], dict[str, Any]],
              failed: Callable[[Any, str], dict[str, Any]], key: Callable[[Any], str]) -> None:
    import logging

    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise SkelInputError("--dask needs Dask's distributed scheduler, not installed: "
                             "pip install 'skelscope[dask]'") from None

    cluster = None
    try:
        if backend.address:
            from .scheduler_probe import refused

            no = refused(backend.address)
            if no is not None:  # at once, not after Dask's retries
                raise SkelInputError(f"cannot reach the Dask scheduler at {backend.address}: {no}")
            try:
                client = Client(backend.address, timeout="5s")
            except (OSError, TimeoutError) as exc:
                raise SkelInputError(f"cannot reach the Dask scheduler at {backend.address}: {exc}") from None
        else:
            cluster = LocalCluster(n_workers=backend.workers, threads_per_worker=1, processes=backend.processes,
                                   dashboard_address=None, silence_logs=logging.ERROR)
            client = Client(cluster)
        try:
            jobs = {client.submit(fn, job, key=f"skelcore-job-{key(job)}", pure=False): job for job in todo}
            futures = list(jobs)
            try:
                for fut in as_completed(futures):
                    try:
                        rec = fut.result()
                    except Exception as exc:  # KilledWorker (a job that kills its worker), lost data
                        from .jobs import one_line

                        rec = failed(jobs[fut], f"the Dask worker failed: {one_line(exc)}")
                    file(rec)
                    fut.release()
            finally:
                client.cancel(futures)
        finally:
            client.close()
    finally:
        if cluster is not None:
            cluster.close()
