"""Display controls: which metric colours the skeleton, the colour range, and each layer's
visibility, point size and opacity, a remove button per layer and a cloud <-> skeletal swap; edges as
lines or tubes; figure options (shaded spheres, eye-dome lighting, orientation axes). Everything goes
through the scene, except closing and swapping, which the session does (``layer_action``)."""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets

from ..scene import LAYER_ORDER, METRICS, Scene, SceneEvent

_LAYER_TITLES = {"cloud": "cloud", "skeletal": "skeletal points", "curve": "curve skeleton"}


_STYLE_TITLES = {"spheres": "points as shaded spheres", "eye_dome": "eye-dome lighting", "axes": "orientation axes"}


class DisplayPanel(QtWidgets.QWidget):
    layer_action = QtCore.Signal(str, str)  # ("close", role) or ("swap", "")

    def __init__(self, scene: Scene, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.scene = scene
        self.metric_box = QtWidgets.QComboBox(self)
        self.metric_box.addItems(list(METRICS))
        self.metric_box.currentTextChanged.connect(self._metric_changed)
        self.auto_range = QtWidgets.QCheckBox("[0, 1]", self)
        self.auto_range.setToolTip("Every metric lies in [0, 1]; untick to choose the colour range")
        self.auto_range.setChecked(True)
        self.vmin = self._range_spin(0.0)
        self.vmax = self._range_spin(1.0)
        self.fit_range = QtWidgets.QPushButton("fit", self)
        self.fit_range.setToolTip("fit the colour range to the shown values")
        self.fit_range.clicked.connect(self._fit_range)
        # as narrow as its word (a push button's least width is wider): the range row fits a narrow dock
        self.fit_range.setMaximumWidth(self.fit_range.fontMetrics().horizontalAdvance(" fit ") + 14)
        self.auto_range.toggled.connect(self._range_changed)
        range_row = QtWidgets.QHBoxLayout()
        range_row.setSpacing(3)
        for w in (self.auto_range, self.vmin, self.vmax, self.fit_range):
            range_row.addWidget(w)
        self.tubes = QtWidgets.QCheckBox("edges as tubes (T)", self)
        self.tubes.toggled.connect(scene.set_edges_as_tubes)
        self.style: dict[str, QtWidgets.QCheckBox] = {}
        for name, title in _STYLE_TITLES.items():
            box = QtWidgets.QCheckBox(title, self)
            box.setChecked(scene.style[name])
            box.toggled.connect(lambda on, n=name: scene.set_style(n, on))
            self.style[name] = box

        grid = QtWidgets.QGridLayout()
        grid.setHorizontalSpacing(4)  # the rows fit a narrow dock
        grid.addWidget(QtWidgets.QLabel("layer"), 0, 0)
        grid.addWidget(QtWidgets.QLabel("size"), 0, 1)
        grid.addWidget(QtWidgets.QLabel("opacity"), 0, 2)
        self.visible: dict[str, QtWidgets.QCheckBox] = {}
        self.size: dict[str, QtWidgets.QDoubleSpinBox] = {}
        self.opacity: dict[str, QtWidgets.QSlider] = {}
        self.remove: dict[str, QtWidgets.QToolButton] = {}
        for row, name in enumerate(LAYER_ORDER, start=1):
            box = QtWidgets.QCheckBox(_LAYER_TITLES[name], self)
            box.setChecked(True)
            box.toggled.connect(lambda on, n=name: scene.set_visible(n, on))
            size = QtWidgets.QDoubleSpinBox(self)
            size.setRange(1.0, 30.0)
            size.setDecimals(0)
            size.setMaximumWidth(56)
            size.valueChanged.connect(lambda v, n=name: scene.set_point_size(n, v))
            opacity = QtWidgets.QSlider(QtCore.Qt.Orientation.Horizontal, self)
            opacity.setRange(0, 100)
            opacity.valueChanged.connect(lambda v, n=name: scene.set_opacity(n, v / 100.0))
            remove = QtWidgets.QToolButton(self)
            remove.setText("✕")
            remove.setToolTip(f"close the {_LAYER_TITLES[name]} (File > Close)")
            remove.clicked.connect(lambda _=False, n=name: self.layer_action.emit("close", n))
            grid.addWidget(box, row, 0)
            grid.addWidget(size, row, 1)
            grid.addWidget(opacity, row, 2)
            grid.addWidget(remove, row, 3)
            self.visible[name], self.size[name], self.opacity[name] = box, size, opacity
            self.remove[name] = remove
        self.swap = QtWidgets.QPushButton("swap roles: cloud ↔ skeletal points", self)
        self.swap.setToolTip("the cloud becomes the skeletal point set and the skeletal point set the cloud")
        self.swap.clicked.connect(lambda: self.layer_action.emit("swap", ""))

        form = QtWidgets.QFormLayout()
        form.setRowWrapPolicy(QtWidgets.QFormLayout.RowWrapPolicy.WrapLongRows)  # a narrow dock: rows wrap
        form.addRow("colour by", self.metric_box)
        form.addRow("range", range_row)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(form)
        layout.addLayout(grid)
        layout.addWidget(self.swap)
        layout.addWidget(self.tubes)
        for box in self.style.values():
            layout.addWidget(box)
        self.invalid = QtWidgets.QLabel(self)
        self.invalid.setWordWrap(True)
        layout.addWidget(self.invalid)
        layout.addStretch(1)
        scene.subscribe(self._on_scene)
        self._sync()

    def add_option(self, widget: QtWidgets.QWidget) -> None:
        """A control added by a feature (e.g. the support filter), below the others, above the stretch."""
        layout = self.layout()
        layout.insertWidget(layout.count() - 1, widget)

    def _range_spin(self, value: float) -> QtWidgets.QDoubleSpinBox:
        spin = QtWidgets.QDoubleSpinBox(self)
        spin.setRange(-1e6, 1e6)
        spin.setDecimals(3)
        spin.setSingleStep(0.05)
        spin.setValue(value)
        spin.setKeyboardTracking(False)
        spin.setMaximumWidth(self.fontMetrics().horizontalAdvance("0.000") + 26)  # "0.000" and the arrows
        spin.valueChanged.connect(self._range_changed)
        return spin

    def _metric_changed(self, metric: str) -> None:
        if metric and metric != self.scene.metric:
            self.scene.set_metric(metric)

    def _range_changed(self, *_: object) -> None:
        auto = self.auto_range.isChecked()
        self.vmin.setEnabled(not auto)
        self.vmax.setEnabled(not auto)
        if auto:
            self.scene.set_clim(None)
        elif self.vmin.value() < self.vmax.value():
            self.scene.set_clim((self.vmin.value(), self.vmax.value()))

    def _fit_range(self) -> None:
        r = self.scene.data_range()
        if r is None or not r[0] < r[1]:
            return
        for spin, v in ((self.vmin, r[0]), (self.vmax, r[1])):
            spin.blockSignals(True)
            spin.setValue(v)
            spin.blockSignals(False)
        self.auto_range.blockSignals(True)
        self.auto_range.setChecked(False)
        self.auto_range.blockSignals(False)
        self._range_changed()

    def _on_scene(self, event: SceneEvent) -> None:
        if event.kind in ("layer", "quantities", "colouring", "thresholds", "display", "style"):
            self._sync()

    def _sync(self) -> None:
        """Reflect the scene in the widgets without feeding changes back."""
        s = self.scene
        self.metric_box.blockSignals(True)
        self.metric_box.setCurrentText(s.metric)
        self.metric_box.blockSignals(False)
        for name in LAYER_ORDER:
            layer = s.layers.get(name)
            widgets = (self.visible[name], self.size[name], self.opacity[name], self.remove[name])
            for w in widgets:
                w.setEnabled(layer is not None)
                w.blockSignals(True)
            if layer is not None:
                self.visible[name].setChecked(layer.visible)
                self.size[name].setValue(layer.point_size)
                self.opacity[name].setValue(int(round(layer.opacity * 100)))
            for w in widgets:
                w.blockSignals(False)
        self.tubes.setEnabled(s.curve is not None)
        self.swap.setEnabled(s.cloud is not None or s.skeletal is not None)
        for box, on in [(self.tubes, s.edges_as_tubes), *((self.style[n], s.style[n]) for n in self.style)]:
            box.blockSignals(True)
            box.setChecked(on)
            box.blockSignals(False)
        n = s.n_invalid_shown()
        self.invalid.setText(
            f"{n} invalid (NaN) {s.metric} values, drawn magenta" if n else ""
        )
