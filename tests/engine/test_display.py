"""Evaluation.show, show_barcodes, _repr_html_ and skelcore.show_ab outside a notebook:
the PNGs are read back and their pixels checked (the colour bar's viridis, magenta where an element
is invalid, docs/metrics.md 5.5), the HTML table against the scores computed from the local arrays."""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

import skelcore
from skelcore import colors
from skelcore.display import where
from skelcore.display.summary_table import HEADER
from skelcore.errors import SkelInputError

pytest.importorskip("pyvista")
pytest.importorskip("matplotlib")

SAMPLES = Path(__file__).resolve().parents[2] / "resources" / "samples"
SIZE = (400, 300)


def truncated(curve: skelcore.CurveSkeleton, y_max: float) -> skelcore.CurveSkeleton:
    """The curve without its vertices above ``y_max`` (the end of the Y's upper arm)."""
    keep = curve.vertices[:, 1] < y_max
    edges = curve.edges[keep[curve.edges].all(axis=1)]
    return skelcore.CurveSkeleton.from_raw(curve.vertices[keep], (np.cumsum(keep) - 1)[edges])


@pytest.fixture(scope="module")
def sample():
    cloud = skelcore.load_cloud(SAMPLES / "yshape_cloud.ply")
    skeletal = skelcore.load_points(SAMPLES / "yshape_skeletal.ply")
    curve = skelcore.load_curve(SAMPLES / "yshape_curve.ply")
    return cloud, skeletal, curve


@pytest.fixture(scope="module")
def ev(sample):
    cloud, skeletal, curve = sample
    return skelcore.evaluate(cloud, skeletal=skeletal, curve=curve)


@pytest.fixture(scope="module")
def ev_cut(sample):
    cloud, _skeletal, curve = sample
    return skelcore.evaluate(cloud, curve=truncated(curve, 0.8))


def _rgb(path: Path) -> np.ndarray:
    from matplotlib import image as mpimg

    img = mpimg.imread(path)
    return np.rint(img[..., :3] * 255).astype(int)


def _near(img: np.ndarray, rgb, tol: int = 30) -> np.ndarray:
    return (np.abs(img - np.asarray(rgb)) <= tol).all(axis=2)


def _lut_pixels(img: np.ndarray) -> np.ndarray:
    """Index into the 256-entry metric colour map of each pixel close to one of its colours, -1 else."""
    from scipy.spatial import cKDTree

    lut = colors.lookup_table(colors.METRIC_COLORMAP, 256).astype(float)
    dist, idx = cKDTree(lut).query(img.reshape(-1, 3).astype(float), p=np.inf, distance_upper_bound=6.5)
    return np.where(np.isfinite(dist), idx, -1).reshape(img.shape[:2])


def _bar_box(img: np.ndarray) -> np.ndarray:
    """The colour bar's part of a panel (right 16 %, middle 70 % of the height)."""
    h, w = img.shape[:2]
    return img[int(0.15 * h): int(0.85 * h), int(0.84 * w):]


def test_show_writes_the_png_with_the_colour_bar_and_magenta_nan(ev, tmp_path):
    assert np.isnan(ev.curve.vertex_smoothness).any()  # the ends and the junction (docs/metrics.md 4)
    out = ev.show("smoothness", path=tmp_path / "s.png", size=SIZE)
    assert out == tmp_path / "s.png" and out.stat().st_size > 1000
    img = _rgb(out)
    assert img.shape[:2] == (SIZE[1], SIZE[0])
    bar = _lut_pixels(_bar_box(img))
    assert (bar >= 0).sum() > 200  # the bar's gradient
    rows_low, rows_high = np.nonzero((bar >= 0) & (bar < 20))[0], np.nonzero(bar > 235)[0]
    assert len(rows_low) > 10 and len(rows_high) > 10
    assert rows_high.mean() < rows_low.mean()  # 1.0 (yellow) at the top, 0.0 (purple) below
    assert _near(img, colors.NAN_COLOR).sum() > 10


