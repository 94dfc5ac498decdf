"""report.html in a real headless Chromium (every image decoded, the page not blank, nothing from
the network) and ``skelcore figure`` (PNG and PDF of the graphic table)."""

from __future__ import annotations

import io
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from compare_helpers import command, make_dataset, manifest
from headless_chromium import browser
from skelcore.cli import main
from skelcore.compare import Backend, run_compare
from skelcore.compare.render import VIEWS

PICTURES = len(VIEWS) + 1  # per finished job: the paper's views and the defect picture


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    root = make_dataset(tmp_path_factory.mktemp("rep"), n=600)
    m = manifest(root, f"""
    [[shapes]]
    path = "clouds/*.ply"
    [[methods]]
    name = "truth"
    kind = "files"
    curve = "skeletons/{{stem}}_curve.ply"
    skeletal = "skeletons/{{stem}}_skeletal.ply"
    [[methods]]
    name = "line"
    kind = "command"
    command = "{command('line')}"
    [[methods]]
    name = "crash"
    kind = "command"
    command = "{command('crash')}"
    [[conditions]]
    name = "normal"
    """)
    res = run_compare(m, root / "out", Backend("serial"), report=True)
    return root, res


def _image(path: Path) -> np.ndarray:
    from matplotlib import image as mpimg

    return mpimg.imread(path)


def _not_blank(img: np.ndarray) -> float:
    rgb = img[..., :3]
    return float((rgb.min(axis=2) < 0.9).mean())  # fraction of pixels that are not (near) white


def test_the_report_is_one_self_contained_file(run):
    root, res = run
    text = Path(res.files["report"]).read_text()
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:|//)""", text)
    assert "<link" not in text
    n_img = text.count("<img ")
    # 4 finished jobs x (5 views + defects) + the distributions; the crashed jobs show their error instead
    assert n_img == 4 * PICTURES + 1
    assert text.count("data:image/png;base64,") == n_img
    assert "exited with status 139" in text and "Leaderboard" in text and "our reading" in text


def test_headless_chromium_loads_every_image_and_draws_a_page(run, tmp_path):
    root, res = run
    url = Path(res.files["report"]).resolve().as_uri()
    dom = browser(tmp_path, "--dump-dom", url)
    assert dom.returncode == 0, dom.stderr[-500:]
    loaded = re.search(r'data-images="(\d+)/(\d+)"', dom.stdout)
    assert loaded, "the page's load script did not run"
    assert loaded.group(1) == loaded.group(2) == str(4 * PICTURES + 1)
    shot = tmp_path / "report.png"
    r = browser(tmp_path, f"--screenshot={shot}", "--window-size=1400,2200", url)
    assert r.returncode == 0 and shot.exists(), r.stderr[-500:]
    img = _image(shot)
    assert img.shape[:2] == (2200, 1400)
    assert _not_blank(img) > 0.03
    shutil.copy(shot, root / "out" / "report_screenshot.png")  # to look at


def test_each_render_shows_the_shape(run):
    root, res = run
    renders = sorted((root / "out" / "renders").glob("*.png"))
    assert len(renders) == 4 * PICTURES
    for p in renders:
        img = _image(p)
        assert img.shape[:2] == (320, 320) and _not_blank(img) > 0.005, p.name
    # the metric views are coloured (viridis or magenta), not only the grey cloud
    colourful = [p for p in renders if p.stem.endswith(("boundedness", "centeredness", "smoothness"))]
    for p in colourful:
        rgb = _image(p)[..., :3]
        sat = rgb.max(axis=2) - rgb.min(axis=2)
        assert (sat > 0.3).mean() > 0.001, p.name


def test_a_rerun_redraws_nothing(run):
    root, res = run
    before = {p: p.stat().st_mtime_ns for p in (root / "out" / "renders").iterdir()}
    again = run_compare(res.manifest.path, root / "out", Backend("serial"), report=True)
    assert again.summary.skipped == again.summary.total == 6
    assert {p: p.stat().st_mtime_ns for p in (root / "out" / "renders").iterdir()} == before


def test_the_distributions_and_barcode_figures_are_drawn_once(run, monkeypatch):
    """Each figure is laid out once and drawn once (savefig would draw it once more under the
    placeholder engine that ``tight_layout`` leaves behind)."""
    from matplotlib.figure import Figure

    from skelcore.compare.job_store import Store
    from skelcore.compare.report import distributions_png
    from skelcore.compare.render import SIZE
    from skelcore.display.barcodes import barcode_png

    root, res = run
    draws = []
    draw = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, renderer: draws.append(1) or draw(self, renderer))
    png = distributions_png(res.rows, ["truth", "line", "crash"], ["normal"])
    assert len(draws) == 1
    img = _image(io.BytesIO(png))
    assert img.shape[1] == 4 * 288 and _not_blank(img) > 0.02
    key = next(r["key"] for r in res.rows if r["status"] == "ok")
    png = barcode_png(Store(root / "out").arrays(key), SIZE)
    assert len(draws) == 2
    assert png == (root / "out" / "renders" / f"{key}_barcodes.png").read_bytes()  # the report's picture

def test_figure_png_and_pdf(run, tmp_path, capsys):
    root, _res = run
    png = tmp_path / "fig.png"
    assert main(["figure", str(root / "out"), "-o", str(png), "--dpi", "80"]) == 0
    assert "4 rows" in capsys.readouterr().out
    img = _image(png)
    assert img.shape[0] > img.shape[1] * 0.5 and _not_blank(img) > 0.03
    shutil.copy(png, root / "out" / "figure.png")
    pdf = tmp_path / "fig.pdf"
    assert main(["figure", str(root / "out"), "-o", str(pdf), "--shapes", "cyl", "--methods", "truth"]) == 0
    assert pdf.read_bytes().startswith(b"%PDF") and "1 rows" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args, message",
    [
        (["--shapes", "horse"], "unknown shape(s) horse"),
        (["--methods", "crash"], "no finished job matches"),
        (["-o", "fig.jpg"], "must end in .png, .pdf or .svg"),
    ],
)
def test_figure_errors_are_one_line(run, tmp_path, capsys, args, message):
    root, _res = run
    argv = ["figure", str(root / "out"), "-o", str(tmp_path / "f.png"), *args]
    if "-o" in args:
        argv = ["figure", str(root / "out"), *[str(tmp_path / a) if a.endswith(".jpg") else a for a in args]]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_figure_of_a_folder_that_is_not_a_run(tmp_path, capsys):
    assert main(["figure", str(tmp_path), "-o", str(tmp_path / "f.png")]) == 2
    assert "no index.json" in capsys.readouterr().err
