"""Evaluation parameters (a subset of skelcore's Params, docs/metrics.md 0-4) the user may change before a run,
the correspondence of a skeletal set with another point count than the cloud (docs/metrics.md 5.1), and the real-scan
options of ``skelcore.evaluate`` (docs/metrics.md 6.2 and 6.4: ``cap_openings``, ``remove_outliers``),
which the ``open_surface`` and ``outliers`` warnings name."""

from __future__ import annotations

from PySide6 import QtCore, QtGui, QtWidgets

from skelcore.params import Params

#: (label, skelcore.evaluate's ``correspondence=``)
CORRESPONDENCE_CHOICES = (
    ("as loaded (pointwise / none)", "auto"),  # with an index file: through it (see the tooltip)
    ("reverse projection", "reverse"),
)


class ElidingComboBox(QtWidgets.QComboBox):
    """A combo box that ends its text with "…" when it is narrower than its text (a plain one cuts it)."""

    def paintEvent(self, event: QtGui.QPaintEvent) -> None:  # noqa: N802
        painter = QtWidgets.QStylePainter(self)
        opt = QtWidgets.QStyleOptionComboBox()
        self.initStyleOption(opt)
        opt.currentText = self.shown_text()
        painter.drawComplexControl(QtWidgets.QStyle.ComplexControl.CC_ComboBox, opt)
        painter.drawControl(QtWidgets.QStyle.ControlElement.CE_ComboBoxLabel, opt)

    def shown_text(self) -> str:
        """The text as drawn (elided to the edit field's width)."""
        opt = QtWidgets.QStyleOptionComboBox()
        self.initStyleOption(opt)
        field = self.style().subControlRect(QtWidgets.QStyle.ComplexControl.CC_ComboBox, opt,
                                            QtWidgets.QStyle.SubControl.SC_ComboBoxEditField, self)
        return self.fontMetrics().elidedText(self.currentText(), QtCore.Qt.TextElideMode.ElideRight, field.width())