def test_magenta_only_where_an_element_is_invalid(ev, tmp_path):
    plain = ev.show("smoothness", path=tmp_path / "nan.png", size=SIZE, colour_bar=False)
    assert _near(_rgb(plain), colors.NAN_COLOR).sum() > 10  # the NaN vertices themselves, no legend
    assert (_lut_pixels(_bar_box(_rgb(plain))) >= 0).sum() < 20  # and no bar
    assert not np.isnan(ev.curve.sample_boundedness).any()
    valid = ev.show("boundedness", path=tmp_path / "b.png", size=SIZE)
    img = _rgb(valid)
    assert _near(img, colors.NAN_COLOR).sum() == 0
    assert (_lut_pixels(img) >= 0).sum() > 100


def test_show_colours_the_skeletal_set_when_asked_or_without_a_curve(sample, ev, tmp_path):
    cloud, skeletal, _curve = sample
    only_points = skelcore.evaluate(cloud, skeletal=skeletal)
    a = _rgb(only_points.show("centeredness", path=tmp_path / "a.png", size=SIZE, colour_bar=False))
    b = _rgb(ev.show("centeredness", path=tmp_path / "b.png", size=SIZE, colour_bar=False, prefer="skeletal"))
    assert (_lut_pixels(a) >= 0).sum() > 500  # thousands of coloured points, not a curve's few hundred
    assert np.abs(a - b).max(axis=2).mean() < 20


