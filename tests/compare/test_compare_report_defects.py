"""report.html draws each job's defects: a compare run on the generated Y with its true
curve and three broken copies (an arm truncated, spurs poking out, a chord closing a loop inside):
each broken job's defect picture has pixels of its defects' colours where the defective elements
project, the sound job's has none, and the legend names only what was found."""

from __future__ import annotations

import csv
import itertools
import re

import numpy as np
import pytest
from scipy.spatial import cKDTree

from compare_helpers import manifest
from diagnostics_helpers import attach_path
from skelcore import colors, shapes
from skelcore.compare import Backend, run_compare
from skelcore.display.scene import _bounds
from skelcore.compare.render_defects import DRAWN
from skelcore.io import write_curve_ply, write_points_ply

SIZE = 320
TOL = 12  # RGB distance (0..255) of a pixel drawn in a colour, unlit


def _truncated(v: np.ndarray, e: np.ndarray):
    """The +y arm cut at half its length (its far vertices and their edges dropped)."""
    keep = v[:, 1] <= 1.0
    idx = np.cumsum(keep) - 1
    return v[keep], idx[e[keep[e].all(axis=1)]]


def _spurs(v: np.ndarray, e: np.ndarray, r: np.ndarray):
    """Two spurs 3 local radii long, straight up and down from inner vertices of two arms."""
    for a, u in ((3, (0, 0, 1.0)), (14, (0, 0, -1.0))):
        v, e, _ = attach_path(v, e, a, v[a] + 3 * r[a] * np.array(u), 6)
    return v, e


def _loop(v: np.ndarray, e: np.ndarray, r: np.ndarray):
    """A chord from vertex 3 to vertex 6 of the +y arm through a point 0.5 r above their midpoint."""
    m = (v[3] + v[6]) / 2 + np.array([0, 0, 0.5 * r[3]])
    v, e, _ = attach_path(v, e, 3, m, 2)
    return v, np.vstack([e, [[len(v) - 1, 6]]])


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    root = tmp_path_factory.mktemp("repdef")
    (root / "clouds").mkdir()
    (root / "skel").mkdir()
    sh = shapes.y_shape(1500, seed=4)
    write_points_ply(root / "clouds" / "y.ply", sh.cloud)
    v, e = sh.curve_vertices, sh.curve_edges
    r = cKDTree(sh.cloud).query(v)[0]
    curves = {"truth": (v, e), "truncated": _truncated(v, e), "spurs": _spurs(v, e, r), "loop": _loop(v, e, r)}
    for name, (cv, ce) in curves.items():
        write_curve_ply(root / "skel" / f"y_{name}.ply", cv, ce)
    body = '[[shapes]]\npath = "clouds/*.ply"\n' + "".join(
        f'[[methods]]\nname = "{n}"\nkind = "files"\ncurve = "skel/{{stem}}_{n}.ply"\n' for n in curves)
    m = manifest(root, body + '[[conditions]]\nname = "normal"\n')
    out = root / "out"
    run_compare(m, out, Backend("serial"), report=True)
    with open(out / "results.csv", newline="") as fh:
        rows = {r["method"]: r for r in csv.DictReader(fh)}
    return out, rows, sh, curves


def _image(path) -> np.ndarray:
    from matplotlib import image as mpimg

    return np.rint(mpimg.imread(path)[..., :3] * 255).astype(int)


def _mask(img: np.ndarray, code: str) -> np.ndarray:
    return np.linalg.norm(img - np.array(colors.DEFECT_COLORS[code]), axis=2) <= TOL


