"""The summary table in the paper's layout (rows d_B/d_Wp, boundedness, centeredness, smoothness;
columns skeletal points / curve skeleton), each score with the number of elements it counted (docs/metrics.md 5.5),
SkelScope's coverage row (docs/metrics.md 5.2, marked as not the paper's), the editable thresholds beta*, c*
(docs/metrics.md 2-3) that re-score without recomputing, and below: the correspondence used (docs/metrics.md 5.1), the trust
warnings, the reference comparison (docs/metrics.md 5.3), and a switch colouring the cloud by its coverage gap."""

from __future__ import annotations

import html
from typing import Any

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from skelcore.params import Params
from skelcore.scores import Scores, paper_table

COLUMNS = ("skeletal points", "curve skeleton")
#: the panel's cells (em dash where not computed, counts spaced and in thousands: "n = 4,687")
_STYLE = {"missing": "—", "sep": "  ", "count": "n = {:,}"}
ROWS = tuple(row for row, _s, _c in paper_table(None, **_STYLE))


def summary_cells(summary: Scores | dict[str, Any] | None, evaluation: Any = None) -> list[list[str]]:
    """The table's text, row by row (Qt-free so it can be tested and reused), from a :class:`Scores`
    or a ``summary()`` dict. Under reverse projection the skeletal centeredness counts cloud rows (the
    pointwise set skel[rows] x cloud, docs/metrics.md 5.1), the other scores skeletal points: its cell says both."""
    if summary is not None and not isinstance(summary, Scores):
        summary = Scores.from_json_dict(summary)
    cells = [[a, b] for _row, a, b in paper_table(summary, **_STYLE)]
    sk = getattr(evaluation, "skeletal", None)
    if summary is not None and getattr(evaluation, "correspondence", None) == "reverse" and sk is not None \
            and sk.rows is not None and summary.n_centeredness_skeletal:
        r = ROWS.index("centeredness")
        n_points = len(np.unique(sk.rows))
        cells[r][0] = (f"{summary.text('centeredness_skeletal')}  (n = {summary.n_centeredness_skeletal:,} cloud rows "
                       f"on {n_points:,} of {len(sk.points):,} skeletal points)")
    return cells


def cell_lines(text: str) -> str:
    """A cell as the panel shows it: the value, then its count on a line of its own
    ("1.000  (n = 4,000)" -> "1.000" / "(n = 4,000)"); a column too narrow for the count breaks it
    after the "=" ("(n =" / "4,000)"), never inside the number, which the table never elides."""
    value, sep, rest = text.partition("  (")
    if not sep:
        return text
    return value + "\n(" + rest.replace(" = ", "\u202f= ")


def window_warning(w: Any) -> str:
    """A trust warning in the window's terms: its finding and the menu or setting that remedies it
    (the engine's message names the command line's flags)."""
    finding = getattr(w, "finding", "") or w.message
    if w.code == "no_correspondence":
        return (f"{finding}: choose Settings > correspondence > reverse projection, or give its index with "
                "File > Open skeletal index… (one cloud row per skeletal point), then re-run (F5)")
    if w.code in ("frame", "collapse") and "--skeleton-scale" in w.message:
        mapping = getattr(w, "mapping", None)
        remedy = "Evaluate > Map skeleton into the cloud's frame…"
        if mapping is not None:
            s, off = mapping
            remedy += f" (suggested: scale {s:.6g}, offset {off[0]:.6g} {off[1]:.6g} {off[2]:.6g})"
        return f"{finding}; map it with {remedy}" if w.code == "frame" else \
            f"{finding} (or, if it is in other units, map it with {remedy})"
    return _window_terms(w.message)


def _window_terms(text: str) -> str:
    """Command-line flags in a stored message (an evaluation read back from a file) in window terms."""
    import re

    text = text.replace("left out by Evaluation.update(diagnostics=False)",
                        "updating… (an edit's defects follow its scores)")
    text = re.sub(r"give --skeletal-index F or --correspondence reverse",
                  "choose Settings > correspondence > reverse projection, or File > Open skeletal index…", text)
    text = re.sub(r"map it with --skeleton-scale S --skeleton-offset X Y Z",
                  "map it with Evaluate > Map skeleton into the cloud's frame…", text)
    text = re.sub(r"--skeleton-scale ([-+0-9.eE]+)", r"scale \1", text)
    text = re.sub(r"--skeleton-offset ([-+0-9.eE]+) ([-+0-9.eE]+) ([-+0-9.eE]+)", r"offset \1 \2 \3", text)
    text = text.replace("--remove-outliers evaluates without them",
                        "Settings > stray points > evaluate without stray points leaves them out (F5 re-runs)")
    text = text.replace("give the sensor position with --viewpoint X Y Z, or close small flat openings with "
                        "--cap-openings",
                        "give the sensor position with Evaluate > Viewpoint from the camera or Viewpoint…, or "
                        "close small flat openings with Settings > openings (F5 re-runs)")
    return text.replace("; raise it with --set coverage_max_points=N)", ")")


