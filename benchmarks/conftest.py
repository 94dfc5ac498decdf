"""The benchmark suite's shared parts: its collection (``bench_*.py`` files, only when ``benchmarks/`` is
given to pytest: ``make test`` runs ``tests/`` alone), the ``--bench-large`` option for the 1M-point
cases, the inputs every module uses (the hammer scan and its built-in skeleton, the reference torus), the
machine described in the JSON, and :func:`measure`, which every case times with.

    .venv/bin/python -m pytest benchmarks --benchmark-json=results.json [--bench-large] [--bench-rounds N]
    .venv/bin/python benchmarks/report.py results.json > docs/benchmark_results.md

Every figure is read as a ratio to the anchor (``bench_anchor.py``: gudhi's Rips H0 of the hammer)
timed in the same run: the cores are shared, so seconds alone move with the machine's load.
"""

from __future__ import annotations

import os
import platform
import time
from functools import lru_cache
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def _hammer_path() -> Path:
    """The hammer scan (4096 points, resources/scans), the anchor's cloud and the real scan of several cases."""
    return ROOT / "resources" / "scans" / "hammer_4096.ply"


_LOAD_AT_START = pytest.StashKey[float]()

# ---- collection and options --------------------------------------------------------------------------


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("skelscope benchmarks")
    group.addoption("--bench-large", action="store_true", default=False,
                    help="also run the cases marked large (1M points: tens of seconds each)")
    group.addoption("--bench-rounds", type=int, default=None, metavar="N",
                    help="timed rounds of every case (default: each case's own, 3-7)")


def pytest_configure(config: pytest.Config) -> None:
    config.stash[_LOAD_AT_START] = round(os.getloadavg()[0], 2)
    config.addinivalue_line("markers", "large: a 1M-point case, run only with --bench-large")


def pytest_collect_file(file_path: Path, parent: pytest.Collector):
    """The benchmark modules are ``bench_*.py`` (pytest's default pattern is ``test_*.py``); a file named
    on the command line is collected by pytest itself."""
    if file_path.suffix == ".py" and file_path.name.startswith("bench_") and not parent.session.isinitpath(file_path):
        return pytest.Module.from_parent(parent, path=file_path)
    return None


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if config.getoption("--bench-large"):
        return
    skip = pytest.mark.skip(reason="a large case: run with --bench-large")
    for item in items:
        if "large" in item.keywords:
            item.add_marker(skip)


