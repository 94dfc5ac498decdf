"""The viewer's trust checks: a skeletal set of another size loads without an error dialog and is
scored with the correspondence chosen in the settings panel; warnings, the correspondence used,
coverage (and the cloud coloured by its gap) and the reference comparison show in the summary."""

from __future__ import annotations

import numpy as np
import pytest

import skelcore
from skelcore import shapes
from skelcore.io import write_curve_ply, write_points_ply

pytestmark = [pytest.mark.gui, pytest.mark.window(auto_evaluate=True, dialogs="record")]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("trust")
    sh = shapes.y_shape(1200, seed=4)
    write_points_ply(d / "cloud.ply", sh.cloud)
    sub = np.random.default_rng(0).choice(len(sh.skeletal), 150, replace=False)
    write_points_ply(d / "sub.ply", sh.skeletal[sub])
    write_curve_ply(d / "far.ply", sh.curve_vertices * 30.0, sh.curve_edges)
    return {"cloud": str(d / "cloud.ply"), "sub": str(d / "sub.ply"), "far": str(d / "far.ply")}


def _evaluate(qtbot, w):
    with qtbot.waitSignal(w.session.evaluated, timeout=120000) as blocker:
        assert w.session.start_evaluation()
    return blocker.args[0]


def test_skeletal_set_of_another_size_scores_by_the_chosen_correspondence(qtbot, window, files):
    w = window
    w.session.auto_evaluate = False
    assert w.session.load_as("cloud", files["cloud"]) and w.session.load_as("skeletal", files["sub"])
    ev = _evaluate(qtbot, w)
    assert w.dialogs == [] and ev.correspondence == "none"
    assert w.summary.cell_text("d_B / d_Wp", "skeletal points") == "—"
    text = w.summary.details_text()
    assert "correspondence: none" in text and "warning [no_correspondence]" in text
    # in the window's terms: which setting or menu, never a command-line flag
    assert "Settings > correspondence > reverse projection" in text and "File > Open skeletal index" in text
    assert "--" not in text

    w.settings_panel.set_correspondence("reverse")
    ev = _evaluate(qtbot, w)
    assert w.dialogs == [] and ev.correspondence == "reverse" and ev.topology is not None
    assert "correspondence: reverse" in w.summary.details_text()
    # counted per cloud row; the cell says how many cloud rows and how many skeletal points
    n_points = len(np.unique(ev.skeletal.rows))
    assert f"(n = 1,200 cloud rows on {n_points} of 150 skeletal points)" in w.summary.cell_text("centeredness",
                                                                                                "skeletal points")
    assert "(n = 150)" in w.summary.cell_text("boundedness", "skeletal points")
    cov = w.summary.cell_text("coverage*", "skeletal points")
    assert cov.startswith(f"{ev.coverage_skeletal.fraction:.3f}")


def test_cloud_coloured_by_its_coverage_gap(qtbot, window, files):
    w = window
    w.session.auto_evaluate = False
    w.session.load_as("cloud", files["cloud"])
    w.session.load_as("skeletal", files["sub"])
    ev = _evaluate(qtbot, w)
    box = w.summary.cloud_by_gap
    assert box.isEnabled()
    with qtbot.waitSignal(w.summary.cloud_colouring) as blocker:
        box.setChecked(True)
    values = blocker.args[0]
    assert np.allclose(values, ev.coverage_skeletal.gap / ev.coverage_skeletal.gap.max())
    mapper = w.view._actors["cloud"].mapper
    assert mapper.scalar_visibility
    # undefined gaps are drawn magenta, by the same rule as every invalid value
    values = values.copy()
    values[:5] = np.nan
    w.view.set_cloud_values(values)
    assert w.view._actors["cloud-nan"].GetVisibility()
    box.setChecked(False)
    assert not w.view._actors["cloud"].mapper.scalar_visibility


def test_warnings_and_reference_in_the_summary(qtbot, window, files):
    from skelscope.panels.summary import detail_lines

    w = window
    cloud = skelcore.load_cloud(files["cloud"])
    far = skelcore.load_curve(files["far"])
    sh = shapes.y_shape(1200, seed=4)
    ev = skelcore.evaluate(cloud, curve=far, reference_curve=(sh.curve_vertices, sh.curve_edges))
    w.summary.show_summary(ev.summary(), ev)
    text = w.summary.details_text()
    assert "warning [frame]" in text and "--skeleton-scale" not in text
    (frame,) = [x for x in ev.warnings if x.code == "frame"]
    s, off = frame.mapping
    assert f"Evaluate > Map skeleton into the cloud's frame… (suggested: scale {s:.6g}" in text
    assert "reference curve: chamfer" in text and "junctions 1/1" in text
    assert any(line.startswith("* coverage is SkelScope's own") for line in detail_lines(ev.summary(), ev))
    assert w.summary.cell_text("coverage*", "curve skeleton") != "—"
