"""File > Save session / Open session, ``skelscope --session F``, and File > Recent.

A feature controller on :class:`skelscope.window_api.WindowApi`. Saving captures the inputs, the settings
and thresholds, the correspondence mode, metric, colour range, display options, camera (with the
view's size) and the picked element into one JSON file (:mod:`skelscope.session_file`). Opening reads and
checks the whole file first (a bad file is a one-line dialog and nothing changes), finds each input
beside the session or at its saved place, loads what it can, restores the rest, and says in ONE
dialog which files are missing or changed (and anything else it could not restore).

File > Recent lists sets and sessions, not single files: a cloud loaded with its skeleton is one
entry (a file added to the loaded set updates the entry), a session is one entry; choosing an entry
loads it whole.
"""

from __future__ import annotations

import json
import os
from typing import TYPE_CHECKING, Any

from PySide6 import QtCore, QtWidgets

from skelcore.errors import SkelInputError
from skelcore.params import Params

from .session_file import ROLES, SessionState, fingerprint, locate, read_session, write_session
from .window_api import ActionSpec

if TYPE_CHECKING:
    from .window_api import WindowApi

__all__ = ["SavedSessions", "MAX_RECENT", "RECENT_KEY", "recent_label"]

MAX_RECENT = 10
RECENT_KEY = "recent_sets"
SESSION_FILTER = "SkelScope session (*.json);;All files (*)"
_TITLES = {"cloud": "cloud", "skeletal": "skeletal point set", "curve": "curve skeleton"}


def recent_label(entry: dict[str, Any]) -> str:
    """The menu text of a recent entry: a session's file name, or the set's file names joined by +."""
    if entry.get("session"):
        return f"{os.path.basename(entry['session'])} (session)"
    return " + ".join(os.path.basename(entry["files"][role]) for role in ROLES if role in entry["files"])