def test_without_a_display_show_writes_a_new_png_in_the_current_folder(ev, tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.chdir(tmp_path)
    assert not where.has_display() and not where.in_notebook()
    first = ev.show("smoothness", size=SIZE)
    data = first.read_bytes()
    second = ev.show("smoothness", size=SIZE)
    assert first == Path("skelscope_smoothness.png") and second == Path("skelscope_smoothness_2.png")
    assert first.read_bytes() == data and second.stat().st_size > 1000  # never over an existing file
    assert "no display: wrote skelscope_smoothness.png" in capsys.readouterr().err
    bars = ev.show_barcodes()
    assert bars == Path("skelscope_barcodes.png") and bars.stat().st_size > 1000


def test_with_a_display_show_opens_a_window(ev, tmp_path, monkeypatch):
    pv = pytest.importorskip("pyvista")
    if not where.has_display():
        pytest.skip("no display")
    monkeypatch.setattr(pv, "OFF_SCREEN", True)  # pyvista's own switch: the window's show() returns at once
    monkeypatch.chdir(tmp_path)
    assert ev.show("centeredness", size=SIZE) is None
    assert list(tmp_path.iterdir()) == []


def test_importing_the_display_loads_no_plotting_library():
    import subprocess
    import sys

    code = ("import sys, skelcore, skelcore.display, skelcore.evaluation, skelcore.compare.render\n"
            "print(sorted(m for m in ('pyvista', 'vtk', 'matplotlib', 'IPython') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_bad_arguments(ev, tmp_path):
    with pytest.raises(ValueError, match="unknown metric 'thickness'"):
        ev.show("thickness")
    with pytest.raises(SkelInputError, match="ending in .png"):
        ev.show("smoothness", path=tmp_path / "s.jpg")
    assert not (tmp_path / "s.jpg").exists()


def test_show_barcodes_draws_both_diagrams(ev, tmp_path):
    out = ev.show_barcodes(path=tmp_path / "bars.png", size=(480, 360))
    img = _rgb(out)
    assert img.shape[:2] == (360, 480)
    h = img.shape[0]
    # anti-aliased thin bars: the cloud's light grey (even channels), the skeleton's blue (b well above r)
    grey = (np.ptp(img, axis=2) < 6) & (img[..., 0] > 140) & (img[..., 0] < 240)
    blue = img[..., 2] - img[..., 0] > 40
    cloud_rows = np.nonzero(grey.sum(axis=1) > 20)[0]
    skel_rows = np.nonzero(blue.sum(axis=1) > 20)[0]
    assert len(cloud_rows) > h / 10 and len(skel_rows) > h / 10
    assert cloud_rows.mean() < skel_rows.mean()  # the cloud's bars above the skeleton's


def test_show_ab_side_by_side_one_colour_range_and_both_tables(ev, ev_cut, tmp_path, capsys):
    out = skelcore.show_ab(ev, ev_cut, "centeredness", labels=("full", "cut"), path=tmp_path / "ab.png", size=SIZE)
    img = _rgb(out)
    assert img.shape[:2] == (SIZE[1], 2 * SIZE[0])
    left, right = img[:, : SIZE[0]], img[:, SIZE[0]:]
    assert (_lut_pixels(_bar_box(right)) >= 0).sum() > 200  # one colour bar, for both panels
    assert (_lut_pixels(_bar_box(left)) >= 0).sum() < 20
    assert (_lut_pixels(left) >= 0).sum() > (_lut_pixels(right[:, : int(0.84 * SIZE[0])]) >= 0).sum() > 50
    text = capsys.readouterr().out
    assert text.index("full:") < text.index("cut:")
    assert text.count("boundedness") == 2 and "[incomplete]" in text.split("cut:")[1]


class _Cells(HTMLParser):
    """Rows of the first table's cells, and the text of every <li>."""

    def __init__(self) -> None:
        super().__init__()
        self.rows: list[list[str]] = []
        self.items: list[str] = []
        self._cell: list[str] | None = None
        self._tables = 0

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self._tables += 1
        if tag == "tr" and self._tables == 1:
            self.rows.append([])
        if tag in ("td", "th", "li"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None and self._tables == 1:
            self.rows[-1].append("".join(self._cell))
        if tag == "li" and self._cell is not None:
            self.items.append("".join(self._cell))
        if tag in ("td", "th", "li"):
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _parse(text: str) -> _Cells:
    p = _Cells()
    p.feed(text)
    return p


def test_repr_html_is_the_papers_table_with_the_defects(ev, ev_cut):
    p = _parse(ev._repr_html_())
    assert p.rows[0] == list(HEADER)
    rows = {r[0]: r[1:] for r in p.rows[1:]}
    assert list(rows)[:4] == ["d_B / d_Wp", "boundedness", "centeredness", "smoothness"]
    b_star = ev.params.beta_star
    samples = ev.curve.sample_boundedness  # the fraction bounded, from the local values (docs/metrics.md 2)
    assert rows["boundedness"][1] == f"{np.mean(samples > b_star):.3f} (n={len(samples)})"
    sm = ev.skeletal.smoothness
    assert rows["smoothness"][0] == f"{np.nanmean(sm):.3f} (n={np.isfinite(sm).sum()})"
    assert rows["d_B / d_Wp"][0] == f"{ev.topology.bottleneck:.4f} / {ev.topology.wasserstein:.4f}"
    assert "defects:</b> none found" in ev._repr_html_()
    cut = _parse(ev_cut._repr_html_())
    assert cut.rows[1][1:] == ["-", "-"]  # no skeletal set: no d_B
    assert any(item.startswith("[incomplete] the curve skeleton does not reach") for item in cut.items)


def test_repr_html_lists_the_other_warnings_and_escapes(sample):
    cloud, _skeletal, curve = sample
    lo, hi = cloud.min(axis=0), cloud.max(axis=0)
    one_edge = skelcore.CurveSkeleton.from_raw(np.array([lo + 0.45 * (hi - lo), lo + 0.55 * (hi - lo)]), [[0, 1]])
    ev1 = skelcore.evaluate(cloud, curve=one_edge)
    codes = {w.code for w in ev1.warnings}
    assert "trivial_smoothness" in codes
    text = ev1._repr_html_()
    assert re.search(r"warnings:</b>.*\[trivial_smoothness\]", text, re.S)
    assert "<script" not in text and "'" not in re.sub(r"<[^>]*>", "", text)  # quotes escaped
