"""The wheel is complete: built from the repository, installed into a fresh venv, ``skelcore
evaluate`` runs from outside the repository on a generated cloud and imports only the wheel's code."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import sysconfig
import venv
import zipfile
from pathlib import Path

import numpy as np
import pytest

from skelcore import shapes

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(out), str(ROOT)],
        capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert "deprecated" not in proc.stderr.lower(), proc.stderr
    (whl,) = out.glob("skelscope-*.whl")
    return whl


def test_wheel_holds_every_subpackage_and_the_license(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    for package in ROOT.joinpath("skelcore").rglob("__init__.py"):
        rel = package.relative_to(ROOT).as_posix()
        assert rel in names
    for package in ROOT.joinpath("app").rglob("__init__.py"):  # the viewer's folder installs as skelscope/
        assert "skelscope/" + package.relative_to(ROOT / "app").as_posix() in names
    assert not [n for n in names if n.startswith("app/")]  # nothing under a generic top-level name
    assert not [n for n in names if n.endswith(".c")]  # the kernels ship compiled, their sources in the sdist
    meta = next(n for n in names if n.endswith("METADATA"))
    text = zipfile.ZipFile(wheel).read(meta).decode()
    assert "License-Expression: MIT" in text
    assert any(n.endswith("licenses/LICENSE") for n in names)
    # package data the library reads at run time ships inside the packages
    for data in [*ROOT.joinpath("skelcore").rglob("data/*"), *ROOT.joinpath("skelcore").rglob("schemas/*.json")]:
        assert data.relative_to(ROOT).as_posix() in names


def test_installed_wheel_evaluates_from_outside_the_repo(wheel, tmp_path):
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=False).create(env_dir)
    py = env_dir / "bin" / "python"
    site = Path(subprocess.check_output(
        [str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], text=True).strip())
    # The wheel's files go into the fresh venv; its third-party dependencies come from the test
    # environment's site-packages through a .pth line (no network, and the editable finder of the
    # test environment is not activated by a plain path line).
    with zipfile.ZipFile(wheel) as zf:
        zf.extractall(site)
    deps = sysconfig.get_paths()["purelib"]
    (site / "zz_test_deps.pth").write_text(deps + "\n")
    shape = tmp_path / "work"
    shape.mkdir()
    cyl = shapes.cylinder(1024)
    np.savetxt(shape / "cyl.xyz", cyl.cloud)
    curve = {"vertices": cyl.curve_vertices.tolist(), "edges": cyl.curve_edges.tolist()}
    (shape / "axis.json").write_text(json.dumps(curve))
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    where = subprocess.run([str(py), "-c", "import skelcore; print(skelcore.__file__)"], cwd=shape,
                           capture_output=True, text=True, env=env, timeout=120)
    assert where.stdout.strip().startswith(str(site)), where.stdout + where.stderr
    proc = subprocess.run(
        [str(py), "-m", "skelcore", "evaluate", "cyl.xyz", "--curve", "axis.json", "--json", "out.json", "--quiet"],
        cwd=shape, capture_output=True, text=True, env=env, timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert "centeredness" in proc.stdout
    result = json.loads((shape / "out.json").read_text())
    assert result["boundedness"]["curve"] > 0.9
    assert result["centeredness"]["curve"] > 0.9
