"""Pictures for a paper, checked by content under Xvfb: sizes follow the scale, the colour bar and
its legend of invalid values, tubes coloured by the metric, skeletal points visible under a curve, the empty
window's hint, figure options, camera files, the level of detail while the camera moves."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PySide6 import QtCore

import skelcore
from shape_files import write_shape_files
from skelcore import shapes
from skelcore.colors import SKELETAL_COLOR, lookup_table

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(1200, 800), questions="default")]

MAGENTA = (255, 0, 255)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    return write_shape_files(tmp_path_factory.mktemp("y"), shapes.y_shape(1500, seed=3))


@pytest.fixture(scope="module")
def evaluation(files):
    from skelcore.io import load_cloud, load_curve, load_points

    return skelcore.evaluate(load_cloud(files["cloud"]), load_points(files["skeletal"]), load_curve(files["curve"]),
                             inputs=dict(files))


@pytest.fixture
def evaluated(window, files, evaluation):
    window.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    window.session._evaluated_layers = (window.scene.cloud, window.scene.skeletal, window.scene.curve)
    window.session._task_succeeded("evaluation", evaluation)
    return window


def _rgb(img):
    return np.asarray(img)[..., :3].astype(int)


def _count(img, colour) -> int:
    return int(np.all(_rgb(img) == np.asarray(colour), axis=-1).sum())


def _grey(img) -> int:
    px = _rgb(img)
    spread = px.max(axis=-1) - px.min(axis=-1)
    return int(((spread <= 6) & (px[..., 0] > 90) & (px[..., 0] < 235)).sum())


def _on_map(img) -> int:
    lut = lookup_table("viridis", 256).astype(int)
    px = _rgb(img).reshape(-1, 3)
    px = px[(px.max(axis=1) - px.min(axis=1)) > 30]  # coloured pixels only
    hits = 0
    for chunk in np.array_split(px, max(1, len(px) // 20000 + 1)):
        hits += int((np.abs(chunk[:, None, :] - lut[None]).max(axis=2).min(axis=1) <= 12).sum())
    return hits


def test_point_sizes_and_line_widths_follow_the_screenshot_scale(window, files):
    window.session.load_files([files["cloud"], files["skeletal"]])
    window.scene.set_style("axes", False)
    one = window.view.image(scale=1)
    two = window.view.image(scale=2)
    assert two.shape[0] == 2 * one.shape[0]
    # 4x the pixels, each point 2x as wide: the cloud covers about 4x as many pixels, not the same
    ratio = _grey(two) / max(_grey(one), 1)
    assert ratio > 2.5, ratio
    # and the view itself is back to its own sizes afterwards
    assert window.view._actors["cloud"].prop.point_size == window.scene.cloud.point_size


@pytest.mark.parametrize("docks", ["shown", "hidden"])  # a narrow view and a wide one
def test_the_colour_bar_can_be_left_out_and_its_invalid_label_sits_right_of_the_swatch(evaluated, docks):
    """The legend of NaN values says "invalid" (docs/metrics.md 5.5), right of its swatch and whole."""
    w = evaluated
    if docks == "hidden":
        for dock in w.docks.values():
            dock.hide()
    w.scene.set_metric("smoothness")  # NaN at the Y's junction and tips
    w.view.image()  # one frame at the view's final size
    with_bar = w.view.image()
    without = w.view.image(colour_bar=False)
    bar = w.view._colour_bar
    assert bar.label.GetInput() == "invalid"
    assert bar.nan_shown and bar.label_starts_right_of_swatch() and bar.nan_legend_inside()
    assert not (_rgb(with_bar)[:, -2:].max(axis=-1) < 60).any()  # no text cut at the right edge
    size = [0.0, 0.0]
    bar.label.GetSize(w.view.plotter.renderer, size)
    narrow = 220  # a view too narrow for the label at its place: swatch and label move left together
    bar._place_nan_legend(narrow)
    assert bar.label_starts_right_of_swatch() and bar.label.GetPosition()[0] * narrow + size[0] <= narrow
    bar.layout()
    assert bar.nan_legend_inside()
    right = slice(int(with_bar.shape[1] * 0.86), None)
    dark = lambda img: int((_rgb(img)[:, right].max(axis=-1) < 60).sum())  # noqa: E731 - bar text and labels
    assert dark(with_bar) > 100 and dark(without) < dark(with_bar) / 10
    # the swatch's pixels: magenta, with no label text inside its box
    px = np.all(_rgb(with_bar)[:, right] == MAGENTA, axis=-1)
    rows, cols = np.nonzero(px)
    assert len(rows) > 50
    box = _rgb(with_bar)[:, right][rows.min():rows.max() + 1, cols.min():cols.max() + 1]
    assert (box.max(axis=-1) < 60).sum() == 0


def test_tubes_follow_the_checkbox_and_the_t_key_and_carry_the_metric_colours(evaluated):
    w = evaluated
    w.scene.set_visible("cloud", False)
    w.scene.set_visible("skeletal", False)
    w.scene.set_metric("centeredness")
    w.actions_by_name["tubes"].trigger()  # T
    assert w.scene.edges_as_tubes and w.display.tubes.isChecked() and w.actions_by_name["tubes"].isChecked()
    tubes = w.view._actors["curve-edges"]
    assert tubes.mapper.dataset.n_strips > 0 and tubes.mapper.scalar_visibility
    values = tubes.mapper.dataset.point_data["values"]
    assert np.nanmin(values) >= 0 and np.nanmax(values) <= 1
    assert _on_map(w.view.image()) > 500  # shaded, but on the colour map, not dark red
    w.display.tubes.setChecked(False)
    assert not w.scene.edges_as_tubes and not w.actions_by_name["tubes"].isChecked()
    assert w.view._actors["curve-edges"].mapper.dataset.n_lines > 0


def test_skeletal_points_stay_visible_under_a_curve(window, files):
    window.session.load_files([files["cloud"], files["skeletal"]])
    window.scene.set_visible("cloud", False)
    alone = _count(window.view.image(), SKELETAL_COLOR)
    window.session.load_as("curve", files["curve"])
    under = _count(window.view.image(), SKELETAL_COLOR)
    assert under > 0.5 * alone, (under, alone)


def test_the_empty_window_shows_a_hint_until_something_is_loaded(window, files):
    assert window.view.hint_visible
    img = window.view.image()
    assert (_rgb(img).max(axis=-1) < 160).sum() > 200  # the hint's grey text
    window.session.load_as("cloud", files["cloud"])
    assert not window.view.hint_visible
    window.session.close_all()
    assert window.view.hint_visible


def test_figure_options_spheres_eye_dome_lighting_and_axes(evaluated):
    w = evaluated
    plain = w.view.image()
    w.actions_by_name["style_spheres"].trigger()
    assert w.display.style["spheres"].isChecked()
    assert w.view._actors["skeletal"].prop.render_points_as_spheres and w.view._actors["skeletal"].prop.lighting
    spheres = w.view.image()
    assert not np.array_equal(plain, spheres)
    w.display.style["eye_dome"].setChecked(True)
    assert w.actions_by_name["style_eye_dome"].isChecked()
    edl = w.view.image()
    assert not np.array_equal(spheres, edl)
    assert w.view.plotter.renderer.axes_widget.GetEnabled()
    w.display.style["axes"].setChecked(False)
    assert not w.view.plotter.renderer.axes_widget.GetEnabled()
    # a new actor (a reload) is built in the chosen style
    w.session.load_as("skeletal", w.scene.skeletal.path)
    assert w.view._actors["skeletal"].prop.render_points_as_spheres


def test_eye_dome_lighting_leaves_the_colour_bar_and_the_legends_crisp(window, evaluation):
    """Eye-dome lighting shades the 3-D scene only: the colour bar, its labels and title, and the
    support legend are the same pixels with it as without it (on screen and in a picture at scale 2),
    while the points are shaded."""
    from skelcore.curve import CurveSkeleton

    ev = evaluation
    w = window
    w.session.show_arrays(ev.cloud, ev.skeletal.points, CurveSkeleton.from_raw(ev.curve.curve.vertices,
                                                                              ev.curve.curve.edges), ev)
    w.scene.set_metric("centeredness")
    w.pick_element(w.scene.element_info("skeletal", "points", 5))  # the support's legend, top left
    assert w.supports.overlay.names
    plain, plain2 = w.view.image(), w.view.image(scale=2)
    w.scene.set_style("eye_dome", True)
    edl, edl2 = w.view.image(), w.view.image(scale=2)
    for a, b in ((plain, edl), (plain2, edl2)):
        h, wd = a.shape[:2]
        bar = (slice(int(0.15 * h), int(0.85 * h)), slice(int(0.87 * wd), wd))  # the bar, its labels, its title
        legend = (slice(0, int(0.12 * h)), slice(0, int(0.3 * wd)))
        assert np.array_equal(a[bar], b[bar]) and np.array_equal(a[legend], b[legend])
        assert not np.array_equal(a, b)  # the scene itself is shaded
    w.scene.set_style("eye_dome", False)
    assert np.array_equal(w.view.image(), plain)


def test_a_saved_camera_restores_the_view_and_the_scripted_mode_reads_it(evaluated, files, tmp_path, capsys,
                                                                         monkeypatch):
    w = evaluated
    w.view.standard_view("xz")
    path = w.save_camera(str(tmp_path / "cam.json"))
    saved = json.loads(open(path).read())
    w.view.standard_view("xy")
    w.load_camera(path)
    assert np.allclose(w.view.camera_state()["position"], saved["position"])
    with pytest.raises(skelcore.SkelInputError, match="not a camera file"):
        (tmp_path / "bad.json").write_text("{}")
        w.load_camera(str(tmp_path / "bad.json"))

    from skelscope.__main__ import main

    QtCore.QSettings.setPath(QtCore.QSettings.Format.NativeFormat, QtCore.QSettings.Scope.UserScope, str(tmp_path))
    import sys

    monkeypatch.setattr(sys, "excepthook", sys.excepthook)
    out_a, out_b = tmp_path / "a.png", tmp_path / "b.png"
    for out in (out_a, out_b):
        code = main([files["cloud"], "--skeletal", files["skeletal"], "--camera", path, "--screenshot", str(out),
                     "--no-colour-bar", "--quit"])
        assert code == 0, capsys.readouterr().err
    fitted = tmp_path / "fitted.png"
    assert main([files["cloud"], "--skeletal", files["skeletal"], "--screenshot", str(fitted), "--quit"]) == 0
    from matplotlib.image import imread

    a, b, c = imread(out_a), imread(out_b), imread(fitted)
    assert np.array_equal(a, b) and not np.array_equal(a, c)  # the saved view, every time
    assert main([files["cloud"], "--camera", str(tmp_path / "bad.json"), "--quit"]) == 2
    assert "bad.json: not a camera file" in capsys.readouterr().err


def test_a_level_of_detail_twin_replaces_a_big_layer_while_the_camera_moves(window, qtbot, monkeypatch):
    import skelscope.view.scene_view as scene_view

    monkeypatch.setattr(scene_view, "LOD_POINTS", 2000)
    cloud = shapes.sphere_surface(10000, seed=1)
    window.scene.set_cloud(cloud)
    view = window.view
    full, twin = view._actors["cloud"], view._actors["cloud-lod"]
    assert twin.mapper.dataset.n_points == 2000 and full.GetVisibility() and not twin.GetVisibility()
    centre = view.widget.rect().center()
    qtbot.mousePress(view.widget, QtCore.Qt.MouseButton.LeftButton, pos=centre)
    assert view.moving and twin.GetVisibility() and not full.GetVisibility()
    qtbot.mouseRelease(view.widget, QtCore.Qt.MouseButton.LeftButton, pos=centre + QtCore.QPoint(40, 0))
    assert not view.moving and full.GetVisibility() and not twin.GetVisibility()
    window.scene.set_visible("cloud", False)
    qtbot.mousePress(view.widget, QtCore.Qt.MouseButton.LeftButton, pos=centre)
    assert not twin.GetVisibility() and not full.GetVisibility()  # a hidden layer stays hidden
    qtbot.mouseRelease(view.widget, QtCore.Qt.MouseButton.LeftButton, pos=centre)


def test_the_twins_draw_fewer_points_when_moving_frames_run_over_budget(window, qtbot, monkeypatch):
    """A frame drawn while moving that takes longer than the budget halves the twins' points as often
    as its excess asks (vertex lists only: the twin's uploaded points stay); quick frames step back up."""
    import skelscope.view.scene_view as scene_view
    from skelscope.view.lod import FRAME_BUDGET_S, DetailLevel

    level = DetailLevel(ladder=(8000, 4000, 2000, 1000))
    assert level.frame_took(FRAME_BUDGET_S * 3.5) and level.points == 2000  # 3.5x over: two halvings
    assert not level.frame_took(FRAME_BUDGET_S / 2) and level.points == 2000
    assert level.frame_took(FRAME_BUDGET_S / 5) and level.points == 4000
    level.fit(FRAME_BUDGET_S * 10, 80_000, 2)  # 2 twins of 8000 would take 2 budgets; 2 of 4000 one
    assert level.points == 4000
    level.fit(FRAME_BUDGET_S * 1000, 80_000, 2)
    assert level.points == 1000  # the smallest when none fits
    monkeypatch.setattr(scene_view, "LOD_POINTS", 2000)
    window.scene.set_cloud(shapes.sphere_surface(10000, seed=1))
    view = window.view
    view.detail = DetailLevel(ladder=(2000, 1000, 500))
    view._detail_fitted = True  # the step rule alone (a full frame's fit is checked above)
    twin = view._meshes["cloud-lod"]
    assert twin.n_points == 2000 and twin.n_verts == 2000
    view._set_moving(True)
    view.plotter.frame_seconds = FRAME_BUDGET_S * 1.5
    view._before_frame()  # the first moving frame: may upload the twin, not counted
    assert twin.n_verts == 2000
    view._before_frame()
    assert twin.n_verts == 1000 and twin.n_points == 2000
    view._set_moving(False)
    assert view.detail.points == 1000  # the next drag starts there


def test_a_pick_among_a_million_skeletal_points_finds_the_clicked_one(window, qtbot):
    cloud = shapes.sphere_surface(1_000_000, seed=0)
    skeletal = cloud * 0.5
    window.scene.set_cloud(cloud)
    window.scene.set_skeletal(skeletal)
    window.scene.set_visible("cloud", False)
    window.view.image()
    target = int(np.argmax(skeletal[:, 2]))  # the top, facing the camera in the default view? any visible one:
    x, y = window.view.world_to_display(skeletal[target])
    info = window.view.pick_display(x, y)
    assert info is not None and info["element"] == "skeletal point"
    assert np.linalg.norm(np.asarray(info["xyz"]) - skeletal[target]) < 0.02


# ---- pictures at any scale, camera framing, backgrounds, barcode labels ------------------------

def _dark_row_runs(img, x0: int) -> list[tuple[int, int, int]]:
    """Runs of rows holding dark (text) pixels in columns x0.., as (first row, last row, rightmost
    dark column): the colour bar's title and tick labels, top to bottom."""
    dark = _rgb(img)[:, x0:].max(axis=-1) < 190  # anti-aliased glyphs: their thin strokes are grey
    rows = np.flatnonzero(dark.any(axis=1))
    runs, start = [], None
    for i, r in enumerate(rows):
        if start is None:
            start = r
        if i + 1 == len(rows) or rows[i + 1] != r + 1:
            cols = np.flatnonzero(dark[start:r + 1].any(axis=0))
            runs.append((int(start), int(r), x0 + int(cols.max())))
            start = None
    return runs


@pytest.mark.parametrize("docks", ["shown", "hidden"])  # a narrow view (title right-aligned) and a wide one
def test_the_colour_bar_title_clears_the_top_label_and_the_view_edge_at_every_scale(evaluated, docks):
    from skelscope.view.colorbar import BAR_WIDTH, BAR_X

    w = evaluated
    if docks == "hidden":
        for dock in w.docks.values():
            dock.hide()
    w.scene.set_metric("centeredness")
    for layer in ("cloud", "skeletal", "curve"):
        w.scene.set_visible(layer, False)
    w.scene.set_visible("skeletal", True)  # the bar describes the skeletal points
    w.scene.set_style("axes", False)
    w.view.image()  # one frame at the view's final size
    for scale in (1, 2, 3):
        img = w.view.image(scale=scale)
        width = img.shape[1]
        runs = _dark_row_runs(img, int((BAR_X + BAR_WIDTH) * width) + 2 * scale)
        assert len(runs) >= 6, (scale, width, runs)  # title, 1.00 ... 0.00 (tick marks may stand apart)
        title, top_label = runs[0], runs[1]
        assert title[1] < top_label[0] - scale, (scale, runs)  # at least a row's gap per scale unit
        # a title sitting on "1.00" would merge their rows into one run twice a label's height
        assert title[1] - title[0] <= 1.6 * (top_label[1] - top_label[0] + 1), (scale, runs)
        assert title[2] < width - 1, (scale, title, width)  # not cut at the right edge
        # the title's text height grows with the picture (not shrinks, not blows up)
        if scale == 1:
            height1 = title[1] - title[0] + 1
        else:
            assert 0.7 * scale * height1 <= title[1] - title[0] + 1 <= 1.4 * scale * height1, (scale, title, height1)


def test_the_orientation_axes_letters_grow_with_the_picture_not_three_times(evaluated):
    w = evaluated
    for layer in ("cloud", "skeletal", "curve"):
        w.scene.set_visible(layer, False)
    w.scene.set_style("axes", True)
    w.view.image()

    def letters_height(img) -> int:
        h, wd = img.shape[:2]
        corner = _rgb(img)[h // 2:, : wd // 2]
        rows = np.flatnonzero((corner.max(axis=-1) < 80).any(axis=1))  # black letters (the arrows are coloured)
        assert len(rows), "no axes letters"
        return int(rows.max() - rows.min() + 1)

    one = letters_height(w.view.image(scale=1, colour_bar=False))
    for scale in (2, 3):
        ratio = letters_height(w.view.image(scale=scale, colour_bar=False)) / one
        assert 0.75 * scale <= ratio <= 1.25 * scale, (scale, ratio)


def test_black_and_transparent_backgrounds_turn_the_text_white_and_leave_the_view_white(evaluated, tmp_path):
    from skelscope.view.colorbar import BAR_WIDTH, BAR_X

    w = evaluated
    black = w.view.image(scale=2, background="black")
    assert black.shape[2] == 3 and tuple(_rgb(black)[0, 0]) == (0, 0, 0)
    labels = _rgb(black)[:, int((BAR_X + BAR_WIDTH) * black.shape[1]) + 4:]
    assert (labels.min(axis=-1) > 200).sum() > 100  # white label text
    assert (labels.max(axis=-1) < 60).sum() > 0.95 * labels[..., 0].size  # on black
    clear = w.view.image(background="transparent")
    assert clear.shape[2] == 4 and clear[0, 0, 3] == 0 and clear[..., 3].max() == 255
    after = w.view.image()
    assert tuple(_rgb(after)[0, 0]) == (255, 255, 255)  # the view itself is back to white
    path = w.save_screenshot(str(tmp_path / "b.png"), background="black")
    from matplotlib.image import imread

    assert imread(path)[0, 0, :3].tolist() == [0, 0, 0]
    with pytest.raises(ValueError, match="background must be one of"):
        w.view.image(background="grey")


def _grey_box(img) -> tuple[int, int, int, int]:
    px = _rgb(img)
    spread = px.max(axis=-1) - px.min(axis=-1)
    ys, xs = np.nonzero((spread <= 6) & (px[..., 0] > 90) & (px[..., 0] < 235))
    return int(xs.min()), int(xs.max()), int(ys.min()), int(ys.max())


def test_a_saved_camera_reproduces_the_framing_through_its_view_size_and_size_sets_it(window, files, tmp_path,
                                                                                     capsys, monkeypatch):
    """The scripted window has another shape than the one the camera was saved in: the camera file
    carries the view's size and the scripted mode takes it (or ``--size W H``)."""
    import sys

    from matplotlib.image import imread

    from skelscope.__main__ import main

    w = window
    w.session.load_files([files["cloud"], files["skeletal"]])
    w.view.standard_view("xz")
    w.view.reset_camera()
    seen = w.view.image(colour_bar=False)
    cam = w.save_camera(str(tmp_path / "cam.json"))
    saved = json.loads(open(cam).read())
    assert saved["view_size"] == [seen.shape[1], seen.shape[0]]
    QtCore.QSettings.setPath(QtCore.QSettings.Format.NativeFormat, QtCore.QSettings.Scope.UserScope, str(tmp_path))
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)
    out = tmp_path / "framed.png"
    assert main([files["cloud"], "--skeletal", files["skeletal"], "--camera", cam, "--screenshot", str(out),
                 "--no-colour-bar", "--quit"]) == 0, capsys.readouterr().err
    got = (imread(str(out))[..., :3] * 255).round().astype(np.uint8)
    assert got.shape == seen.shape[:2] + (3,)
    # the cloud lies where it lay in the window, to a pixel or two
    assert np.abs(np.subtract(_grey_box(got), _grey_box(seen))).max() <= 2, (_grey_box(got), _grey_box(seen))
    # --size wins over the camera's; a size the screen cannot hold is still a view of that size (no WM)
    assert main([files["cloud"], "--camera", cam, "--size", "420", "300", "--screenshot", str(out), "--quit"]) == 0
    assert imread(str(out)).shape[:2] == (300, 420)
    assert main([files["cloud"], "--size", "0", "300", "--quit"]) == 2
    assert "--size W H must be two integers" in capsys.readouterr().err
    assert main([files["cloud"], "--transparent", "--background", "black", "--quit"]) == 2
    assert "--transparent contradicts --background black" in capsys.readouterr().err
    (tmp_path / "badsize.json").write_text(json.dumps({**saved, "view_size": [10, -3]}))
    assert main([files["cloud"], "--camera", str(tmp_path / "badsize.json"), "--quit"]) == 2
    assert "badsize.json: not a camera file (view_size" in capsys.readouterr().err


def test_the_scripted_background_option(files, tmp_path, capsys, monkeypatch):
    import sys

    from matplotlib.image import imread

    from skelscope.__main__ import main

    QtCore.QSettings.setPath(QtCore.QSettings.Format.NativeFormat, QtCore.QSettings.Scope.UserScope, str(tmp_path))
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)
    for background, corner in (("black", [0, 0, 0]), ("white", [1, 1, 1])):
        out = tmp_path / f"{background}.png"
        assert main([files["cloud"], "--skeletal", files["skeletal"], "--background", background,
                     "--screenshot", str(out), "--quit"]) == 0, capsys.readouterr().err
        assert imread(str(out))[0, 0, :3].tolist() == corner
    out = tmp_path / "clear.png"
    assert main([files["cloud"], "--background", "transparent", "--screenshot", str(out), "--quit"]) == 0
    assert imread(str(out))[0, 0, 3] == 0


