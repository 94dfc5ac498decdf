"""External skeletons in the window: a point set with another point count than the cloud
can be loaded as a skeletal set scored by reverse projection or through an index file; a new cloud
over a loaded skeleton asks one question; warnings name the window's menus and settings; a skeleton
in another frame is mapped into the cloud's from a menu."""

from __future__ import annotations

import numpy as np
import pytest

import skelcore
from skelcore import shapes
from skelcore.io import write_curve_ply, write_points_ply

from skelscope.loading import (
    REPLACE_CLOUD, REPLACE_CLOUD_KEEP, SKELETAL_INDEX, SKELETAL_REVERSE, SKIP,
)

pytestmark = [pytest.mark.gui, pytest.mark.window(dialogs="record")]

N_SUB = 200


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("external")
    sh = shapes.y_shape(1000, seed=7)
    rows = np.sort(np.random.default_rng(1).choice(len(sh.skeletal), N_SUB, replace=False))
    write_points_ply(d / "cloud.ply", sh.cloud)
    write_points_ply(d / "skeletal.ply", sh.skeletal)
    write_points_ply(d / "sub.ply", sh.skeletal[rows])  # another tool's subset of the contracted points
    (d / "sub_index.txt").write_text("\n".join(str(r) for r in rows) + "\n")
    (d / "bad_index.txt").write_text("\n".join(str(r) for r in rows[:-1]) + "\n")  # one row short
    write_curve_ply(d / "curve.ply", sh.curve_vertices, sh.curve_edges)
    other = shapes.cylinder(1400, radius=0.4, length=2.0, seed=2)
    write_points_ply(d / "other_cloud.ply", other.cloud)
    write_curve_ply(d / "far_curve.ply", sh.curve_vertices * 40.0 + 7.0, sh.curve_edges)
    paths = {p.stem: str(p) for p in d.iterdir()}
    return paths, sh, rows


def _answering(w, *answers):
    """The session's questions answered in turn; every question and its options recorded."""
    asked = []
    replies = list(answers)

    def ask(question, options):
        asked.append((question, options))
        choice = replies.pop(0)
        assert choice in options, (choice, options)
        return choice

    w.session.ask = ask
    return asked


def _evaluate(qtbot, w):
    with qtbot.waitSignal(w.session.evaluated, timeout=120000) as blocker:
        assert w.session.start_evaluation()
    return blocker.args[0]


def test_a_point_set_of_another_count_is_offered_as_a_reverse_projected_skeletal_set(window, qtbot, files):
    paths, sh, _ = files
    w = window
    w.session.load_files([paths["cloud"]])
    asked = _answering(w, SKELETAL_REVERSE)
    w.session.load_files([paths["sub"]])
    ((question, options),) = asked
    assert options[0] == SKIP  # the default answer never changes what is loaded
    assert SKELETAL_REVERSE in options and SKELETAL_INDEX in options
    assert f"has {N_SUB} points but the cloud has {len(sh.cloud)}" in question
    assert w.scene.skeletal is not None and w.scene.skeletal.n_points == N_SUB
    assert w.settings_panel.correspondence() == "reverse"  # the answer set the window's setting
    ev = _evaluate(qtbot, w)
    assert ev.correspondence == "reverse" and ev.topology is not None and w.dialogs == []
    n_points = len(np.unique(ev.skeletal.rows))
    cell = w.summary.cell_text("centeredness", "skeletal points")
    assert f"(n = {len(sh.cloud):,} cloud rows on {n_points:,} of {N_SUB:,} skeletal points)" in cell
    assert f"(n = {N_SUB:,})" in w.summary.cell_text("boundedness", "skeletal points")