def _project(cloud: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """(row, col) pixels of ``pts`` under the defect picture's camera (isometric, fitted to the cloud)."""
    import pyvista as pv

    pl = pv.Plotter(off_screen=True, window_size=[SIZE, SIZE])
    try:
        pl.add_points(np.asarray(cloud, float))
        pl.camera_position = "iso"
        pl.reset_camera(bounds=_bounds(np.asarray(cloud, float)))
        pl.render()
        ren, out = pl.renderer, []
        for p in np.asarray(pts, float):
            ren.SetWorldPoint(*p, 1.0)
            ren.WorldToDisplay()
            x, y, _ = ren.GetDisplayPoint()
            out.append((SIZE - 1 - y, x))
    finally:
        pl.close()
    return np.array(out)


def _near(mask: np.ndarray, pixels: np.ndarray, px: float) -> float:
    """The share of the mask's pixels within ``px`` of one of ``pixels``."""
    rc = np.argwhere(mask)
    d, _ = cKDTree(pixels).query(rc)
    return float((d <= px).mean())


def _segment_points(v: np.ndarray, edges: np.ndarray, n: int = 12) -> np.ndarray:
    t = np.linspace(0, 1, n)[:, None, None]
    return (v[edges[:, 0]][None] * (1 - t) + v[edges[:, 1]][None] * t).reshape(-1, 3)


def test_the_defect_colours_are_their_own():
    """No defect colour is near a viridis entry, magenta, another defect's or a scene colour (CIELAB)."""
    def lab(rgb):
        c = np.asarray(rgb, float) / 255
        c = np.where(c > 0.04045, ((c + 0.055) / 1.055) ** 2.4, c / 12.92)
        m = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
        xyz = c @ m.T / np.array([0.9505, 1.0, 1.089])
        f = np.where(xyz > 0.008856, np.cbrt(xyz), 7.787 * xyz + 16 / 116)
        return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], -1)

    viridis = lab(colors.lookup_table(colors.METRIC_COLORMAP, 256))
    scene = [colors.MAGENTA, colors.CLOUD_GREY, colors.SKELETAL_COLOR, colors.CURVE_COLOR, colors.PICK_COLOR,
             colors.DEFECT_SKELETON, (255, 255, 255), *colors.SUPPORT_COLORS.values()]
    for code, c in colors.DEFECT_COLORS.items():
        assert np.linalg.norm(viridis - lab(c), axis=1).min() >= 20, code
        assert min(np.linalg.norm(lab(s) - lab(c)) for s in scene) >= 20, code
    for a, b in itertools.combinations(colors.DEFECT_COLORS.values(), 2):
        assert np.linalg.norm(lab(a) - lab(b)) >= 20


def test_the_broken_jobs_have_the_expected_defects(run):
    _out, rows, _sh, _c = run
    assert rows["truth"]["defects"] == ""
    assert rows["truncated"]["defects"] == "incomplete"
    assert {"spurious_branches", "outside"} <= set(rows["spurs"]["defects"].split(";"))
    assert "spurious_cycles" in rows["loop"]["defects"].split(";")


def test_each_defect_is_drawn_in_its_colour_where_it_is_and_a_sound_job_shows_none(run):
    out, rows, sh, curves = run
    pics = {m: _image(out / "renders" / f"{r['key']}_defects.png") for m, r in rows.items()}
    for img in pics.values():
        assert img.shape[:2] == (SIZE, SIZE)
    # the sound job: the skeleton in grey, no pixel of any defect colour
    for code in DRAWN:
        assert not _mask(pics["truth"], code).any(), code
    # truncated: the missing cloud points are the cut arm's (y > 1), drawn in the missing parts' colour
    miss = _mask(pics["truncated"], "incomplete")
    assert miss.sum() > 200
    cut_arm = sh.cloud[sh.cloud[:, 1] > 0.9]
    assert _near(miss, _project(sh.cloud, cut_arm), 3) > 0.95
    assert _near(miss, _project(sh.cloud, sh.cloud[sh.cloud[:, 1] < 0.5]), 1) < 0.2
    for code in DRAWN[1:]:
        assert not _mask(pics["truncated"], code).any(), code
    # spurs: the spurs' edges (those added to the true curve) in the spurious branches' colour, and where
    # they leave the shape in the outside colour
    v, e = curves["spurs"]
    n_true = len(sh.curve_edges)
    spur_px = _project(sh.cloud, _segment_points(v, e[n_true:]))
    for code in ("spurious_branches", "outside"):
        mask = _mask(pics["spurs"], code)
        assert mask.sum() > 20, code
        assert _near(mask, spur_px, 6) > 0.95, code
    assert not _mask(pics["spurs"], "incomplete").any() and not _mask(pics["spurs"], "spurious_cycles").any()
    # the loop: the short cycle in the spurious cycles' colour (the chord and the arm between its ends, vertices 3-6)
    v, e = curves["loop"]
    cyc = np.vstack([e[n_true:], [[3, 4], [4, 5], [5, 6]]])
    mask = _mask(pics["loop"], "spurious_cycles")
    assert mask.sum() > 20 and _near(mask, _project(sh.cloud, _segment_points(v, cyc)), 6) > 0.95
    far = np.flatnonzero(np.linalg.norm(v - v[0], axis=1) > 1.5)  # the other arms' far halves
    far_e = e[np.isin(e, far).all(axis=1)]
    assert _near(mask, _project(sh.cloud, _segment_points(v, far_e)), 2) < 0.05


