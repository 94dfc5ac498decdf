"""The repository is self-contained: its files name no folder outside it and no machine's absolute
path, and the real scans that tests, golden outputs and benchmarks read ship in resources/scans with
their licence notice beside them."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCANS = ROOT / "resources" / "scans"
SCAN_FILES = ("hammer_4096.ply", "apple_tree_22367.ply", "cave_27375.ply", "horse_1987_mesh.ply")

# a folder beside the repository, or an absolute path on one machine (written in pieces, so that this
# file, which is excluded anyway, does not match itself when copied elsewhere)
OUTSIDE = re.compile("|".join([r"\.\./" + "shared", "shared" + "/data", "shared" + "/SP" + "EC",
                               "/" + "work/", "/" + "root/", "/" + "home/"]).encode())
#: folders of a working tree that are not part of the repository (when git is not there to say so)
NOT_SOURCES = {".git", ".venv", "build", "dist", "__pycache__", ".pytest_cache", ".hypothesis", "_build",
               "gallery", "out"}


def _repository_files() -> list[Path]:
    """The tracked files (``git ls-files``); without git, every file of the tree less build output."""
    try:
        out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True, timeout=60)
        names = [n for n in out.stdout.decode().split("\0") if n]
        if names:
            return [ROOT / n for n in names]
    except (OSError, subprocess.SubprocessError):
        pass
    files = []
    for folder, dirs, names in os.walk(ROOT):
        dirs[:] = [d for d in dirs if d not in NOT_SOURCES and not d.endswith(".egg-info")]
        files += [Path(folder) / n for n in names]
    return files


def test_no_file_names_a_folder_outside_the_repository_or_a_machine_path():
    me = Path(__file__).resolve()
    hits = []
    for path in _repository_files():
        if path.resolve() == me or not path.is_file():
            continue
        data = path.read_bytes()
        if b"\0" in data[:8192]:  # binary (scans, pictures, stored arrays)
            continue
        for no, line in enumerate(data.splitlines(), 1):
            if OUTSIDE.search(line):
                hits.append(f"{path.relative_to(ROOT)}:{no}: {line.decode(errors='replace').strip()[:120]}")
    assert hits == []


def test_the_real_scans_ship_with_their_licence_notice(scans):
    assert scans == SCANS
    for name in SCAN_FILES:
        path = SCANS / name
        assert path.is_file(), name
        assert path.read_bytes().startswith(b"ply\n"), name
    notice = (SCANS / "LICENSE").read_text(encoding="utf-8")
    assert "MIT License" in notice
    assert "Copyright (c) 2025 weiqimeng1" in notice
    assert "weiqimeng1/PointCloud_Skeletonization_Metrics" in notice
    assert "THE SOFTWARE IS PROVIDED \"AS IS\"" in notice
    readme = (SCANS / "README.md").read_text(encoding="utf-8")
    assert all(name in readme for name in SCAN_FILES)
    assert "LICENSE" in readme


def test_the_scans_load_with_the_sizes_their_readme_gives(scans):
    from skelcore.io import load_cloud

    sizes = {"hammer_4096.ply": 4096, "apple_tree_22367.ply": 22367, "cave_27375.ply": 27375,
             "horse_1987_mesh.ply": 1987}
    for name, n in sizes.items():
        assert load_cloud(scans / name).shape == (n, 3), name
