"""The wheel is complete: built from the repository's sdist, installed into a fresh venv, ``skelcore
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
def sdist(tmp_path_factory) -> tuple[set[str], Path]:
    """The source distribution built from the repository: its member names (the top folder left off) and
    its unpacked tree."""
    import tarfile

    tmp = tmp_path_factory.mktemp("sdist")
    out = tmp / "dist"
    proc = subprocess.run([sys.executable, "-m", "build", "--sdist", "--no-isolation", "-o", str(out), str(ROOT)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    (sdist,) = out.glob("skelscope-*.tar.gz")
    with tarfile.open(sdist) as tar:
        names = {n.split("/", 1)[1] for n in tar.getnames() if "/" in n}
        tar.extractall(tmp / "src", filter="data")
    (src,) = (tmp / "src").iterdir()
    return names, src


@pytest.fixture(scope="module")
def wheel(sdist, tmp_path_factory) -> Path:
    """The wheel pip builds from the unpacked sdist in an isolated build environment (the path of an install
    from the package index, and the one `python -m build` takes): built once for the module's tests."""
    out = tmp_path_factory.mktemp("wheel")
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(out), str(sdist[1])],
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


def _pip(*args: str, timeout: int = 300) -> subprocess.CompletedProcess:
    proc = subprocess.run([sys.executable, "-m", "pip", *args], capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc


def test_installs_beside_a_project_that_ships_app(wheel, tmp_path):
    """Another project's top-level ``app`` package and SkelScope install into one environment, and
    uninstalling either leaves the other whole: SkelScope installs nothing under a generic name."""
    other = tmp_path / "other"
    (other / "app").mkdir(parents=True)
    (other / "app" / "__init__.py").write_text("WHO = 'other'\n")
    (other / "pyproject.toml").write_text(
        '[build-system]\nrequires = ["setuptools>=61"]\nbuild-backend = "setuptools.build_meta"\n'
        '[project]\nname = "other-app"\nversion = "1.0"\n[tool.setuptools]\npackages = ["app"]\n')
    wheels = tmp_path / "wheels"
    _pip("wheel", "-q", "--no-deps", "--no-build-isolation", "-w", str(wheels), str(other))
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=False).create(env_dir)
    py = env_dir / "bin" / "python"
    site = Path(subprocess.check_output(
        [str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], text=True).strip())
    (site / "zz_test_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    (other_whl,) = wheels.glob("other_app-*.whl")
    _pip("--python", str(py), "install", "-q", "--no-deps", "--no-index", str(other_whl), str(wheel))
    probe = ("import app, skelscope, skelcore, skelscope.__main__ as m; "
             "print(app.WHO, skelscope.__file__.startswith(%r), m.missing_viewer_libraries())" % str(site))
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    out = subprocess.run([str(py), "-c", probe], cwd=tmp_path, capture_output=True, text=True, env=env)
    assert out.stdout.split() == ["other", "True", "[]"], out.stdout + out.stderr
    _pip("--python", str(py), "uninstall", "-q", "-y", "other-app")
    assert (site / "skelscope" / "__init__.py").is_file() and (site / "skelscope" / "main_window.py").is_file()
    assert not (site / "app").exists()
    _pip("--python", str(py), "install", "-q", "--no-deps", "--no-index", str(other_whl))
    _pip("--python", str(py), "uninstall", "-q", "-y", "skelscope")
    assert (site / "app" / "__init__.py").read_text() == "WHO = 'other'\n"


def test_viewer_without_its_libraries_says_so_in_one_line(wheel, tmp_path):
    """``skelscope`` installed without the ``app`` extra (no PySide6, pyvista, pyvistaqt): the extra to
    install in one line, exit 2; its help and the engine still work."""
    deps = tmp_path / "deps"
    deps.mkdir()
    viewer_only = ("pyside6", "shiboken6", "pyvista", "pyvistaqt")
    for entry in Path(sysconfig.get_paths()["purelib"]).iterdir():
        if not entry.name.lower().startswith(viewer_only) and not entry.name.startswith("__editable__"):
            (deps / entry.name).symlink_to(entry)
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=False).create(env_dir)
    py = env_dir / "bin" / "python"
    site = Path(subprocess.check_output(
        [str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], text=True).strip())
    (site / "zz_test_deps.pth").write_text(f"{deps}\n")
    _pip("--python", str(py), "install", "-q", "--no-deps", "--no-index", str(wheel))
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    run = [str(env_dir / "bin" / "skelscope")]
    assert subprocess.run([*run, "--help"], capture_output=True, text=True, env=env, cwd=tmp_path).returncode == 0
    proc = subprocess.run(run, capture_output=True, text=True, env=env, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and "pip install 'skelscope[app]'" in proc.stderr, proc.stderr
    assert "PySide6" in proc.stderr and "Traceback" not in proc.stderr
    engine = subprocess.run([str(py), "-c", "import skelcore; print(skelcore.evaluate.__name__)"], capture_output=True,
                            text=True, env=env, cwd=tmp_path)
    assert engine.returncode == 0, engine.stderr


def test_sdist_holds_the_project_and_builds_the_wheel(sdist, wheel):
    """The source distribution is the whole tracked project (tests, docs, examples, samples, scans), and
    its unpacked tree builds the wheel (the module's wheel is built from it); the long description renders
    as the package index renders it."""
    from readme_renderer.markdown import render

    names, _src = sdist
    tracked = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    left_out = [f for f in tracked if f not in names and not f.startswith((".gitignore", "."))]
    assert left_out == []
    meta = next(n for n in zipfile.ZipFile(wheel).namelist() if n.endswith("METADATA"))
    text = zipfile.ZipFile(wheel).read(meta).decode()
    description = text.split("\n\n", 1)[1]
    assert "Description-Content-Type: text/markdown" in text
    assert render(description) is not None and len(description) > 500
    import re

    relative = re.findall(r"\]\((?!https?://|#)[^)]*\)", description)
    assert relative == []