def test_the_legend_names_only_what_was_found(run):
    out, rows, _sh, _c = run
    page = (out / "report.html").read_text()
    cells = re.findall(r"(<ul class=legend>.*?</ul>|<div class=legend>.*?</div>)", page)
    assert len(cells) == 4  # one per job, in manifest order
    by = dict(zip(["truth", "truncated", "spurs", "loop"], cells))
    assert "no defect found" in by["truth"]
    named = {m: set(re.findall(r"background:(#[0-9a-f]{6})", c)) for m, c in by.items()}
    hexes = {k: colors.hex_color(c) for k, c in colors.DEFECT_COLORS.items()}
    assert named["truth"] == set()
    assert named["truncated"] == {hexes["incomplete"]} and "missing parts: " in by["truncated"]
    assert named["spurs"] == {hexes["spurious_branches"], hexes["outside"]}
    assert "spurious branches" in by["spurs"] and "outside the shape" in by["spurs"]
    assert hexes["spurious_cycles"] in named["loop"] and "spurious cycles" in by["loop"]
    assert "<th>defects</th>" in page


def test_the_pictures_drawn_on_the_report_s_shared_plotter_are_those_of_a_plotter_each(run, tmp_path):
    """report.html draws every 3D picture on one off-screen plotter (skelcore.display.plotter.OffscreenPlotter):
    the last job's pictures, drawn after the other jobs' on it, are byte for byte those drawn each on a
    plotter of its own."""
    from skelcore.compare.job_store import Store
    from skelcore.compare.render import VIEWS, render_job
    from skelcore.compare.render_defects import defect_layers, render_defects
    from skelcore.diagnostics.trust import DEFECT_CODES

    out, rows, _sh, _c = run
    store = Store(out)
    key = rows["loop"]["key"]  # the last in the table
    arrays = store.arrays(key)
    fresh = render_job(tmp_path, key, arrays)
    for view in VIEWS:
        assert fresh[view].read_bytes() == (out / "renders" / f"{key}_{view}.png").read_bytes(), view
    codes = [w["code"] for w in store.get(key)["evaluation"]["warnings"] if w["code"] in DEFECT_CODES]
    alone = render_defects(tmp_path, key, arrays, defect_layers(arrays, codes))
    assert alone.read_bytes() == (out / "renders" / f"{key}_defects.png").read_bytes()


def test_the_shared_plotter_renders_each_picture_once(run, tmp_path):
    """pyvista renders a shown plotter at every actor added and camera reset; the shared plotter holds
    that back while a picture is drawn and renders it once (VTK's render-window StartEvent counted)."""
    from skelcore.compare.job_store import Store
    from skelcore.compare.render import SIZE, VIEWS, render_job
    from skelcore.display.plotter import OffscreenPlotter

    out, rows, _sh, _c = run
    key = rows["loop"]["key"]
    arrays = Store(out).arrays(key)
    renders = []
    with OffscreenPlotter(SIZE) as shared:
        shared.png(lambda pl: pl.add_points(arrays["cloud"]))  # the first picture makes the window
        shared._pl.render_window.AddObserver("StartEvent", lambda *_: renders.append(1))
        paths = render_job(tmp_path, key, arrays, plotter=shared)
    three_d = [v for v in VIEWS if v != "barcodes"]
    assert len(renders) == len(three_d)
    for view in VIEWS:
        assert paths[view].read_bytes() == (out / "renders" / f"{key}_{view}.png").read_bytes(), view