def fit_combo(combo: QtWidgets.QComboBox, least: int = 10) -> None:
    """Let ``combo`` narrow to ``least`` characters (an :class:`ElidingComboBox` then elides its text)
    and give each choice's full text in its tooltip (the combo's own tooltip starts with the current
    choice)."""
    combo.setSizeAdjustPolicy(QtWidgets.QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
    combo.setMinimumContentsLength(least)
    base = combo.toolTip()
    for i in range(combo.count()):
        combo.setItemData(i, combo.itemText(i), QtCore.Qt.ItemDataRole.ToolTipRole)

    def tip(text: str) -> None:
        combo.setToolTip(f"{text}: {base}" if base else text)

    combo.currentTextChanged.connect(tip)
    tip(combo.currentText())


class SettingsPanel(QtWidgets.QWidget):
    changed = QtCore.Signal()

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        d = Params()
        self.boundedness_method = ElidingComboBox(self)
        self.boundedness_method.addItems(["rays", "paper"])
        self.boundedness_method.setToolTip("docs/metrics.md 2: 'rays' (rotation invariant) or 'paper' (the reference tool)")
        self.normalize_by = ElidingComboBox(self)
        self.normalize_by.addItems(["longest_side", "diagonal"])
        self.normalize_by.setToolTip("docs/metrics.md 0: the bounding-box measure scaled to 1.6")
        self.k_center = self._int(0, 10000, 0, "neighbours for skeletal centeredness; 0 = auto (docs/metrics.md 3)")
        self.k_center.setSpecialValueText("auto")
        self.tangent_k = self._int(1, 1000, d.tangent_k, "neighbours for PCA tangents (docs/metrics.md 4)")
        self.smooth_k = self._int(1, 1000, d.smooth_k, "neighbours compared for smoothness (docs/metrics.md 4)")
        self.curve_samples = self._int(1, 1_000_000, d.curve_samples, "samples S along the curve (docs/metrics.md 3)")
        self.eps_quantile = QtWidgets.QDoubleSpinBox(self)
        self.eps_quantile.setRange(0.01, 1.0)
        self.eps_quantile.setDecimals(3)
        self.eps_quantile.setSingleStep(0.01)
        self.eps_quantile.setValue(d.eps_quantile)
        self.eps_quantile.setToolTip("docs/metrics.md 1: quantile of nearest-neighbour distances giving eps*")
        self.correspondence_choice = ElidingComboBox(self)
        for text, key in CORRESPONDENCE_CHOICES:
            self.correspondence_choice.addItem(text, key)
        self.correspondence_choice.setToolTip(
            "docs/metrics.md 5.1: a skeletal set with another point count than the cloud has no row-by-row "
            "correspondence. 'reverse' maps every cloud point to its nearest skeletal point (with only "
            "a curve: its nearest point on the curve) and scores topology and centeredness on that set; "
            "'as loaded' uses the set's index file (File > Open skeletal index…) or, without one, leaves "
            "them out, with a warning"
        )
        self.remove_outliers = QtWidgets.QCheckBox("evaluate without stray points", self)
        self.remove_outliers.setToolTip(
            "docs/metrics.md 6.4: leave out the cloud's stray points (they fail both the radius and the statistical "
            "test) and their skeletal rows; they are found and reported (the outliers warning) either way")
        self.cap_openings = QtWidgets.QCheckBox("close small flat openings", self)
        self.cap_openings.setToolTip(
            "docs/metrics.md 6.2: close the cloud's small flat openings with points on their planes for "
            "boundedness, as the paper did for its cave (the open_surface warning)")
        form = QtWidgets.QFormLayout(self)
        # a narrow dock (a small screen, a large scale factor): each value under its label, never cut off
        form.setRowWrapPolicy(QtWidgets.QFormLayout.RowWrapPolicy.WrapLongRows)
        for combo in (self.correspondence_choice, self.boundedness_method, self.normalize_by):
            fit_combo(combo)
        form.addRow("correspondence", self.correspondence_choice)
        form.addRow("boundedness estimator", self.boundedness_method)
        form.addRow("normalization", self.normalize_by)
        form.addRow("k (centeredness)", self.k_center)
        form.addRow("k (tangents)", self.tangent_k)
        form.addRow("k (smoothness)", self.smooth_k)
        form.addRow("curve samples", self.curve_samples)
        form.addRow("eps* quantile", self.eps_quantile)
        form.addRow("stray points", self.remove_outliers)
        form.addRow("openings", self.cap_openings)
        for box in (self.remove_outliers, self.cap_openings):
            box.toggled.connect(lambda *_: self.changed.emit())
        for w in (self.boundedness_method, self.normalize_by, self.correspondence_choice):
            w.currentTextChanged.connect(lambda *_: self.changed.emit())
        for w in (self.k_center, self.tangent_k, self.smooth_k, self.curve_samples, self.eps_quantile):
            w.valueChanged.connect(lambda *_: self.changed.emit())

    def _int(self, lo: int, hi: int, value: int, tip: str) -> QtWidgets.QSpinBox:
        spin = QtWidgets.QSpinBox(self)
        spin.setRange(lo, hi)
        spin.setValue(value)
        spin.setToolTip(tip)
        return spin

    def correspondence(self) -> str:
        """``correspondence=`` for :func:`skelcore.evaluate`: "auto" or "reverse"."""
        return str(self.correspondence_choice.currentData())

    def set_correspondence(self, key: str) -> None:
        index = self.correspondence_choice.findData(key)
        if index < 0:
            raise ValueError(f"unknown correspondence {key!r}")
        self.correspondence_choice.setCurrentIndex(index)

    def scan_options(self) -> dict[str, bool]:
        """``remove_outliers=`` and ``cap_openings=`` for :func:`skelcore.evaluate`."""
        return {"remove_outliers": self.remove_outliers.isChecked(), "cap_openings": self.cap_openings.isChecked()}

    def set_scan_options(self, remove_outliers: bool = False, cap_openings: bool = False) -> None:
        self.remove_outliers.setChecked(bool(remove_outliers))
        self.cap_openings.setChecked(bool(cap_openings))

    def params(self, base: Params | None = None) -> Params:
        """The chosen parameters on top of ``base`` (thresholds are set in the summary panel). On the
        defaults, the same (frozen) object while the choices stay: the window asks for them several
        times per edit, and each validated copy costs about a millisecond (docs/performance.md 6.10)."""
        chosen = dict(
            boundedness_method=self.boundedness_method.currentText(),
            normalize_by=self.normalize_by.currentText(),
            k_center=None if self.k_center.value() == 0 else self.k_center.value(),
            tangent_k=self.tangent_k.value(),
            smooth_k=self.smooth_k.value(),
            curve_samples=self.curve_samples.value(),
            eps_quantile=self.eps_quantile.value(),
        )
        if base is not None:
            return base.replace(**chosen)
        made = getattr(self, "_made", None)
        if made is None or made[0] != chosen:
            made = self._made = (chosen, Params().replace(**chosen))
        return made[1]

    def set_params(self, params: Params) -> None:
        self.boundedness_method.setCurrentText(params.boundedness_method)
        self.normalize_by.setCurrentText(params.normalize_by)
        self.k_center.setValue(0 if params.k_center is None else int(params.k_center))
        self.tangent_k.setValue(params.tangent_k)
        self.smooth_k.setValue(params.smooth_k)
        self.curve_samples.setValue(params.curve_samples)
        self.eps_quantile.setValue(params.eps_quantile)