@pytest.mark.parametrize("width", [230, 300, 380, 520])
def test_the_barcode_axis_labels_stay_inside_the_panel_in_their_shortest_form(qtbot, evaluation, width):
    from skelscope.panels.barcode import BarcodePanel, tick_text

    panel = BarcodePanel()
    qtbot.addWidget(panel)
    panel.resize(width, 380)
    panel.show()
    qtbot.waitExposed(panel)
    panel.show_topology(evaluation.topology)
    panel.draw_now()
    qtbot.waitUntil(lambda: not panel.draw_pending, timeout=30000)
    fig = panel.figure
    renderer = panel.canvas.get_renderer()
    ax = panel._axes()[1]
    lo, hi = ax.get_xlim()
    shown = [t for t, v in zip(ax.get_xticklabels(), ax.get_xticks()) if lo - 1e-12 <= v <= hi + 1e-12]
    assert len(shown) >= 2
    for label in shown:
        box = label.get_window_extent(renderer)
        assert box.x0 >= 0 and box.x1 <= fig.bbox.width and box.y0 >= 0, (width, label.get_text(), box)
        text = label.get_text()
        assert not (("." in text) and text.endswith("0")), text  # "0.02", never "0.0200"
    for ax_ in panel._axes():  # the y labels too
        box = ax_.yaxis.label.get_window_extent(renderer)
        assert box.x0 >= 0, (width, box)
    assert tick_text(0.02) == "0.02" and tick_text(0.0025) == "0.0025" and tick_text(-0.0) == "0"
