"""``skelscope CLOUD --curve C --edits LOG.json --screenshot OUT.png --quit``: the edit log replayed on
the curve (skelcore.edit.replay) before it is scored, for figures: the picture and the printed scores
are those of the edited curve (the same picture as the edited curve loaded from its own file); a log
made for another skeleton, or --edits without --curve, is one line on stderr and exit 2.

The shape: the cylinder's axis with a two-edge twig (tests/app/test_app_editing.py)."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from PySide6 import QtCore

import skelcore.edit as edit
from skelcore.io import load_curve
from skelcore.io.writers import write_curve
from skelscope.__main__ import main
from test_app_editing import twig_files

pytestmark = pytest.mark.gui


@pytest.fixture
def no_user_settings(qapp, tmp_path, monkeypatch):
    QtCore.QSettings.setPath(QtCore.QSettings.Format.NativeFormat, QtCore.QSettings.Scope.UserScope, str(tmp_path))
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)


def _picture(path):
    from matplotlib.image import imread

    return (imread(path)[..., :3] * 255).round().astype(int)


def test_a_replayed_edit_log_is_pictured_and_scored_as_the_edited_curve(tmp_path, capsys, no_user_settings):
    cloud, curve_path, tip = twig_files(tmp_path)
    curve = load_curve(curve_path)
    c1, ch1 = edit.delete_vertex(curve, tip)  # the twig's two vertices
    c2, ch2 = edit.delete_vertex(c1, tip - 1)
    log = str(tmp_path / "twig.edits.json")
    edit.write_log(log, edit.new_log(curve, [ch1, ch2]))
    edited = str(tmp_path / "cyl_edited.ply")
    write_curve(edited, c2)
    common = ["--metric", "centeredness", "--size", "400", "300", "--quit"]

    out = str(tmp_path / "replayed.png")
    assert main([cloud, "--curve", curve_path, "--edits", log, "--screenshot", out, *common]) == 0
    replayed = capsys.readouterr().out
    assert "replayed 2 edit(s) of twig.edits.json on cyl_curve.ply" in replayed
    assert main([cloud, "--curve", edited, "--screenshot", str(tmp_path / "file.png"), *common]) == 0
    from_file = capsys.readouterr().out
    assert main([cloud, "--curve", curve_path, "--screenshot", str(tmp_path / "loaded.png"), *common]) == 0
    loaded = capsys.readouterr().out
    scores = lambda text: [line for line in text.splitlines() if "wrote" not in line and "replayed" not in line]
    assert scores(replayed) == scores(from_file) != scores(loaded)
    assert np.array_equal(_picture(out), _picture(tmp_path / "file.png"))
    assert not np.array_equal(_picture(out), _picture(tmp_path / "loaded.png"))


@pytest.mark.parametrize("case, message", [
    ("another", "was made for another skeleton"),
    ("no_curve", "--edits LOG.json goes with --curve C"),
    ("not_a_log", "not an edit log"),
])
def test_a_bad_edit_log_is_one_line_and_exit_2(case, message, tmp_path, capsys, no_user_settings):
    cloud, curve_path, tip = twig_files(tmp_path)
    curve = load_curve(curve_path)
    other, _ch = edit.delete_vertex(curve, tip)
    log = str(tmp_path / "log.edits.json")
    if case == "not_a_log":
        open(log, "w").write('{"operations": []}')
    else:
        edit.write_log(log, edit.new_log(other, [edit.delete_vertex(other, tip - 1)[1]]))  # made for another curve
    argv = [cloud, "--edits", log, "--quit"] if case == "no_curve" else [cloud, "--curve", curve_path, "--edits", log,
                                                                        "--quit"]
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1 and "Traceback" not in err
    if case != "no_curve":
        assert log in err