def detail_lines(summary: Scores | dict[str, Any] | None, evaluation: Any) -> list[str]:
    """The text under the table (Qt-free): correspondence, warnings, reference, run facts."""
    if summary is None or evaluation is None:
        return []
    s = evaluation.scores()  # what these lines show does not depend on the thresholds
    lines = []
    corr = getattr(evaluation, "correspondence", None)
    if corr is not None:
        source = getattr(evaluation.skeletal, "source", "skeletal") if evaluation.skeletal is not None else ""
        extra = " (the cloud projected onto the curve)" if source == "curve" else ""
        lines.append(f"correspondence: {corr}{extra}")
    for what, why in (getattr(evaluation, "not_computed", None) or {}).items():
        lines.append(f"not computed: {what}: {_window_terms(why)}")
    for w in getattr(evaluation, "warnings", None) or []:
        lines.append(f"⚠ warning [{w.code}]: {window_warning(w)}")
    if s.reference_chamfer is not None:
        lines.append(
            f"reference curve: chamfer {s.text('reference_chamfer')}, Hausdorff {s.text('reference_hausdorff')}, "
            f"precision {s.text('reference_precision')}, recall {s.text('reference_recall')}, F1 {s.text('reference_f1')}"
        )
        lines.append("  ours / reference: " + ", ".join(
            f"{k} {getattr(s, f'reference_{k}')[0]}/{getattr(s, f'reference_{k}')[1]}"
            for k in ("junctions", "endpoints", "components", "cycles")
        ))
    if s.coverage_skeletal is not None or s.coverage_curve is not None:
        lines.append(f"* coverage is SkelScope's own, not the paper's: covered fraction (s = {s.coverage_slack:g}, "
                     f"tau = {s.text('coverage_tau')}), mean / max gap in normalized units")
    lines.append(f"boundedness estimator: {evaluation.params.boundedness_method}")
    if s.d_B is not None:
        lines.append(f"eps* = {s.text('eps_star')} (normalized units), K = {s.n_bars} bars compared")
    if s.seconds is not None:
        lines.append(f"evaluated in {s.seconds:.2f} s")
    return lines


def cloud_gap_values(evaluation: Any) -> tuple[np.ndarray, str] | None:
    """Per cloud point gap / max gap in [0, 1] (the skeletal set's balls when it has coverage, else
    the curve's; NaN where undefined, drawn magenta) and which one; None without coverage."""
    if evaluation is None:
        return None
    for kind in ("skeletal", "curve"):
        cov = getattr(evaluation, f"coverage_{kind}", None)
        if cov is not None:
            gap = np.asarray(cov.gap, dtype=float)
            top = float(np.nanmax(gap)) if np.isfinite(gap).any() else 0.0
            return (gap / top if top > 0 else np.where(np.isfinite(gap), 0.0, np.nan)), kind
    return None


GAP_TIP = ("each cloud point's distance to the union of the skeleton's medial balls, / the largest gap "
           "(0 = covered); magenta where undefined")
_GAP_OF = {"skeletal": "skeletal point set", "curve": "curve skeleton"}
NO_RESULT = "No evaluation yet: load a cloud and a skeleton, then Evaluate (F5)."


