"""Editing the curve skeleton in the window (Edit menu, through :class:`skelscope.window_api.WindowApi`).

Edit mode (E) turns a pick on the curve (:mod:`skelscope.view.picking`) into a selection: a curve
vertex on a branch selects the branch, a junction vertex the vertex, a curve sample its edge; the last
two vertices picked are kept for Join. Delete deletes the selected edge or vertex or prunes the selected
branch, Shift+Delete deletes the picked vertex itself, "Cut cycle here" removes the selected edge of a
cycle, Join adds the edge between the last two vertices picked, Ctrl+drag moves a curve vertex. Each edit is one :class:`EditCommand` on
a QUndoStack (Ctrl+Z, Ctrl+Shift+Z) holding the curve before and after and the engine's changes
(:mod:`skelcore.edit`), listed in the History dock (its button opens the loaded curve against the
edited one in the A/B view, :mod:`skelscope.edit_compare`); applying one shows the new curve and scores it
again in the worker (:meth:`skelscope.session.Session.show_edited_curve`: ``Evaluation.update`` when
the shown evaluation is of the curve before). File > Save skeleton as… writes the edited curve (the
format by its suffix) and its edit log beside it (``NAME.edits.json``).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, Callable

from PySide6 import QtCore, QtGui, QtWidgets

from .scene import SceneEvent
from .window_api import RIGHT, ActionSpec, WindowApi

if TYPE_CHECKING:
    from .scene.defects import DefectRow

__all__ = ["EditController", "EditCommand", "edit_log_path"]

CURVE_FILTER = "Curve skeletons (*.ply *.obj *.swc *.cg *.graphml *.json);;All files (*)"


def edit_log_path(path: str) -> str:
    """Where the edit log of a curve saved at ``path`` goes: ``NAME.edits.json`` beside it."""
    root, _ext = os.path.splitext(path)
    return root + ".edits.json"


class EditCommand(QtGui.QUndoCommand):
    """One edit: the curve ``before`` and ``after`` and the engine's ``changes`` (several for a row's
    action that deletes several edges); the evaluations of both curves once known, so an undo or a
    redo shows its scores at once."""

    def __init__(self, controller: "EditController", text: str, before: Any, after: Any, changes: list[Any],
                 ev_before: Any = None) -> None:
        super().__init__(text)
        self.controller = controller
        self.before, self.after, self.changes = before, after, list(changes)
        self.ev_before, self.ev_after = ev_before, None

    def redo(self) -> None:
        self.controller.show_curve(self.after, self.ev_after, self)

    def undo(self) -> None:
        self.ev_after = self.controller.evaluation_of(self.after)
        self.controller.show_curve(self.before, self.ev_before, self)


class EditController(QtCore.QObject):
    """Edit mode, the selection, the undo stack and its History dock, Save skeleton as…."""

    def __init__(self, window: WindowApi) -> None:
        super().__init__(window.widget)
        self.window = window
        self.scene = window.scene
        self.session = window.session
        self.active = False
        self.stack = QtGui.QUndoStack(self)
        self.original: Any = None  # the curve the stack's first edit starts from
        self.selection: dict[str, Any] = {}  # {"kind": "branch"|"edge"|"vertex", "index": ...}
        self.vertices: list[int] = []  # the last vertices picked (Join joins the last two)
        self._applying = False
        self._quiet = False  # a replayed log: the curve replaced without scoring each step
        #: how the last curve shown was scored: "known", "update", "full" or "" (Session.show_edited_curve)
        self.last_scoring = ""
        view = QtWidgets.QUndoView(self.stack)
        view.setEmptyLabel("loaded curve")
        self.history = view
        box = QtWidgets.QWidget()  # the list, and a row of buttons under it (history_buttons)
        layout = QtWidgets.QVBoxLayout(box)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(view)
        self.history_buttons = QtWidgets.QHBoxLayout()
        layout.addLayout(self.history_buttons)
        dock = window.add_dock("History", box, RIGHT)
        if "Defects" in window.docks:  # a tab beside the Defects dock (a small screen has no room for another)
            window.widget.tabifyDockWidget(window.docks["Defects"], dock)
        if "Barcodes" in window.docks:
            window.docks["Barcodes"].raise_()
        in_edit = self._can_edit
        self.actions: dict[str, tuple[QtGui.QAction, ActionSpec]] = {}
        for spec in (
            ActionSpec("edit_mode", "Edit mode", "edit.mode", self.set_active, "E", enabled=lambda: self.scene.curve is not None,
                       checked=lambda: self.active),
            ActionSpec("undo", "Undo", "edit.history", self.undo, "Ctrl+Z", enabled=self.stack.canUndo),
            ActionSpec("redo", "Redo", "edit.history", self.redo, "Ctrl+Shift+Z", enabled=self.stack.canRedo),
            ActionSpec("edit_delete", "Delete selection (edge, vertex or branch)", "edit.ops", self.delete_selected,
                       "Delete", enabled=in_edit),
            ActionSpec("edit_delete_vertex", "Delete picked vertex", "edit.ops", self.delete_picked_vertex,
                       "Shift+Delete", enabled=in_edit),
            ActionSpec("edit_cut_cycle", "Cut cycle here", "edit.ops", self.cut_selected_cycle, enabled=in_edit),
            ActionSpec("edit_join", "Join the last two picked vertices", "edit.ops", self.join_picked, "J",
                       enabled=in_edit),
            ActionSpec("save_skeleton", "Save skeleton as…", "file.export", self.save_dialog,
                       enabled=lambda: self.scene.curve is not None),
        ):
            self.actions[spec.name] = (window.add_action(spec), spec)
        self.dock = dock
        self.dragging: int | None = None  # the curve vertex a Ctrl+drag moves
        window.view.plotter.installEventFilter(self)
        self.stack.indexChanged.connect(lambda _i: self._refresh_actions())
        window.element_picked.connect(self._picked)
        self.scene.subscribe(self._on_scene)

    # ---- state ----------------------------------------------------------------------------
    @property
    def applying(self) -> bool:
        """The curve is being replaced by an edit, its undo or its redo (the same skeleton, edited)."""
        return self._applying

    def _can_edit(self) -> bool:
        return self.active and self.scene.curve is not None

    def set_active(self, on: bool = True) -> None:
        """Edit mode on or off (E): picks select, the History dock shows."""
        self.active = bool(on) and self.scene.curve is not None
        self.selection, self.vertices = {}, []
        if self.active:
            self.dock.show()
            self.dock.raise_()
        self.window.show_message("edit mode: pick a branch, an edge or a vertex; Delete removes it"
                                 if self.active else "edit mode off", 5000)
        self._refresh_actions()

    def _refresh_actions(self) -> None:
        """This controller's actions' enable and check states (edit mode and the stack change them
        without a scene event)."""
        import shiboken6

        if not shiboken6.isValid(self.stack):  # the window going away: the stack clears itself
            return
        for _name, (action, spec) in self.actions.items():
            if not shiboken6.isValid(action):
                return
            if spec.enabled is not None:
                action.setEnabled(bool(spec.enabled()))
            if spec.checked is not None and action.isChecked() != bool(spec.checked()):
                action.blockSignals(True)
                action.setChecked(bool(spec.checked()))
                action.blockSignals(False)

    def _on_scene(self, event: SceneEvent) -> None:
        if event.kind == "layer" and event.layer == "curve" and not self._applying:
            layer = self.scene.curve
            self.stack.clear()  # another curve (loaded, closed, mapped): the edits were of the one before
            self.original = None if layer is None else layer.curve
            self.selection, self.vertices = {}, []
            if layer is None:
                self.active = False
            self._refresh_actions()

    def evaluation_of(self, curve: Any, partial: bool = False) -> Any:
        """The shown evaluation when it is of ``curve`` (kept by the undo step), else None; never an
        edit's first phase (its defects still updating: an undo step keeps whole evaluations) unless
        ``partial`` (the A/B view after Esc stopped the defects: it shows what is there)."""
        from .edit_scoring import defects_pending

        ev = self.scene.evaluation
        layer = self.scene.curve
        if (ev is None or layer is None or layer.curve is not curve or self.session.stale_reason()
                or (defects_pending(ev) and not partial)):
            return None
        return ev

    def show_curve(self, curve: Any, known: Any, command: EditCommand | None = None) -> None:
        """The stack's way to change the curve: shown, then scored (the known evaluation at once)."""
        self._applying = True
        try:
            self.last_scoring = self.session.show_edited_curve(curve, known, score=not self._quiet,
                                                               edited=curve is not self.original)
        finally:
            self._applying = False
        self.selection, self.vertices = {}, []
        if command is not None:
            self.window.show_message(f"{command.text()}: {curve.n_vertices} vertices, {curve.n_edges} edges", 5000)

    # ---- edits ----------------------------------------------------------------------------
    def apply(self, text: str, operations: list[Callable[[Any], tuple[Any, Any]]]) -> bool:
        """Apply ``operations`` (each ``curve -> (new curve, change)``) as one undoable edit; a refused
        edit (one line from the engine) is shown and changes nothing."""
        from skelcore.errors import SkelInputError

        layer = self.scene.curve
        if layer is None:
            self.window.show_message("no curve skeleton to edit")
            return False
        before = curve = layer.curve
        changes = []
        try:
            for op in operations:
                curve, change = op(curve)
                changes.append(change)
        except SkelInputError as exc:
            self.window.show_error("Edit refused", str(exc))
            return False
        if self.original is None or not self.stack.count():
            self.original = before
        self.stack.push(EditCommand(self, text, before, curve, changes, self.evaluation_of(before)))
        return True

    def undo(self) -> None:
        self.stack.undo()

    def redo(self) -> None:
        self.stack.redo()

    def delete_selected(self) -> bool:
        """Delete: the selected edge or vertex, or prune the selected branch."""
        import skelcore.edit as edit

        sel = self.selection
        kind, index = sel.get("kind"), sel.get("index")
        if kind == "branch":
            return self.apply(f"prune branch #{index}", [lambda c: edit.prune_branch(c, index)])
        if kind == "edge":
            return self.apply(f"delete edge {index[0]}-{index[1]}", [lambda c: edit.delete_edge(c, index)])
        if kind == "vertex":
            return self.apply(f"delete vertex #{index}", [lambda c: edit.delete_vertex(c, index)])
        self.window.show_message("nothing selected: in edit mode (E), pick a branch, an edge or a vertex")
        return False

    def delete_picked_vertex(self) -> bool:
        import skelcore.edit as edit

        if not self.vertices:
            self.window.show_message("no vertex picked: in edit mode (E), pick a curve vertex")
            return False
        v = self.vertices[-1]
        return self.apply(f"delete vertex #{v}", [lambda c: edit.delete_vertex(c, v)])

    def cut_selected_cycle(self) -> bool:
        import skelcore.edit as edit

        if self.selection.get("kind") != "edge":
            self.window.show_message("pick an edge of the cycle first (a curve sample between two vertices)")
            return False
        a, b = self.selection["index"]
        return self.apply(f"cut cycle at {a}-{b}", [lambda c: edit.cut_cycle(c, (a, b))])

    def join_picked(self) -> bool:
        import skelcore.edit as edit

        if len(self.vertices) < 2:
            self.window.show_message("Join: pick two curve vertices first")
            return False
        a, b = self.vertices[-2:]
        return self.apply(f"join {a}-{b}", [lambda c: edit.add_edge(c, (a, b))])

    # ---- selection ------------------------------------------------------------------------
    def select(self, kind: str, index: Any) -> None:
        """Select a branch id, an edge (a vertex pair) or a vertex id, as a pick in edit mode would."""
        if kind not in ("branch", "edge", "vertex"):
            raise ValueError(f"unknown selection {kind!r}: branch, edge or vertex")
        self.selection = {"kind": kind, "index": tuple(int(v) for v in index) if kind == "edge" else int(index)}

    def _picked(self, info: dict[str, Any] | None) -> None:
        if not self.active or info is None or info.get("layer") != "curve":
            if self.active and info is None:
                self.selection = {}
            return
        layer = self.scene.curve
        if layer is None or layer.curve is None:
            return
        index = int(info["index"])
        if info.get("location") == "samples":
            edge = info.get("edge")
            if edge is None:
                return
            a, b = (int(v) for v in layer.curve.edges[int(edge)])
            self.select("edge", (a, b))
            what = f"edge {a}-{b} (Delete removes it, Cut cycle here cuts a cycle)"
        else:
            self.vertices = (self.vertices + [index])[-2:]
            branch = info.get("branch")
            if branch is not None:
                self.select("branch", int(branch["branch"]))
                what = f"branch #{int(branch['branch'])} (Delete prunes it; Shift+Delete deletes vertex #{index})"
            else:
                self.select("vertex", index)
                what = f"vertex #{index} (Delete removes it)"
        self.window.show_message(f"selected {what}", 8000)

    # ---- dragging a vertex ----------------------------------------------------------------
    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802
        """In edit mode, Ctrl+drag on a curve vertex moves it (one undoable edit, on release) on the
        plane through it facing the camera; the camera does not move meanwhile."""
        t = event.type()
        Type = QtCore.QEvent.Type  # noqa: N806
        if t not in (Type.MouseButtonPress, Type.MouseMove, Type.MouseButtonRelease):
            return False
        if t == Type.MouseButtonPress:
            if (not self._can_edit() or event.button() != QtCore.Qt.MouseButton.LeftButton
                    or not event.modifiers() & QtCore.Qt.KeyboardModifier.ControlModifier):
                return False
            x, y = self.window.view.qt_to_display(event.position())
            info = self.window.view.pick_display(x, y)
            if info is None or info.get("layer") != "curve" or info.get("location") != "vertices":
                return False
            self.dragging = int(info["index"])
            self.window.show_message(f"moving vertex #{self.dragging}: release to drop it", 5000)
            return True
        if self.dragging is None:
            return False
        if t == Type.MouseButtonRelease:
            v, self.dragging = self.dragging, None
            layer = self.scene.curve
            if layer is not None and v < layer.curve.n_vertices:
                x, y = self.window.view.qt_to_display(event.position())
                self.move_vertex(v, self.window.view.display_to_world(x, y, layer.curve.vertices[v]))
        return True

    def move_vertex(self, v: int, xyz: Any) -> bool:
        """Move curve vertex ``v`` to ``xyz`` (a drag's drop), as one undoable edit."""
        import skelcore.edit as edit

        xyz = tuple(float(c) for c in xyz)
        return self.apply(f"move vertex #{v}", [lambda c: edit.move_vertex(c, v, xyz)])

    # ---- the Defects dock's rows ----------------------------------------------------------
    def row_actions(self, row: "DefectRow") -> list[tuple[str, Callable[[], Any]]]:
        """What a Defects row offers: prune a spurious branch, delete an outside edge, cut a spurious
        cycle (at the first of its edges whose removal keeps the curve in one piece)."""
        import skelcore.edit as edit

        layer = self.scene.curve
        if layer is None or row.column != "curve":
            return []
        edges = [tuple(int(v) for v in layer.curve.edges[int(i)]) for i in row.edges
                 if 0 <= int(i) < layer.curve.n_edges]
        out: list[tuple[str, Callable[[], Any]]] = []
        if row.code == "spurious_branches" and len(row.branches) == 1:
            b = int(row.branches[0])
            out.append(("Prune this branch", lambda: self.apply(f"prune branch #{b}", [lambda c: edit.prune_branch(c, b)])))
        elif row.code == "outside" and edges:
            text = "Delete this edge" if len(edges) == 1 else f"Delete these {len(edges)} edges"
            done = "delete an outside edge" if len(edges) == 1 else f"delete {len(edges)} outside edges"
            ops = [lambda c, e=e: edit.delete_edge(c, e) for e in edges]
            out.append((text, lambda: self.apply(done, ops)))
        elif row.code == "spurious_cycles" and edges:
            out.append(("Cut this cycle", lambda: self._cut_first(edges)))
        elif row.code == "disconnected" and edges:
            pair = _nearest_join(layer.curve, edges)
            if pair is not None:
                a, b = pair
                out.append(("Join this piece", lambda: self.apply(f"join vertices #{a} and #{b}",
                                                                  [lambda c: edit.add_edge(c, (a, b))])))
        return out

    def _cut_first(self, edges: list[tuple[int, int]]) -> bool:
        import skelcore.edit as edit
        from skelcore.errors import SkelInputError

        layer = self.scene.curve
        for e in edges:
            try:
                edit.cut_cycle(layer.curve, e)
            except SkelInputError:
                continue
            return self.apply(f"cut cycle at {e[0]}-{e[1]}", [lambda c: edit.cut_cycle(c, e)])
        self.window.show_error("Edit refused", "no edge of this cycle can be cut without splitting the curve")
        return False

    def replay(self, log: dict[str, Any]) -> list[str]:
        """An edit log (a saved session's) replayed on the loaded curve, one undoable edit per
        operation, scored once by the evaluation that follows; its problem in one line otherwise."""
        import skelcore.edit as edit
        from skelcore.errors import SkelInputError

        layer = self.scene.curve
        if layer is None:
            return ["the curve's edits: no curve skeleton loaded"]
        try:
            _final, changes = edit.replay(layer.curve, log)
        except SkelInputError as exc:
            return [f"the curve's edits were not replayed: {exc}"]
        self.original = layer.curve
        before = layer.curve
        self._quiet = True
        try:
            for change in changes:
                self.stack.push(EditCommand(self, change.op.replace("_", " "), before, change.curve, [change]))
                before = change.curve
        finally:
            self._quiet = False
        return []

    # ---- saving ---------------------------------------------------------------------------
    def edit_log(self) -> dict[str, Any] | None:
        """The edits done (up to the stack's position) as an edit log of the curve they start from."""
        import skelcore.edit as edit

        if self.original is None or not self.stack.index():
            return None
        changes = [c for i in range(self.stack.index()) for c in self.stack.command(i).changes]
        return edit.new_log(self.original, changes)

    def save(self, path: str) -> list[str]:
        """Write the shown curve to ``path`` (format by suffix) and, when edited, its edit log beside
        it. Over the loaded curve's file only when the user agrees (a question; default: no);
        over another existing file likewise. Returns the files written ([] when not agreed)."""
        import skelcore.edit as edit
        from skelcore.io.writers import write_curve

        layer = self.scene.curve
        if layer is None:
            raise ValueError("no curve skeleton to save")
        path = os.path.abspath(path)
        log_path = edit_log_path(path)
        loaded = layer.path and os.path.abspath(layer.path) == path
        existing = [p for p in (path, log_path) if os.path.exists(p)]
        if existing:
            names = ", ".join(os.path.basename(p) for p in existing)
            question = (f"{os.path.basename(path)} is the loaded curve skeleton's file: replace it with the edited curve?"
                        if loaded else f"{names} exist(s) already: replace?")
            options = ["Keep the file (cancel)", "Replace"]
            if self.session.ask(question, options) != options[1]:
                self.window.show_message("not saved")
                return []
        inputs = [p for p in self.window.input_files() if os.path.abspath(p) != path]
        if loaded:  # the user agreed: the loaders' guard on this file is lifted for this write only
            from skelcore.io.atomic import protect, release

            release(path)
            try:
                write_curve(path, layer.curve, inputs=inputs)
            finally:
                protect(path)
        else:
            write_curve(path, layer.curve, inputs=inputs)
        written = [path]
        log = self.edit_log()
        if log is not None:
            defects = getattr(self.window, "defects", None)
            if defects is not None and defects.marks:  # the Defects dock's marks, beside the operations
                log = {**log, "defect_marks": dict(defects.marks)}
            edit.write_log(log_path, log)
            written.append(log_path)
        self.window.show_message(f"saved {', '.join(os.path.basename(p) for p in written)}", 8000)
        return written

    def save_dialog(self) -> None:
        from skelcore.errors import SkelInputError

        layer = self.scene.curve
        if layer is None:
            return
        stem = os.path.splitext(os.path.basename(layer.path or "curve.ply"))[0]
        default = os.path.join(self.window.last_dir(), f"{stem}_edited.ply")
        path, _ = QtWidgets.QFileDialog.getSaveFileName(
            self.window.widget, "Save skeleton as", default, CURVE_FILTER,
            options=QtWidgets.QFileDialog.Option.DontConfirmOverwrite)
        if path:
            try:
                self.save(path)
            except (ValueError, OSError, SkelInputError) as exc:
                self.window.show_error("Save skeleton failed", str(exc))


def _nearest_join(curve: Any, edges: list[tuple[int, int]]) -> tuple[int, int] | None:
    """The closest pair (a vertex of the piece holding ``edges``, a vertex of another piece): where
    "Join this piece" adds its edge (:func:`~skelcore.diagnostics.pieces.nearest_other_piece`)."""
    from skelcore.diagnostics.pieces import curve_pieces, nearest_other_piece

    _n, piece = curve_pieces(curve)
    _gap, own, other = nearest_other_piece(curve.vertices, piece)
    p = int(piece[edges[0][0]])
    return None if p < 0 or own[p] < 0 else (int(own[p]), int(other[p]))
