"""Shared fixtures: analytic shapes with known answers, and the optional real data folder."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from shape_files import write_shape_files  # noqa: F401 - also importable from here, as before

SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


@pytest.fixture
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        pytest.skip("the shared data folder is not present")
    return SHARED_DATA


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)
