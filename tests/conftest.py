"""Shared fixtures: analytic shapes with known answers, and the optional real data folder."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


@pytest.fixture
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        pytest.skip("../shared/data is not present")
    return SHARED_DATA


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


def write_shape_files(folder: Path, shape, stem: str = "y") -> dict[str, str]:
    """Write a Shape's cloud, skeletal set and curve as PLY files; returns their paths by role."""
    from skelcore.io import write_curve_ply, write_points_ply

    paths = {k: Path(folder) / f"{stem}_{k}.ply" for k in ("cloud", "skeletal", "curve")}
    write_points_ply(paths["cloud"], shape.cloud)
    write_points_ply(paths["skeletal"], shape.skeletal)
    write_curve_ply(paths["curve"], shape.curve_vertices, shape.curve_edges)
    return {k: str(v) for k, v in paths.items()}