class SavedSessions(QtCore.QObject):
    """The session actions, the Recent menu, and restoring a session into the window."""

    def __init__(self, window: WindowApi) -> None:
        super().__init__(window.widget)
        self.window = window
        self._restoring = False
        self._pending_pick: tuple[dict[str, Any], tuple[Any, ...]] | None = None
        self.menu = window.submenu("file.recent")
        has_layers = lambda: bool(window.scene.layers)  # noqa: E731
        window.add_action(ActionSpec("open_session", "Open session…", "file.session", self.open_dialog))
        window.add_action(ActionSpec("save_session", "Save session…", "file.session", self.save_dialog,
                                     enabled=has_layers))
        # a set is recorded once the files loaded together are all in (a session records itself)
        window.session.loaded.connect(
            lambda _role, _path: None if self._restoring else QtCore.QTimer.singleShot(0, self, self._record_set))
        window.session.evaluated.connect(self._evaluated)
        window.scene.subscribe(self._on_scene)
        self.fill_menu()

    # ---- saving ---------------------------------------------------------------------------
    def capture(self, path: str) -> SessionState:
        """The window's state as a session to be written at ``path`` (paths made relative to it)."""
        w = self.window
        scene = w.scene
        base = os.path.dirname(os.path.abspath(path))
        in_memory = [_TITLES[r] for r, layer in scene.layers.items() if not layer.path]
        if in_memory:
            raise ValueError(f"the {' and '.join(in_memory)} exist only in memory (no file): a session "
                             "records files; export them first")
        state = SessionState()
        state.files = {role: fingerprint(layer.path, base) for role, layer in scene.layers.items()}
        state.params = w.session.params().to_dict()
        state.correspondence = w.session.correspondence_provider()
        state.scan_options = dict(w.session.scan_options_provider())
        state.metric = scene.metric
        state.clim = scene.clim
        state.edges_as_tubes = scene.edges_as_tubes
        state.style = dict(scene.style)
        state.layers = {role: {"visible": layer.visible, "point_size": layer.point_size, "opacity": layer.opacity}
                        for role, layer in scene.layers.items()}
        sk = scene.skeletal
        if sk is not None and sk.index is not None and sk.index_path:
            state.skeletal_index = fingerprint(sk.index_path, base)
        state.mappings = {role: (float(layer.mapping[0]), tuple(float(v) for v in layer.mapping[1]))
                          for role, layer in scene.layers.items() if role != "cloud" and layer.mapping is not None}
        state.viewpoints = [tuple(float(v) for v in p) for p in w.session.viewpoints]
        state.edits = w.curve_edits() if scene.curve is not None and scene.curve.edited else None
        defects = getattr(w, "defects", None)
        state.defect_marks = dict(defects.marks) if defects is not None else {}
        state.camera = w.view.camera_state()
        picked = w.picked_element()
        if picked is not None:
            state.picked = {"layer": picked["layer"], "location": picked["location"], "index": int(picked["index"])}
        return state

    def save(self, path: str) -> str:
        """Write the session file (atomically, never over an input) and list it under Recent."""
        out = write_session(path, self.capture(path), self.window.input_files())
        self._push({"session": os.path.abspath(out)})
        return out

    def save_dialog(self) -> None:
        w = self.window
        stem = _stem(w.scene)
        path, _ = QtWidgets.QFileDialog.getSaveFileName(
            w.widget, "Save session", os.path.join(w.last_dir(), f"{stem}_session.json"), SESSION_FILTER)
        if not path:
            return
        try:
            out = self.save(path)
        except (ValueError, OSError) as exc:
            w.show_error("Save session failed", str(exc))
            return
        w.show_message(f"Session: wrote {os.path.basename(out)}")

    # ---- opening --------------------------------------------------------------------------
    def sessions_dir(self) -> str:
        """Where Open session looks first: the folder of the newest session saved or opened (sessions
        are kept apart from the data they name), else the last data folder."""
        folders = [os.path.dirname(e["session"]) for e in self.recent() if e.get("session")]
        return next((f for f in folders if os.path.isdir(f)), self.window.last_dir())

    def open_dialog(self) -> None:
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self.window.widget, "Open session", self.sessions_dir(),
                                                        SESSION_FILTER)
        if path:
            self.open(path)

    def open(self, path: str) -> list[str]:
        """Open a session file: a bad file is one line (dialog; nothing changes); otherwise restore it
        and show what could not be restored in one dialog. Returns those lines."""
        try:
            state = read_session(path)
        except SkelInputError as exc:
            self.window.show_error("Open session failed", str(exc))
            return [str(exc)]
        problems = self.restore(state, path)
        self.report(problems, os.path.basename(path))
        return problems

    def restore(self, state: SessionState, path: str) -> list[str]:
        """Load what the session names and restore its settings, display, camera and picked element.
        Returns one line per thing not restored as saved (missing or changed files first)."""
        w, scene = self.window, self.window.scene
        problems: list[str] = []
        found: dict[str, str] = {}
        for role in ROLES:
            if role in state.files:
                where = locate(role, state.files[role], path)
                if where.problem:
                    problems.append(where.problem)
                if where.path is not None:
                    found[role] = where.path
        saved = Params(**state.params) if state.params else Params()
        w.set_settings(saved, state.correspondence, state.scan_options)
        shown = w.session.params()
        left = [k for k, v in saved.to_dict().items() if shown.to_dict()[k] != v]
        if left:
            problems.append("settings the Settings panel does not hold were left at their defaults: " + ", ".join(left))
        index_at = None
        if state.skeletal_index is not None:
            where = locate("skeletal index", state.skeletal_index, path)
            if where.problem:
                problems.append(where.problem)
            index_at = where.path
        w.session.viewpoints = [tuple(p) for p in state.viewpoints]  # before the evaluation the loading starts
        self._restoring = True
        try:
            with w.session.batch():  # one evaluation, of the inputs as mapped and indexed
                problems += w.session.load_roles(found)
                problems += self._restore_index(index_at, state)
                problems += self._restore_mappings(state)
                if state.edits is not None:
                    problems += w.replay_curve_edits(state.edits)
                w.session.set_correspondence(state.correspondence)  # the saved choice of the set just loaded
        finally:
            self._restoring = False
        scene.set_metric(state.metric)
        scene.set_clim(state.clim)
        scene.set_edges_as_tubes(state.edges_as_tubes)
        for name, on in state.style.items():
            scene.set_style(name, on)
        for role, opts in state.layers.items():
            if role in scene.layers:
                scene.set_visible(role, opts["visible"])
                scene.set_point_size(role, opts["point_size"])
                scene.set_opacity(role, opts["opacity"])
        if state.camera is not None and scene.layers:
            w.view.set_camera_state(state.camera)
        defects = getattr(w, "defects", None)
        if defects is not None:  # the next evaluation keeps those whose defect it has
            defects.set_marks(state.defect_marks)
        self._pending_pick = None
        if state.picked is not None:
            if w.session.runner.running:  # after the evaluation lands (it clears the pick panel)
                self._pending_pick = (state.picked, tuple(scene.layers.values()))
            else:
                problems += self._restore_pick(state.picked)
        self._push({"session": os.path.abspath(path)})
        return problems

    def _restore_index(self, index_at: str | None, state: SessionState) -> list[str]:
        """The skeletal set's index file, found beside the session or where it was (docs/metrics.md 5.1)."""
        from skelcore.io.correspondence_files import load_skeletal_index

        scene = self.window.scene
        if index_at is None or state.skeletal_index is None:
            return []
        name = os.path.basename(state.skeletal_index.path)
        if scene.skeletal is None or scene.cloud is None:
            return [f"skeletal index {name}: not used (no skeletal set and cloud loaded)"]
        try:
            index = load_skeletal_index(index_at, scene.skeletal.n_points, scene.cloud.n_points)
        except SkelInputError as exc:
            return [str(exc)]
        scene.set_skeletal_index(index, index_at)
        return []

    def _restore_mappings(self, state: SessionState) -> list[str]:
        """Each skeleton layer mapped into the cloud's frame as it was (Evaluate > Map skeleton…)."""
        scene = self.window.scene
        out = []
        for role, (scale, offset) in state.mappings.items():
            if role not in scene.layers:
                out.append(f"the {_TITLES[role]}'s mapping (scale {scale:.6g}): its layer was not loaded")
                continue
            scene.map_skeleton(scale, offset, only=(role,))
        return out

    def _restore_pick(self, picked: dict[str, Any]) -> list[str]:
        layer = self.window.scene.layers.get(picked["layer"])
        what = f"picked element ({picked['layer']} #{picked['index']})"
        if layer is None:
            return [f"{what}: its layer was not loaded"]
        n = len(layer.samples) if picked["location"] == "samples" and layer.samples is not None else (
            None if picked["location"] == "samples" else layer.n_points)
        if n is None or picked["index"] >= n:
            return [f"{what}: not in the loaded data"]
        self.window.select_element(picked["layer"], picked["location"], picked["index"])
        return []

    def _evaluated(self, _evaluation: Any) -> None:
        pending, self._pending_pick = self._pending_pick, None
        if pending is not None and pending[1] == tuple(self.window.scene.layers.values()):
            problems = self._restore_pick(pending[0])
            if problems:
                self.window.show_message(problems[0])

    def _on_scene(self, event: Any) -> None:
        if event.kind == "layer" and not self._restoring:
            self._pending_pick = None  # the inputs changed: the saved pick means nothing now

    def report(self, problems: list[str], name: str) -> None:
        """What a session could not restore, in one dialog (scripted: on stderr)."""
        if not problems:
            self.window.show_message(f"Session {name} restored")
            return
        text = f"Session {name}: restored what could be; not as saved:\n" + "\n".join(f"• {p}" for p in problems)
        if not self.window.interactive:
            import sys

            for line in problems:
                print(f"skelscope: warning: {line}", file=sys.stderr)
            return
        box = QtWidgets.QMessageBox(QtWidgets.QMessageBox.Icon.Warning, "Open session", text,
                                    QtWidgets.QMessageBox.StandardButton.Ok, self.window.widget)
        box.exec()

    # ---- File > Recent --------------------------------------------------------------------
    def recent(self) -> list[dict[str, Any]]:
        """The recent entries, newest first: {"session": path} or {"files": {role: path}}."""
        raw = self.window.settings.value(RECENT_KEY, "[]")
        try:
            entries = json.loads(raw if isinstance(raw, str) else "[]")
        except json.JSONDecodeError:
            return []
        return [e for e in entries if isinstance(e, dict) and (isinstance(e.get("session"), str) or (
            isinstance(e.get("files"), dict) and e["files"] and set(e["files"]) <= set(ROLES)))]

    def _push(self, entry: dict[str, Any], replace_top: bool = False) -> None:
        entries = self.recent()
        if replace_top and entries:
            entries = entries[1:]
        entries = [entry] + [e for e in entries if e != entry]
        self.window.settings.setValue(RECENT_KEY, json.dumps(entries[:MAX_RECENT]))
        self.fill_menu()

    def _record_set(self) -> None:
        """After a load: the loaded files are the newest set. The set at the top with the same cloud
        is this set growing (a skeleton added to it): that entry is updated, not one added per file."""
        files = {role: os.path.abspath(layer.path) for role, layer in self.window.scene.layers.items() if layer.path}
        if not files:
            return
        entries = self.recent()
        top = entries[0].get("files") if entries else None
        self._push({"files": files}, replace_top=top is not None and top.get("cloud") == files.get("cloud"))

    def fill_menu(self) -> None:
        self.menu.clear()
        entries = self.recent()
        for entry in entries:
            act = self.menu.addAction(recent_label(entry))
            act.setToolTip(entry["session"] if entry.get("session") else "\n".join(entry["files"].values()))
            act.triggered.connect(lambda _=False, e=entry: self.open_recent(e))
        self.menu.setEnabled(bool(entries))

    def open_recent(self, entry: dict[str, Any]) -> list[str]:
        """Open a recent session, or load a recent set whole (missing files said in one dialog)."""
        if entry.get("session"):
            return self.open(entry["session"])
        files = {role: p for role, p in entry["files"].items() if role in ROLES}
        problems = [f"{os.path.basename(p)}: missing (the {role}; looked for {p})"
                    for role, p in files.items() if not os.path.isfile(p)]
        problems += self.window.session.load_roles({r: p for r, p in files.items() if os.path.isfile(p)})
        if problems:
            self.window.show_error("Open recent", "\n".join(problems))
        return problems


def _stem(scene: Any) -> str:
    for role in ROLES:
        layer = scene.layers.get(role)
        if layer is not None and layer.path:
            return os.path.splitext(os.path.basename(layer.path))[0]
    return "skelscope"
