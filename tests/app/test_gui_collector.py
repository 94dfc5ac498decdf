"""Python's cyclic garbage collection runs on the window's thread while a window is open
(app/gui_collector.py; docs/guide/viewer.md, "Opening data", Threads)."""

from __future__ import annotations

import gc
import threading

from skelscope.gui_collector import GuiCollector


class _Node:
    """A member of a reference cycle that records the thread that frees it."""

    freed_in: list[int] = []

    def __del__(self) -> None:
        _Node.freed_in.append(threading.get_ident())


def test_a_cycle_dropped_in_a_worker_thread_is_freed_on_the_window_s_thread(window, qtbot):
    _Node.freed_in = []

    def work() -> None:
        node = _Node()
        node.cycle = [node]
        del node
        for _ in range(40):  # far past generation 0's threshold: the interpreter would collect here
            junk = [[] for _ in range(5000)]
        del junk

    worker = threading.Thread(target=work)
    worker.start()
    worker.join()
    assert not gc.isenabled() and not _Node.freed_in
    qtbot.waitUntil(lambda: bool(_Node.freed_in), timeout=5000)
    assert _Node.freed_in == [threading.get_ident()]


def test_the_last_release_gives_the_collection_back_as_it_was(qtbot):
    was = gc.isenabled()
    try:
        for before in (True, False):
            (gc.enable if before else gc.disable)()
            c = GuiCollector()
            c.acquire()
            c.acquire()
            assert not gc.isenabled()
            c.release()
            assert not gc.isenabled()
            c.release()
            assert gc.isenabled() == before
            c.release()  # one too many: nothing
            assert gc.isenabled() == before
    finally:
        (gc.enable if was else gc.disable)()


def test_closing_the_window_gives_the_collection_back(qtbot, tmp_path):
    from PySide6 import QtCore

    from skelscope.gui_collector import gui_collector
    from skelscope.main_window import MainWindow

    before = gui_collector().users  # another test's window may still be open
    w = MainWindow(settings=QtCore.QSettings(str(tmp_path / "settings.ini"), QtCore.QSettings.Format.IniFormat))
    assert gui_collector().users == before + 1 and not gc.isenabled()
    w.close()
    assert gui_collector().users == before
    assert gc.isenabled() == (before == 0)
    w.deleteLater()