# ---- the machine -------------------------------------------------------------------------------------


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _memory_gb() -> float | None:
    try:
        with open("/proc/meminfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("MemTotal:"):
                    return round(int(line.split()[1]) / 1024**2, 1)
    except OSError:
        pass
    return None


def _blas() -> str:
    """numpy's BLAS as numpy reports it (name and version), or "" when it does not say."""
    try:
        cfg = np.show_config(mode="dicts")
        blas = cfg["Build Dependencies"]["blas"]
        return f"{blas.get('name', '')} {blas.get('version', '')}".strip()
    except Exception:  # numpy < 1.25 has no mode="dicts"
        return ""


def pytest_benchmark_update_machine_info(config: pytest.Config, machine_info: dict) -> None:
    import skelcore

    machine_info["cpu_model"] = _cpu_model()
    machine_info["cores"] = os.cpu_count()
    machine_info["memory_gb"] = _memory_gb()
    machine_info["python"] = platform.python_version()
    machine_info["numpy"] = np.__version__
    machine_info["numpy_blas"] = _blas()
    machine_info["skelcore"] = skelcore.__version__
    machine_info["load_average_at_start"] = config.stash.get(_LOAD_AT_START, None)
    machine_info["load_average_at_end"] = round(os.getloadavg()[0], 2)  # pytest-benchmark asks at the end
    machine_info["bench_large"] = bool(config.getoption("--bench-large"))


# ---- timing ------------------------------------------------------------------------------------------


@pytest.fixture
def measure(benchmark, request) -> Callable:
    """``measure(fn, rounds=3, warmup=1, setup=None)``: ``fn`` timed ``rounds`` times, one call per
    round, after ``warmup`` untimed calls (first-call loading left out); ``setup`` (untimed) returns
    ``(args, kwargs)`` for each call. ``--bench-rounds`` overrides every case's rounds. The load average
    before and after, the 95th percentile of the rounds' seconds (``p95``, numpy's linear interpolation)
    and the median CPU seconds of this process per round (``cpu_median``: what the shared cores' load
    does not inflate) go into the case's extra_info."""
    forced = request.config.getoption("--bench-rounds")

    def run(fn: Callable, *, rounds: int = 3, warmup: int = 1, setup: Callable | None = None):
        cpu: list[float] = []

        def timed(*args, **kwargs):
            t0 = time.process_time()
            try:
                return fn(*args, **kwargs)
            finally:
                cpu.append(time.process_time() - t0)

        benchmark.extra_info["load_average_before"] = round(os.getloadavg()[0], 2)
        out = benchmark.pedantic(timed, setup=setup, rounds=forced or rounds, warmup_rounds=warmup, iterations=1)
        benchmark.extra_info["load_average_after"] = round(os.getloadavg()[0], 2)
        data = list(getattr(getattr(benchmark.stats, "stats", None), "data", None) or [])
        if data:
            benchmark.extra_info["p95"] = float(np.percentile(data, 95))
        if cpu[warmup:]:
            benchmark.extra_info["cpu_median"] = float(np.median(cpu[warmup:]))
        return out

    return run


def _peak_rss_mb(code: str) -> float | None:
    """The peak resident memory (MB; Linux ``VmHWM``) of a fresh Python process that runs ``code`` with
    this folder's helpers importable (``from conftest import _torus``): what a user's process holds at
    most, imports and inputs included. None where the kernel does not report it."""
    import subprocess
    import sys

    tail = ("\nimport re\nfrom pathlib import Path\n"
            "print(re.search(r'VmHWM:\\s+(\\d+)', Path('/proc/self/status').read_text()).group(1))")
    done = subprocess.run([sys.executable, "-c", code + tail], cwd=Path(__file__).parent, capture_output=True,
                          text=True)
    if done.returncode != 0:
        raise RuntimeError(done.stderr.strip().splitlines()[-1] if done.stderr.strip() else "child failed")
    try:
        return round(int(done.stdout.split()[-1]) / 1024, 1)
    except (ValueError, IndexError):
        return None


@pytest.fixture
def peak_rss_mb() -> Callable:
    """``peak_rss_mb(code)`` -> the peak MB of a fresh process running ``code``: :func:`_peak_rss_mb`."""
    return _peak_rss_mb


# ---- inputs ------------------------------------------------------------------------------------------


@pytest.fixture(scope="session")
def hammer_path() -> Path:
    return _hammer_path()


@pytest.fixture(scope="session")
def hammer(hammer_path) -> np.ndarray:
    from skelcore.io import load_cloud

    return load_cloud(str(hammer_path))


@pytest.fixture(scope="session")
def hammer_skeleton(hammer):
    """The built-in skeletonizer's (skeletal set, curve) of the hammer, made once per run."""
    from skelcore.skeleton import skeletonize

    return skeletonize(hammer)


@lru_cache(maxsize=2)
def _torus(n: int, curve_only: bool = False):
    """The reference torus: R = 1, r = 0.3, ``n`` points; skeletal set = each point's projection onto the
    core circle + 1 % jitter (None with ``curve_only``); curve = a 64-gon of the core circle."""
    from skelcore import shapes

    shape = shapes.torus(n, R=1.0, r=0.3, n_curve=64, seed=0)
    skeletal = None
    if not curve_only:
        skeletal = shape.skeletal + np.random.default_rng(0).normal(scale=0.01, size=shape.skeletal.shape)
    return shape.cloud, skeletal, (shape.curve_vertices, shape.curve_edges)


@pytest.fixture(scope="session")
def torus() -> Callable:
    """``torus(n, curve_only=False)`` -> (cloud, skeletal set or None, (curve vertices, edges)), cached."""
    return _torus