class SummaryPanel(QtWidgets.QWidget):
    thresholds_changed = QtCore.Signal(float, float)
    #: per cloud point values in [0, 1] to colour the cloud by (gap / max gap), or None for plain
    cloud_colouring = QtCore.Signal(object)
    rerun_requested = QtCore.Signal()

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.table = QtWidgets.QTableWidget(len(ROWS), len(COLUMNS), self)
        self.table.setHorizontalHeaderLabels([c.replace(" ", "\n") for c in COLUMNS])  # narrow columns
        self.table.setVerticalHeaderLabels(list(ROWS))
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.horizontalHeader().setSectionResizeMode(QtWidgets.QHeaderView.ResizeMode.Stretch)
        self.table.verticalHeader().setSectionResizeMode(QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        self.table.setVerticalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.table.setSizeAdjustPolicy(QtWidgets.QAbstractScrollArea.SizeAdjustPolicy.AdjustToContents)
        # a number is never cut: a cell wraps between its words, each row as tall as its wrapped text
        self.table.setWordWrap(True)
        self.table.setTextElideMode(QtCore.Qt.TextElideMode.ElideNone)
        defaults = Params()
        self.beta_star = self._spin("bounded means beta > beta* (docs/metrics.md 2)", defaults.beta_star)
        self.c_star = self._spin("centred means c > c* (docs/metrics.md 3)", defaults.c_star)
        self.details = QtWidgets.QLabel(NO_RESULT)
        self.details.setWordWrap(True)
        self.details.setTextInteractionFlags(QtCore.Qt.TextInteractionFlag.TextSelectableByMouse)
        self.cloud_by_gap = QtWidgets.QCheckBox("colour the cloud by coverage gap", self)
        self.cloud_by_gap.setToolTip(GAP_TIP)
        self.cloud_by_gap.setEnabled(False)
        self.cloud_by_gap.toggled.connect(self._emit_cloud_colouring)
        self._evaluation: Any = None
        self.no_result = NO_RESULT  # the line shown without a result (see set_no_result)
        # Shown while the results are out of date (see set_stale).
        self.rerun = QtWidgets.QPushButton("", self)
        self.rerun.setStyleSheet("QPushButton { color: #8a4b00; font-weight: bold; }")
        self.rerun.clicked.connect(self.rerun_requested.emit)
        self.rerun.setVisible(False)
        self.stale = ""
        form = QtWidgets.QFormLayout()
        form.addRow("beta* (boundedness)", self.beta_star)
        form.addRow("c* (centeredness)", self.c_star)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addWidget(self.table)
        layout.addWidget(self.rerun)
        layout.addLayout(form)
        layout.addWidget(self.cloud_by_gap)
        layout.addWidget(self.details)
        layout.addStretch(1)
        self.show_summary(None)

    def _spin(self, tip: str, value: float) -> QtWidgets.QDoubleSpinBox:
        spin = QtWidgets.QDoubleSpinBox(self)
        spin.setRange(0.0, 1.0)
        spin.setDecimals(3)
        spin.setSingleStep(0.05)
        spin.setValue(value)
        spin.setToolTip(tip)
        spin.setKeyboardTracking(False)
        spin.valueChanged.connect(self._emit_thresholds)
        return spin

    def _emit_thresholds(self, *_: Any) -> None:
        self.thresholds_changed.emit(self.beta_star.value(), self.c_star.value())

    def set_thresholds(self, beta_star: float, c_star: float) -> None:
        """Show thresholds (e.g. from a new evaluation's params) without re-emitting them."""
        for spin, value in ((self.beta_star, beta_star), (self.c_star, c_star)):
            spin.blockSignals(True)
            spin.setValue(float(value))
            spin.blockSignals(False)

    def show_summary(self, summary: dict[str, Any] | None, evaluation: Any = None) -> None:
        for r, row in enumerate(summary_cells(summary, evaluation)):
            for c, text in enumerate(row):
                item = QtWidgets.QTableWidgetItem(cell_lines(text))
                item.setData(QtCore.Qt.ItemDataRole.UserRole, text)
                item.setToolTip(text)
                item.setTextAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
                self.table.setItem(r, c, item)
        self._evaluation = evaluation
        gap = cloud_gap_values(evaluation)
        self.cloud_by_gap.setEnabled(gap is not None)
        if gap is not None:
            # which skeleton's gap in the tooltip: the box's text stays short enough for a narrow dock
            self.cloud_by_gap.setToolTip(f"{GAP_TIP} (the {_GAP_OF[gap[1]]}'s balls)")
        self._emit_cloud_colouring()
        self._grey(bool(self.stale))
        if summary is None or evaluation is None:
            # Nothing shown: no line may describe a run whose values are gone.
            self.details.setText(self.no_result)
            return
        lines = detail_lines(summary, evaluation)
        warned = [i for i, t in enumerate(lines) if t.startswith("⚠")]
        self.details.setTextFormat(QtCore.Qt.TextFormat.RichText)
        self.details.setText("<br>".join(
            f"<span style='color:#b35900'>{html.escape(t)}</span>" if i in warned else html.escape(t)
            for i, t in enumerate(lines)
        ))

    def set_no_result(self, text: str) -> None:
        """The line shown while there is no result: what is loaded, running or was cancelled, and how
        to get a result (the window words it)."""
        self.no_result = text
        if self._evaluation is None:
            self.details.setText(text)

    def details_text(self) -> str:
        """The text under the table, as plain lines."""
        return "\n".join(detail_lines(self._summary_for_text(), self._evaluation)) if self._evaluation else self.details.text()

    def _summary_for_text(self) -> dict[str, Any] | None:
        return None if self._evaluation is None else self._evaluation.summary()

    def _emit_cloud_colouring(self, *_: Any) -> None:
        gap = cloud_gap_values(self._evaluation) if self.cloud_by_gap.isChecked() else None
        self.cloud_colouring.emit(None if gap is None else gap[0])

    def set_stale(self, reason: str) -> None:
        """Mark the results out of date ("settings changed", "inputs changed"): values greyed, a
        re-run button naming the reason; "" clears the mark."""
        self.stale = reason
        self.rerun.setText(f"{reason}: re-run (F5)" if reason else "")
        self.rerun.setVisible(bool(reason))
        self._grey(bool(reason))

    def _grey(self, grey: bool) -> None:
        colour = self.palette().color(QtGui.QPalette.ColorGroup.Disabled, QtGui.QPalette.ColorRole.Text) if grey \
            else self.palette().color(QtGui.QPalette.ColorRole.Text)
        for r in range(self.table.rowCount()):
            for c in range(self.table.columnCount()):
                item = self.table.item(r, c)
                if item is not None:
                    item.setForeground(colour)
        self.details.setEnabled(not grey)

    def is_greyed(self) -> bool:
        item = self.table.item(1, 0)
        return item is not None and item.foreground().color() != self.palette().color(QtGui.QPalette.ColorRole.Text)

    def cell_text(self, row: str, column: str) -> str:
        item = self.table.item(ROWS.index(row), COLUMNS.index(column))
        return "" if item is None else str(item.data(QtCore.Qt.ItemDataRole.UserRole))
