"""The one main-window fixture of the viewer's GUI tests.

``window`` is a shown :class:`skelscope.main_window.MainWindow` with a throwaway settings file; its runner
is shut down (and its A/B windows closed) afterwards. A module or a test sets its options with
``@pytest.mark.window(...)``:

- ``auto_evaluate`` (False): evaluate as soon as the inputs are loaded;
- ``size`` (None: the window's own): ``(width, height)``;
- ``dialogs`` ("fail"): an error dialog fails the test; "record" appends its text to ``window.dialogs``;
- ``questions`` ("fail"): a question to the user fails the test; "default" takes its first option
  (Enter) and appends ``(question, options)`` to ``window.questions``.
"""

from __future__ import annotations

import pytest

OPTIONS = {"auto_evaluate": False, "size": None, "dialogs": "fail", "questions": "fail"}


def window_options(request: pytest.FixtureRequest) -> dict:
    marker = request.node.get_closest_marker("window")
    given = dict(marker.kwargs) if marker is not None else {}
    unknown = set(given) - set(OPTIONS)
    if unknown:
        raise ValueError(f"unknown window option(s) {sorted(unknown)}; known: {sorted(OPTIONS)}")
    return {**OPTIONS, **given}


@pytest.fixture
def window(request, qtbot, tmp_path, monkeypatch):
    from PySide6 import QtCore, QtWidgets

    from skelscope.main_window import MainWindow

    opts = window_options(request)
    dialogs: list[str] = []
    if opts["dialogs"] == "record":
        def critical(parent, title, text, *args, **kwargs):
            dialogs.append(text)
            return QtWidgets.QMessageBox.StandardButton.Ok

        monkeypatch.setattr(QtWidgets.QMessageBox, "critical", critical)
        monkeypatch.setattr(QtWidgets.QMessageBox, "exec", lambda self: dialogs.append(self.text()) or 0)
    elif opts["dialogs"] == "fail":
        monkeypatch.setattr(QtWidgets.QMessageBox, "critical", lambda *a, **k: pytest.fail(f"error dialog {a[2]!r}"))
        monkeypatch.setattr(QtWidgets.QMessageBox, "exec", lambda self: pytest.fail(f"error dialog {self.text()!r}"))
    else:
        raise ValueError(f"dialogs={opts['dialogs']!r}: 'record' or 'fail'")
    monkeypatch.setattr(QtWidgets.QInputDialog, "getItem", lambda *a, **k: pytest.fail(f"unexpected question {a[2]!r}"))

    w = MainWindow(settings=QtCore.QSettings(str(tmp_path / "settings.ini"), QtCore.QSettings.Format.IniFormat))
    w.session.auto_evaluate = opts["auto_evaluate"]
    w.dialogs = dialogs
    w.questions = []
    if opts["questions"] == "default":
        def ask(question, options):  # Enter on every question: its default
            w.questions.append((question, options))
            return options[0]

        w.session.ask = ask
    elif opts["questions"] != "fail":
        raise ValueError(f"questions={opts['questions']!r}: 'default' or 'fail'")
    qtbot.addWidget(w)
    if opts["size"] is not None:
        w.resize(*opts["size"])
    w.show()
    qtbot.waitExposed(w)
    yield w
    w.compare.close_views()
    w.session.runner.shutdown()


def _collector_users() -> int:
    """The windows holding the GUI thread's collector (app/gui_collector.py); 0 before any window."""
    import sys

    module = sys.modules.get("skelscope.gui_collector")
    return 0 if module is None or module._collector is None else module._collector.users


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item):
    item.collector_users_before = _collector_users()
    return (yield)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item):
    """A test that leaves a main window open (its hold on the collector kept: the automatic collection
    off for every later test) fails its teardown, named."""
    result = yield
    users, before = _collector_users(), getattr(item, "collector_users_before", 0)
    if users > before:
        raise AssertionError(f"{item.nodeid} left {users - before} main window(s) open "
                             "(app/gui_collector.py: the collector's users)")
    return result
