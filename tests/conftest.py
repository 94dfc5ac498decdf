"""Fixtures for every test: a seeded random generator, and the real scans shipped in resources/scans; the
order in which the xdist workers take the test files (heaviest first, from tests/file_costs.txt); and the
collection without the cyclic garbage collector (docs/guide/testing.md, "Order and cost")."""

from __future__ import annotations

import gc
from pathlib import Path

import numpy as np
import pytest
from shape_files import write_shape_files  # noqa: F401 - also importable from here, as before

#: seconds per test file in a recorded run of the whole suite (the file's header says how it is made)
FILE_COSTS = Path(__file__).with_name("file_costs.txt")

#: the real scans of the paper's toolbox, in the repository (resources/scans/README.md says what each is)
SCANS = Path(__file__).resolve().parents[1] / "resources" / "scans"


@pytest.fixture(scope="session")
def scans() -> Path:
    """The folder of the real scans (hammer_4096.ply, apple_tree_22367.ply, cave_27375.ply,
    horse_1987_mesh.ply); part of the repository, so never skipped."""
    return SCANS


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


def file_costs(path: Path = FILE_COSTS) -> dict[str, float]:
    """The recorded seconds of each test file, by its path from the repository root ("tests/...")."""
    costs = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.strip() and not line.startswith("#"):
            seconds, name = line.split()
            costs[name] = float(seconds)
    return costs


def pytest_configure(config: pytest.Config) -> None:
    """Under xdist the controller takes the files in the order the workers collected them: without this,
    ``--dist loadfile`` would reorder them by their number of tests, which says little of their cost."""
    if hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """On an xdist worker, the test files heaviest first by their recorded cost (longest processing time
    first: the last files handed out are short, so neither worker idles long at the end); a file keeps its
    own tests' order. A run without workers keeps the collection order."""
    if not hasattr(config, "workerinput"):
        return
    costs = file_costs()
    median = sorted(costs.values())[len(costs) // 2]
    items.sort(key=lambda item: -costs.get(item.nodeid.split("::", 1)[0], median))


@pytest.hookimpl(wrapper=True)
def pytest_collection(session: pytest.Session):
    """Collection with the cyclic garbage collector paused, then the objects it made frozen: importing the
    test modules (and pytest rewriting their asserts) makes hundreds of thousands of objects, which each
    automatic collection would scan again and again (about 6 of a worker's 20-25 CPU s of collection), and
    which every later collection of the run would scan again too. Frozen, they are left out of every later
    collection, as the viewer does with its imports (``app/__main__.py``, ``import_view_libraries``)."""
    collecting = gc.isenabled()
    gc.disable()
    try:
        return (yield)
    finally:
        gc.collect()  # the garbage of the imports is freed, not frozen
        gc.freeze()
        if collecting:
            gc.enable()
