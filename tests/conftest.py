"""Fixtures for every test: a seeded random generator, and the real scans shipped in resources/scans."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from shape_files import write_shape_files  # noqa: F401 - also importable from here, as before

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