def test_a_skeletal_set_with_an_index_file_is_scored_through_its_index(window, qtbot, files):
    paths, sh, rows = files
    w = window
    w.session.load_files([paths["cloud"]])
    _answering(w, SKELETAL_INDEX)
    titles = []
    w.session.ask_file = lambda title: titles.append(title) or paths["sub_index"]
    w.session.load_files([paths["sub"]])
    assert titles and "sub.ply" in titles[0]  # it asked for the index file of that set
    layer = w.scene.skeletal
    assert layer.n_points == N_SUB and np.array_equal(layer.index, rows) and layer.index_path == paths["sub_index"]
    assert w.settings_panel.correspondence() == "auto"
    ev = _evaluate(qtbot, w)
    assert ev.correspondence == "index" and np.array_equal(ev.skeletal.index, rows)
    assert ev.inputs["skeletal_index"] == paths["sub_index"]
    # the same numbers as the engine given the index directly (independent of the window)
    direct = skelcore.evaluate(sh.cloud, sh.skeletal[rows], skeletal_index=rows)
    np.testing.assert_array_equal(ev.skeletal.centeredness_raw, direct.skeletal.centeredness_raw)
    assert ev.topology.bottleneck == direct.topology.bottleneck


def test_an_index_file_that_does_not_fit_or_is_not_chosen_loads_nothing(window, files):
    paths, _, _ = files
    w = window
    w.session.load_files([paths["cloud"]])
    _answering(w, SKELETAL_INDEX, SKELETAL_INDEX)
    w.session.ask_file = lambda title: paths["bad_index"]
    w.session.load_files([paths["sub"]])
    assert w.scene.skeletal is None
    assert len(w.dialogs) == 1 and "bad_index.txt" in w.dialogs[0] and "rows" in w.dialogs[0]
    w.session.ask_file = lambda title: None  # the file dialog cancelled
    w.session.load_files([paths["sub"]])
    assert w.scene.skeletal is None and len(w.dialogs) == 1


def test_file_open_skeletal_index_gives_a_loaded_set_its_correspondence(window, qtbot, files):
    paths, _, rows = files
    w = window
    w.session.load_as("cloud", paths["cloud"])
    w.session.load_as("skeletal", paths["sub"])
    ev = _evaluate(qtbot, w)
    assert ev.correspondence == "none"
    text = w.summary.details_text()
    assert "File > Open skeletal index" in text and "--skeletal-index" not in text
    action = w.actions_by_name["open_index"]
    assert action.isEnabled() and action.text() in ("Open skeletal index…",)
    assert w.session.load_index(paths["sub_index"])
    assert w.scene.evaluation is None and np.array_equal(w.scene.skeletal.index, rows)
    assert _evaluate(qtbot, w).correspondence == "index"


@pytest.mark.parametrize("keep", [False, True])
def test_a_new_cloud_over_a_loaded_skeleton_asks_one_question(window, files, keep):
    paths, _, _ = files
    w = window
    w.session.load_files([paths["cloud"], paths["skeletal"], paths["curve"]])
    asked = _answering(w, REPLACE_CLOUD_KEEP if keep else REPLACE_CLOUD)
    w.session.load_files([paths["other_cloud"]])
    assert len(asked) == 1  # not a second "clear it or keep it?" after "replaces ... and clears its skeleton"
    assert REPLACE_CLOUD in asked[0][1] and REPLACE_CLOUD_KEEP in asked[0][1]
    assert w.scene.cloud.path == paths["other_cloud"]
    assert ("skeletal" in w.scene.layers and "curve" in w.scene.layers) == keep


