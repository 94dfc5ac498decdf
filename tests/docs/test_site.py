"""The documentation site: ``make docs``'s build, warnings as errors, from a copy
of the sources in a temporary folder (so the gallery really runs and nothing is written into the
tree), then its front page and one gallery page opened in headless Chromium."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from headless_chromium import browser

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow  # one Sphinx build, about 25 s of CPU


def _image(path: Path) -> np.ndarray:
    from matplotlib import image as mpimg

    return mpimg.imread(path)[..., :3]


def _not_white(rgb: np.ndarray) -> float:
    return float((rgb.min(axis=2) < 0.9).mean())


def _viridis_bins(rgb: np.ndarray, n: int = 32) -> int:
    """How many of viridis' n colour bins the picture shows (>= 20 pixels within 0.04 of the bin's
    colour): a figure's colour bar shows them all, the theme's text and code colours none."""
    from skelcore import colors

    lut = colors.lookup_table("viridis", n)[:, :3] / 255.0
    px = rgb.reshape(-1, 3)
    px = px[px.max(axis=1) - px.min(axis=1) > 0.15]
    d = np.linalg.norm(px[:, None, :] - lut[None], axis=2)
    near = d.min(axis=1) < 0.04
    return int((np.bincount(d.argmin(axis=1)[near], minlength=n) >= 20).sum())


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """Build the site as ``make docs`` does (-W --keep-going), from a copy of its sources."""
    src = tmp_path_factory.mktemp("site-src")
    shutil.copytree(ROOT / "docs", src / "docs", ignore=shutil.ignore_patterns("_build", "gallery"))
    for name in ("README.md", "CHANGELOG.md"):
        shutil.copy(ROOT / name, src / name)
    for name in ("examples", "screenshots"):  # read only: the gallery's scripts, the viewer's pictures
        (src / name).symlink_to(ROOT / name)
    out = src / "html"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
           "MPLBACKEND": "Agg"}
    r = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                        "-d", str(src / "doctrees"), str(src / "docs"), str(out)],
                       capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0, (r.stdout + r.stderr)[-3000:]
    return out


def test_every_page_of_the_guide_is_built(site):
    pages = {"index", "guide/getting_started", "guide/cli", "guide/viewer", "guide/metrics/topology",
             "guide/metrics/boundedness", "guide/metrics/centeredness", "guide/metrics/smoothness",
             "skeletonizers", "guide/compare", "guide/diagnostics", "api/evaluate", "api/io", "api/compare",
             "changelog", "notes", "gallery/index"}
    missing = [p for p in pages if not (site / f"{p}.html").is_file()]
    assert not missing
    # the developer notes list every other docs/*.md (a note added later is listed without an edit)
    notes = (site / "notes.html").read_text()
    for md in ("metrics", "boundedness", "performance", "layout"):
        assert f'href="{md}.html"' in notes, md
    # autodoc documented the public API from its docstrings
    api = (site / "api" / "evaluate.html").read_text()
    for name in ('id="skelcore.evaluate"', 'id="skelcore.Evaluation"', 'id="skelcore.Scores"', 'id="skelcore.Params"'):
        assert name in api, name
    # each metric's page carries its section of docs/metrics.md as the file stands (read at build time)
    notes = (ROOT / "docs" / "metrics.md").read_text()
    for page, start, end in (("topology", "## 1.", "## 2."), ("boundedness", "## 2.", "## 3."),
                             ("centeredness", "## 3.", "## 4."), ("smoothness", "## 4.", "## 5.")):
        section = notes[notes.index("\n" + start):notes.index("\n" + end)]
        first = re.search(r"^### [0-9.]+ ([^(`:]+)", section, re.MULTILINE).group(1).strip()
        assert first in (site / "guide" / "metrics" / f"{page}.html").read_text(), (page, first)
    # the CLI page's help texts come from the parser itself
    cli = (site / "guide" / "cli.html").read_text()
    assert "usage: skelcore evaluate" in cli and "--boundedness-method" in cli


def test_the_gallery_pictures_were_made_at_build_time(site):
    shots = sorted((site / "_images").glob("sphx_glr_plot_*_001.png"))
    assert len(shots) >= 3, shots
    for p in shots:
        rgb = _image(p)
        assert rgb.shape[0] > 200 and _not_white(rgb) > 0.02, p.name


def test_front_page_renders_in_headless_chromium(site, tmp_path):
    url = (site / "index.html").resolve().as_uri()
    shot = tmp_path / "index.png"
    # one launch: the DOM after the page's scripts ran on stdout, and the page's picture
    r = browser(tmp_path, "--dump-dom", f"--screenshot={shot}", "--window-size=1300,1000", url)
    assert r.returncode == 0 and shot.exists(), r.stderr[-500:]
    assert re.search(r"<title>\s*SkelScope", r.stdout)
    assert "Getting started" in r.stdout and "The metrics" in r.stdout
    rgb = _image(shot)
    assert rgb.shape[:2] == (1000, 1300)
    assert _not_white(rgb) > 0.01  # text and the sidebar, not a blank page


def test_a_gallery_page_renders_with_its_picture(site, tmp_path):
    page = site / "gallery" / "plot_01_score_a_skeleton.html"
    url = page.resolve().as_uri()
    shot = tmp_path / "gallery.png"
    r = browser(tmp_path, "--dump-dom", f"--screenshot={shot}", "--window-size=1300,3000", url)
    assert r.returncode == 0 and shot.exists(), r.stderr[-500:]
    assert "Score a skeleton and colour it by centeredness" in r.stdout
    assert "d_B / d_Wp" in r.stdout  # the script's printed table, captured at build time
    img = re.search(r'<img[^>]+src="([^"]*sphx_glr_plot_01_score_a_skeleton_001\.png)"', r.stdout)
    assert img, "the gallery page has no picture"
    assert (page.parent / img.group(1)).is_file()
    rgb = _image(shot)
    # the picture was decoded and drawn: its colour bar's viridis is on the page (0 bins without it)
    assert _viridis_bins(rgb) >= 24
