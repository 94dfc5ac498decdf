"""Two skeletons of one cloud side by side: A (the main window's) and B (another method's).

One pyvista interactor split in two renderers that share one camera (linked cameras: rotating either
moves both), each drawing the cloud and its skeleton coloured by the chosen metric, and the summary
table with A, B and B - A columns (the scores of :meth:`Evaluation.summary` at A's thresholds; green where B is better).
File > "Compare with a second skeleton (B)…" loads B's files and evaluates them in the worker;
File > "Open comparison run…" (:mod:`skelscope.compare_run`) opens two report rows' stored results.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from skelcore.scores import COLUMN, LOCAL_METRICS, Scores, column_keys, format_score

from .edit_scoring import defects_pending
from .window_api import ActionSpec, WindowApi
from .window_size import FRAME_ALLOWANCE, initial_size

__all__ = ["ab_rows", "ab_defect_rows", "CompareWindow", "CompareController"]

#: the mark of SkelScope's own scores (coverage), as in the main window's summary
OWN = "*"


def _label(key: str) -> str:
    return COLUMN[key].label + (OWN if COLUMN[key].group == "skelscope" else "")


def ab_rows(a: Any, b: Any) -> list[tuple[str, float, float, float]]:
    """(label, A, B, B - A) per compared paper score (:data:`skelcore.scores.SCORE_COLUMNS`), then
    SkelScope's coverage (labels marked "*", as in the main summary), of two
    :class:`~skelcore.scores.Scores` (or ``Evaluation.summary()`` dicts); NaN where either side has
    no such score (a missing topology, no curve), and a row left out when neither has it."""
    a, b = (s if isinstance(s, Scores) else Scores.from_json_dict(s) for s in (a, b))
    keys = column_keys(group=("paper", "skelscope"), compared=True)
    fa, fb = a.flat(keys), b.flat(keys)
    return [(_label(k), fa[k], fb[k], fb[k] - fa[k]) for k in keys
            if not (math.isnan(fa[k]) and math.isnan(fb[k]))]


def vacuous_scores(ev: Any) -> dict[str, str]:
    """The scores of ``ev`` that say nothing, by A/B row label, each with its warning: the curve's
    smoothness without a degree-2 vertex (``trivial_smoothness``), and the scores a collapsed skeleton
    gets for free (``collapse``: topology, boundedness, centeredness and smoothness of that skeleton;
    its coverage stays, and tells)."""
    out: dict[str, str] = {}
    sk = getattr(ev, "skeletal", None)
    topology_of = "curve" if sk is None or getattr(sk, "source", "skeletal") == "curve" else "skeletal"
    for w in getattr(ev, "warnings", None) or []:
        code = w["code"] if isinstance(w, dict) else w.code
        message = w["message"] if isinstance(w, dict) else w.message
        why = f"[{code}] {message}"
        if code == "trivial_smoothness":
            out.setdefault(_label("smoothness_curve"), why)
        elif code == "collapse":
            kind = "curve" if message.startswith("the curve skeleton") else "skeletal"
            keys = [f"{metric}_{kind}" for metric in ("boundedness", "centeredness", "smoothness")]
            keys += ["d_B", "d_Wp"] if kind == topology_of else []
            for key in keys:
                out.setdefault(_label(key), why)
    return out


def ab_defect_rows(ev_a: Any, ev_b: Any) -> list[tuple[str, float, float, float]]:
    """(label, A, B, B - A) per defect code found in A or B: how many of each (the Defects panel's rows,
    :func:`skelscope.scene.defects.defect_rows`); fewer is better."""
    from .scene.defects import DEFECT_TITLES, defect_counts

    ca, cb = defect_counts(ev_a), defect_counts(ev_b)
    return [(f"defects: {code}", float(ca.get(code, 0)), float(cb.get(code, 0)),
             float(cb.get(code, 0) - ca.get(code, 0))) for code in DEFECT_TITLES if code in ca or code in cb]


def _lower_is_better(label: str) -> bool:
    if label.startswith("defects: "):
        return True
    return any(_label(c.key) == label and c.better == "lower" for c in COLUMN.values())


#: the tooltip of a defect count the A/B view does not know (Esc stopped the edit's second phase)
NOT_COMPUTED = "the edited curve's defects were not computed (Esc stopped them; Evaluate, F5, finds them)"

#: the A/B window's size on a screen with room for it
AB_SIZE = (1400, 850)


class CompareWindow(QtWidgets.QWidget):
    """A/B view of two evaluations of one cloud."""

    def __init__(self, ev_a: Any, ev_b: Any, names: tuple[str, str] = ("A", "B"), metric: str = "centeredness",
                 thresholds: tuple[float, float] | None = None, parent: QtWidgets.QWidget | None = None,
                 context: str = "") -> None:
        super().__init__(parent, QtCore.Qt.WindowType.Window)
        from .view.interactor import ClosingInteractor

        self.context = context  # e.g. a compare run's dataset, condition and seed
        self.setWindowTitle(f"SkelScope — A: {names[0]}  |  B: {names[1]}" + (f"  ({context})" if context else ""))
        self.fit_to_screen(self.screen())
        self.ev_a, self.ev_b, self.names = ev_a, ev_b, names
        self.thresholds = thresholds or (ev_a.params.beta_star, ev_a.params.c_star)
        self.plotter = ClosingInteractor(self, shape=(1, 2), auto_update=False)
        self.metric_box = QtWidgets.QComboBox(self)
        self.metric_box.addItems(list(LOCAL_METRICS))
        self.metric_box.setCurrentText(metric)
        self.metric_box.currentTextChanged.connect(self.draw)
        self.table = QtWidgets.QTableWidget(self)
        self.table.setColumnCount(4)
        self.table.setHorizontalHeaderLabels(["score", f"A: {names[0]}", f"B: {names[1]}", "B - A"])
        self.table.verticalHeader().setVisible(False)
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        top = QtWidgets.QHBoxLayout()
        top.addWidget(QtWidgets.QLabel("colour by", self))
        top.addWidget(self.metric_box)
        top.addStretch(1)
        if context:
            top.addWidget(QtWidgets.QLabel(context, self))
        split = QtWidgets.QSplitter(QtCore.Qt.Orientation.Vertical, self)
        split.addWidget(self.plotter)
        split.addWidget(self.table)
        split.setSizes([520, 330])
        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(top)
        layout.addWidget(split)
        self.rows = ab_rows(ev_a.scores(*self.thresholds), ev_b.scores(*self.thresholds))
        from .scene.defects import sound_line

        self.defect_rows = ab_defect_rows(ev_a, ev_b)  # the defects of A and B
        # an edit's first phase whose defects Esc stopped: its defect counts are not known, not 0
        self.pending = tuple(defects_pending(ev) for ev in (ev_a, ev_b))
        self.vacuous = (vacuous_scores(ev_a), vacuous_scores(ev_b))
        self._legends: list[Any] = []  # (renderer, legend, fit observer): one per half that draws defects
        self.sound = (sound_line(ev_a), sound_line(ev_b))
        self._fill_table()
        self.draw()
        self.plotter.link_views()  # one camera for both renderers
        self.plotter.reset_camera()

    def _fill_table(self) -> None:
        """The scores, then one row per defect code found in A or B (counts) and the sound / not line."""
        n_scores = len(self.rows)
        self.table.setRowCount(n_scores + len(self.defect_rows) + 1)
        for r, (label, a, b, d) in enumerate(self.rows + self.defect_rows):
            if r < n_scores:
                texts = (label, *(format_score(v, 4, nan="—") for v in (a, b)), format_score(d, 4, nan="—", signed=True))
            elif any(self.pending):
                texts = (label, *("not computed" if p else f"{v:.0f}" for p, v in zip(self.pending, (a, b))), "—")
            else:
                texts = (label, f"{a:.0f}", f"{b:.0f}", f"{d:+.0f}" if d else "0")
            vacuous = [(side, v[label]) for side, v in zip("AB", self.vacuous) if r < n_scores and label in v]
            for c, text in enumerate(texts):
                item = QtWidgets.QTableWidgetItem(text)
                if c:
                    item.setTextAlignment(QtCore.Qt.AlignmentFlag.AlignRight | QtCore.Qt.AlignmentFlag.AlignVCenter)
                if c == 0 and label.endswith(OWN):
                    item.setToolTip("SkelScope's own score, not the paper's: the fraction of the cloud covered by "
                                    "the skeleton's medial balls")
                if c in (1, 2) and label in self.vacuous[c - 1]:
                    item.setText(f"{text} (vacuous)")
                    item.setForeground(self.palette().color(QtGui.QPalette.ColorGroup.Disabled,
                                                            QtGui.QPalette.ColorRole.Text))
                    item.setToolTip(f"says nothing: {self.vacuous[c - 1][label]}")
                if r >= n_scores and c and any(self.pending):
                    item.setToolTip(NOT_COMPUTED)
                elif c == 3 and vacuous and not math.isnan(d):
                    # a vacuous value is no improvement nor a loss: grey, never green or red
                    item.setForeground(self.palette().color(QtGui.QPalette.ColorGroup.Disabled,
                                                            QtGui.QPalette.ColorRole.Text))
                    item.setToolTip("not compared: " + "; ".join(f"{side}'s {label} says nothing ({why})"
                                                                for side, why in vacuous))
                elif c == 3 and not math.isnan(d) and d != 0:
                    better = d < 0 if _lower_is_better(label) else d > 0  # distances: lower is better
                    item.setForeground(QtCore.Qt.GlobalColor.darkGreen if better else QtCore.Qt.GlobalColor.darkRed)
                    item.setToolTip("B is better" if better else "A is better")
                self.table.setItem(r, c, item)
        last = n_scores + len(self.defect_rows)
        sound = ["not computed" if p else t for p, t in zip(self.pending, self.sound)]
        for c, text in enumerate(("sound (no defect warning)", *sound, "")):
            item = QtWidgets.QTableWidgetItem(text)
            item.setToolTip(NOT_COMPUTED if text == "not computed" else text)
            if text == "not computed":
                item.setForeground(self.palette().color(QtGui.QPalette.ColorGroup.Disabled, QtGui.QPalette.ColorRole.Text))
            elif c in (1, 2):
                item.setForeground(QtCore.Qt.GlobalColor.darkGreen if text == "sound" else QtCore.Qt.GlobalColor.darkRed)
            self.table.setItem(last, c, item)
        self.table.resizeColumnsToContents()

    def fit_to_screen(self, screen: Any) -> None:
        """AB_SIZE, shrunk to ``screen``'s free area as the main window is, and placed inside it."""

        free = screen.availableGeometry()
        width, height = initial_size(free.size(), AB_SIZE)
        self.resize(width, height)
        x = free.x() + max(0, (free.width() - width - FRAME_ALLOWANCE[0]) // 2)
        y = free.y() + max(0, (free.height() - height - FRAME_ALLOWANCE[1]) // 2)
        self.move(x, y)

    def cell(self, row: int, col: int) -> str:
        return self.table.item(row, col).text()

    def draw(self, *_: Any) -> None:
        import pyvista as pv

        from skelcore.colors import CLOUD_GREY, CURVE_COLOR, MAGENTA

        from .view.actors import display_coordinates
        from .view.style import make_lut

        metric = self.metric_box.currentText()
        b_star, _c_star = self.thresholds
        lut = make_lut((0.0, 1.0))
        self.plotter.clear_actors()  # every renderer's
        for renderer, legend, observer in self._legends:
            renderer.RemoveObserver(observer)
            renderer.RemoveViewProp(legend)
        self._legends = []
        for title in list(self.plotter.scalar_bars.keys()):
            self.plotter.remove_scalar_bar(title, render=False)
        for col, (ev, name) in enumerate(((self.ev_a, self.names[0]), (self.ev_b, self.names[1]))):
            self.plotter.subplot(0, col)
            self.plotter.set_background("white")
            self.plotter.add_text(f"{'AB'[col]}: {name}", font_size=10, color="black", name=f"title-{col}")
            self.plotter.add_mesh(pv.PolyData(display_coordinates(ev.cloud)), color=CLOUD_GREY, style="points",
                                  point_size=2, opacity=0.3, lighting=False, reset_camera=False, render=False)
            if ev.skeletal is not None:
                values = {"boundedness": ev.skeletal.boundedness, "centeredness": ev.skeletal.centeredness(b_star),
                          "smoothness": ev.skeletal.smoothness}[metric]
                mesh = pv.PolyData(display_coordinates(ev.skeletal.points))
                mesh["values"] = np.asarray(values, dtype=float)
                self.plotter.add_mesh(mesh, scalars="values", cmap=lut, clim=(0.0, 1.0), nan_color=MAGENTA,
                                      style="points", point_size=6, lighting=False, reset_camera=False,
                                      render=False, show_scalar_bar=col == 1,
                                      scalar_bar_args={"title": metric, "color": "black", "vertical": True,
                                                       "position_x": 0.86, "position_y": 0.2, "height": 0.6,
                                                       "width": 0.06, "n_labels": 5, "fmt": "%.2f"})
            self._draw_defects(ev)
            if ev.curve is not None:
                curve = ev.curve.curve
                edges = np.asarray(curve.edges, dtype=np.int64).reshape(-1, 2)
                if len(edges):
                    cells = np.hstack([np.full((len(edges), 1), 2, dtype=np.int64), edges]).ravel()
                    self.plotter.add_mesh(pv.PolyData(display_coordinates(curve.vertices), lines=cells),
                                          color=CURVE_COLOR, line_width=2.5, lighting=False, reset_camera=False,
                                          render=False)
                if metric != "smoothness":
                    vals = ev.curve.sample_boundedness if metric == "boundedness" else ev.curve.sample_centeredness(b_star)
                    mesh = pv.PolyData(display_coordinates(ev.curve.samples))
                    mesh["values"] = np.asarray(vals, dtype=float)
                    self.plotter.add_mesh(mesh, scalars="values", cmap=lut, clim=(0.0, 1.0), nan_color=MAGENTA,
                                          style="points", point_size=5, lighting=False, reset_camera=False,
                                          render=False, show_scalar_bar=False)
        self.plotter.render()

    def _draw_defects(self, ev: Any) -> None:
        """Missing parts' cloud points and halos around spurious branches and cycles, as in the main
        view (:mod:`skelscope.view.defect_overlay`'s colours and styles), in the current renderer."""
        import pyvista as pv

        from skelcore.colors import DEFECT_COLORS

        from .scene.defects import defect_rows
        from .view.actors import display_coordinates

        rows = defect_rows(ev)
        drawn: list[str] = []  # the legend's entries (the main view's styles and labels)
        missing = [r.cloud_rows for r in rows if r.code == "incomplete" and len(r.cloud_rows)]
        if missing and ev.cloud is not None:
            sel = np.unique(np.concatenate(missing))
            self.plotter.add_mesh(pv.PolyData(display_coordinates(np.asarray(ev.cloud)[sel])),
                                  color=DEFECT_COLORS["incomplete"], style="points", point_size=4, lighting=False,
                                  reset_camera=False, render=False)
            drawn.append("incomplete")
        if ev.curve is not None:
            drawn += self._draw_curve_defects(ev, rows)
        if drawn:
            from .view.defect_overlay import LEGEND_LABELS, defect_legend, keep_fitted

            legend = defect_legend(drawn)
            renderer = self.plotter.renderer
            renderer.AddViewProp(legend)
            observer = keep_fitted(legend, renderer, [LEGEND_LABELS[k] for k in drawn])
            self._legends.append((renderer, legend, observer))

    def legend_labels(self, col: int) -> list[str]:
        """The defect legend's entries of half ``col`` (0: A, 1: B); [] when it draws no defect."""
        renderer = self.plotter.renderers[col]
        return [legend.GetEntryString(i) for r, legend, _observer in self._legends if r is renderer
                for i in range(legend.GetNumberOfEntries())]

    def _draw_curve_defects(self, ev: Any, rows: list[Any]) -> list[str]:
        import pyvista as pv

        from skelcore.colors import DEFECT_COLORS

        from .view.actors import display_coordinates

        drawn = []
        verts = np.asarray(ev.curve.curve.vertices, dtype=float)
        edges = np.asarray(ev.curve.curve.edges, dtype=np.int64).reshape(-1, 2)
        for code in ("spurious_branches", "spurious_cycles", "outside"):
            ids = [r.edges for r in rows if r.code == code and len(r.edges)]
            if not ids:
                continue
            pick = edges[np.unique(np.concatenate(ids))]
            cells = np.hstack([np.full((len(pick), 1), 2, dtype=np.int64), pick]).ravel()
            self.plotter.add_mesh(pv.PolyData(display_coordinates(verts), lines=cells), color=DEFECT_COLORS[code],
                                  line_width=9 if code != "outside" else 5, opacity=0.5 if code != "outside" else 1.0,
                                  lighting=False, reset_camera=False, render=False)
            drawn.append(code)
        return drawn

    def image(self) -> np.ndarray:
        self.plotter.render()
        return np.asarray(self.plotter.screenshot(None, return_img=True))

    def picture(self) -> np.ndarray:
        """The whole window (both views, the table) as an (H, W, 3) uint8 image."""
        from PySide6 import QtGui

        self.plotter.render()
        img = self.grab().toImage().convertToFormat(QtGui.QImage.Format.Format_RGB888)
        h, w, bpl = img.height(), img.width(), img.bytesPerLine()
        return np.frombuffer(img.constBits(), np.uint8).reshape(h, bpl)[:, : w * 3].reshape(h, w, 3).copy()

    def closeEvent(self, event: Any) -> None:  # noqa: N802
        self.plotter.close()
        super().closeEvent(event)


class CompareController(QtCore.QObject):
    """File > Compare with a second skeleton (B): load, evaluate B in the worker, open the A/B window."""

    NAME = "evaluation B"

    def __init__(self, window: WindowApi) -> None:
        super().__init__(window.widget)
        self.window = window
        self.views: list[CompareWindow] = []
        self._pending: tuple[Any, str] | None = None
        window.session.runner.succeeded.connect(self._succeeded)
        window.add_action(ActionSpec("compare", "Compare with a second skeleton (B)…", "file.compare", self.dialog))
        window.closing.connect(self.close_views)  # the A/B windows close with the main window

    def close_views(self) -> None:
        for view in self.views:
            view.close()
        self.views = []

    def dialog(self) -> None:
        from skelcore.io import SUPPORTED_EXTENSIONS

        patterns = " ".join(f"*{ext}" for ext in sorted(set(SUPPORTED_EXTENSIONS)))
        paths, _ = QtWidgets.QFileDialog.getOpenFileNames(self.window.widget,
                                                          "Open skeleton B (skeletal points and/or curve)",
                                                          self.window.last_dir(),
                                                          f"Skeletons ({patterns});;All files (*)")
        if paths:
            self.compare_files(paths)

    def compare_files(self, paths: list[str]) -> bool:
        """Load B's skeletal set and/or curve skeleton and evaluate them against A's cloud."""
        from skelcore.errors import SkelInputError
        from skelcore.io import load_any

        skeletal = curve = None
        try:
            for path in paths:
                item = load_any(path)
                if item.kind == "curve":
                    curve = item.curve
                else:
                    skeletal = item.points
        except SkelInputError as exc:
            self.window.show_error("Compare", str(exc))
            return False
        name = ", ".join(os.path.basename(p) for p in paths)
        return self.compare_arrays(skeletal, curve, name)

    def compare_arrays(self, skeletal: Any, curve: Any, name: str = "B") -> bool:
        import skelcore

        ev_a = self.window.scene.evaluation
        if ev_a is None:
            self.window.show_error("Compare", "evaluate A (the loaded skeleton) first")
            return False
        if skeletal is None and curve is None:
            self.window.show_error("Compare", "skeleton B has neither skeletal points nor a curve")
            return False
        params = ev_a.params
        cloud = ev_a.cloud
        # B's own set decides: pointwise when it has the cloud's rows, else A's choice of reverse projection
        pointwise = skeletal is not None and len(skeletal) == len(cloud)
        correspondence = "reverse" if ev_a.correspondence == "reverse" and not pointwise else "auto"
        scan = getattr(ev_a, "scan", None)
        viewpoints = [list(v) for v in scan.viewpoints] if scan is not None and scan.viewpoints else None  # as A's

        def job(progress: Any, cancel: Any) -> Any:
            return skelcore.evaluate(cloud, skeletal, curve, params, progress, cancel, correspondence=correspondence,
                                     viewpoints=viewpoints)

        self._pending = (ev_a, name)
        self.window.session.runner.start(job, self.NAME)
        return True

    def _succeeded(self, name: str, result: Any) -> None:
        if name != self.NAME or self._pending is None:
            return
        ev_a, b_name = self._pending
        self._pending = None
        a_name = ", ".join(os.path.basename(p) for role, p in self.window.scene.input_paths().items()
                           if p and role != "cloud") or "loaded skeleton"
        self.open(ev_a, result, (a_name, b_name))

    def open(self, ev_a: Any, ev_b: Any, names: tuple[str, str], thresholds: Any = "window",
             context: str = "") -> CompareWindow:
        """The A/B window; ``thresholds`` "window" (the main window's beta*, c*), None (A's own
        parameters, e.g. a compare run's) or a (beta*, c*) pair."""
        scene = self.window.scene
        if thresholds == "window":
            thresholds = (scene.beta_star, scene.c_star)
        view = CompareWindow(ev_a, ev_b, names, metric=scene.metric, thresholds=thresholds, context=context)
        view.fit_to_screen(self.window.widget.screen())  # the main window's screen
        view.show()
        self.views = [v for v in self.views if v.isVisible()]
        self.views.append(view)
        return view