def test_a_skeleton_in_another_frame_is_mapped_from_the_menu_the_warning_names(window, qtbot, files, tmp_path):
    paths, sh, _ = files
    w = window
    w.session.load_as("cloud", paths["cloud"])
    w.session.load_as("curve", paths["far_curve"])
    ev = _evaluate(qtbot, w)
    (frame,) = [x for x in ev.warnings if x.code == "frame"]
    text = w.summary.details_text()
    assert "Evaluate > Map skeleton into the cloud's frame…" in text and "--skeleton" not in text
    from skelscope.map_dialog import MapSkeletonDialog, suggested_mapping

    mapping = suggested_mapping(w.scene.evaluation)
    assert mapping == frame.mapping
    dialog = MapSkeletonDialog(w, mapping)
    assert dialog.mapping()[0] == pytest.approx(mapping[0], rel=1e-5)
    # the exact inverse of how the file was made: the curve lands on the cloud's own
    assert w.session.map_skeleton(1 / 40.0, (-7.0 / 40.0,) * 3)
    np.testing.assert_allclose(w.scene.curve.points, sh.curve_vertices, atol=1e-9)
    assert w.scene.curve.mapping == (pytest.approx(1 / 40.0), pytest.approx((-7.0 / 40.0,) * 3))
    ev = _evaluate(qtbot, w)
    assert not [x for x in ev.warnings if x.code == "frame"]
    # the coloured PLY of the mapped curve says in its header that, and how, it was mapped
    written = w.export_ply(str(tmp_path / "ply"))
    assert written
    for path in written:
        header = open(path, "rb").read().split(b"end_header")[0].decode("ascii")
        (line,) = [ln for ln in header.splitlines() if ln.startswith("comment mapping:")]
        assert "scale 0.025 and offset -0.175 -0.175 -0.175" in line and "cloud's frame" in line


@pytest.mark.parametrize("how", ["drop", "file_open"])
def test_a_reverse_projection_choice_does_not_stick_to_the_next_skeletal_set(window, qtbot, files, how):
    """Reverse projection chosen for a set of another size; a pointwise set loaded next is scored
    pointwise, as from a fresh launch (and as A in the A/B view); the other set, reloaded, asks again."""
    paths, sh, rows = files
    w = window
    w.session.load_files([paths["cloud"]])
    _answering(w, SKELETAL_REVERSE)
    w.session.load_files([paths["sub"]])
    assert w.settings_panel.correspondence() == "reverse"
    assert _evaluate(qtbot, w).correspondence == "reverse"
    if how == "drop":
        w.session.load_files([paths["skeletal"]])
    else:
        w.session.load_as("skeletal", paths["skeletal"])
    assert w.settings_panel.correspondence() == "auto"
    ev = _evaluate(qtbot, w)
    fresh = skelcore.evaluate(sh.cloud, sh.skeletal)
    assert ev.correspondence == fresh.correspondence == "pointwise"
    assert ev.summary()["centeredness"]["skeletal"] == pytest.approx(fresh.summary()["centeredness"]["skeletal"])
    assert w.summary.cell_text("centeredness", "skeletal points").startswith(
        f"{fresh.summary()['centeredness']['skeletal']:.3f}")
    with qtbot.waitSignal(w.session.runner.succeeded, timeout=120000):
        assert w.compare.compare_arrays(sh.skeletal[::-1].copy(), None, "reversed rows")
    view = w.compare.views[-1]
    assert view.ev_a.correspondence == view.ev_b.correspondence == "pointwise"
    # the set of another size decides again when it comes back: scored with no correspondence by default
    w.session.load_as("skeletal", paths["sub"])
    assert w.settings_panel.correspondence() == "auto"
    assert w.dialogs == []


def test_the_correspondence_chosen_for_a_set_stays_when_it_is_mapped(window, files):
    paths, _, _ = files
    w = window
    w.session.load_files([paths["cloud"]])
    _answering(w, SKELETAL_REVERSE)
    w.session.load_files([paths["sub"]])
    assert w.session.map_skeleton(2.0, (0.0, 0.0, 0.0))
    assert w.settings_panel.correspondence() == "reverse"


def test_reverse_projection_chosen_in_the_settings_stays_with_its_set(window, qtbot, files):
    paths, sh, _ = files
    w = window
    w.session.load_as("cloud", paths["cloud"])
    w.session.load_as("skeletal", paths["sub"])
    w.settings_panel.set_correspondence("reverse")  # the no_correspondence warning's remedy
    assert _evaluate(qtbot, w).correspondence == "reverse"
    w.session.load_as("skeletal", paths["skeletal"])
    assert w.settings_panel.correspondence() == "auto"
    assert _evaluate(qtbot, w).correspondence == "pointwise"
