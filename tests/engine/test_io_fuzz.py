"""Fuzz the loaders: random truncations and byte flips of valid files of every format must give
either a successful load or a one-line SkelInputError, never another exception (seeded, fast)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from test_io_formats import CLOUD_WRITERS, CURVE_WRITERS, make_cloud, make_curve

from skelcore.errors import SkelInputError
from skelcore.io import load_any, load_cloud, load_curve

CASES_PER_FILE = 24


def _mutations(data: bytes, rng: np.random.Generator, n: int):
    """Half truncations (anywhere, biased to the header), half 1-4 byte flips; then one of each kind."""
    for k in range(n):
        if k % 2 == 0:
            cut = int(rng.integers(0, min(len(data), 200))) if k % 4 == 0 else int(rng.integers(0, len(data)))
            yield f"cut{cut}", data[:cut]
        else:
            buf = bytearray(data)
            for _ in range(int(rng.integers(1, 5))):
                pos = int(rng.integers(0, min(len(buf), 160))) if k % 4 == 1 else int(rng.integers(0, len(buf)))
                buf[pos] = int(rng.integers(0, 256))
            yield f"flip{k}", bytes(buf)


def _check(path, loader) -> str:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # NaN vertices dropped by CurveSkeleton.from_raw
            loader(path)
    except SkelInputError as err:
        msg = str(err)
        assert "\n" not in msg and path.name in msg, msg
        return "error"
    return "ok"


FILES = [("cloud", n) for n in sorted(CLOUD_WRITERS)] + [("curve", n) for n in sorted(CURVE_WRITERS)]


@pytest.mark.parametrize("kind,name", FILES)
def test_corrupted_files_raise_only_skelinputerror(tmp_path, kind, name):
    seed = sum(map(ord, name))
    rng = np.random.default_rng(seed)
    src = tmp_path / "src"
    src.mkdir()
    if kind == "cloud":
        suffix, writer = CLOUD_WRITERS[name]
        good = src / f"good{suffix}"
        writer(good, make_cloud(12, seed=seed))
        loaders = (load_cloud, load_any)
    else:
        suffix, writer = CURVE_WRITERS[name]
        good = src / f"good{suffix}"
        writer(good, *make_curve())
        loaders = (load_curve, load_any)
    data = good.read_bytes()
    outcomes = {"ok": 0, "error": 0}
    for tag, mutated in _mutations(data, rng, CASES_PER_FILE):
        path = tmp_path / f"{tag}{suffix}"
        path.write_bytes(mutated)
        for loader in loaders:
            outcomes[_check(path, loader)] += 1
    # The cases must actually exercise the error paths (a truncation to 0 bytes always fails).
    assert outcomes["error"] > 0
