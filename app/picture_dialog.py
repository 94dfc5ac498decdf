"""File > Save picture: one dialog for the file, the scale factor, the background (white, black or
transparent) and whether the colour bar is drawn (the screenshot's options, as ``skelscope
--screenshot`` takes them: ``--scale``, ``--background``, ``--no-colour-bar``)."""

from __future__ import annotations

import os
from dataclasses import dataclass

from PySide6 import QtWidgets

__all__ = ["PictureOptions", "PictureDialog", "BACKGROUND_CHOICES"]

BACKGROUND_CHOICES = (("white", "white"), ("black (white text)", "black"), ("transparent (PNG alpha)", "transparent"))
"""(label, ``SceneView.image``'s ``background``)"""


@dataclass(frozen=True)
class PictureOptions:
    path: str
    scale: int = 2
    background: str = "white"
    colour_bar: bool = True

    @property
    def transparent(self) -> bool:
        return self.background == "transparent"


class PictureDialog(QtWidgets.QDialog):
    def __init__(self, parent: QtWidgets.QWidget | None, default_path: str, size: tuple[int, int] = (0, 0)) -> None:
        super().__init__(parent)
        self.setWindowTitle("Save picture of the 3D view")
        self._size = size
        self.path = QtWidgets.QLineEdit(default_path, self)
        browse = QtWidgets.QPushButton("…", self)
        browse.clicked.connect(self._browse)
        row = QtWidgets.QHBoxLayout()
        row.addWidget(self.path, 1)
        row.addWidget(browse)
        self.scale = QtWidgets.QSpinBox(self)
        self.scale.setRange(1, 8)
        self.scale.setValue(2)
        self.scale.setToolTip("the picture is this many times the view's size; points, lines and text grow with it")
        self.scale.valueChanged.connect(self._show_size)
        self.pixels = QtWidgets.QLabel(self)
        scale_row = QtWidgets.QHBoxLayout()
        scale_row.addWidget(self.scale)
        scale_row.addWidget(self.pixels, 1)
        self.background = QtWidgets.QComboBox(self)
        for text, key in BACKGROUND_CHOICES:
            self.background.addItem(text, key)
        self.background.setToolTip("on black, the colour bar's and the axes' text turns white")
        self.colour_bar = QtWidgets.QCheckBox("with the colour bar", self)
        self.colour_bar.setChecked(True)
        form = QtWidgets.QFormLayout()
        form.addRow("file", row)
        form.addRow("scale", scale_row)
        form.addRow("background", self.background)
        form.addRow("", self.colour_bar)
        buttons = QtWidgets.QDialogButtonBox(
            QtWidgets.QDialogButtonBox.StandardButton.Save | QtWidgets.QDialogButtonBox.StandardButton.Cancel, self)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(form)
        layout.addWidget(buttons)
        self._show_size()

    def _show_size(self) -> None:
        w, h = self._size
        self.pixels.setText(f"{w * self.scale.value()} x {h * self.scale.value()} pixels" if w and h else "")

    def _browse(self) -> None:
        # The overwrite question comes once, from the window, for whatever path is finally chosen.
        path, _ = QtWidgets.QFileDialog.getSaveFileName(
            self, "Save picture", self.path.text(), "PNG (*.png)",
            options=QtWidgets.QFileDialog.Option.DontConfirmOverwrite)
        if path:
            self.path.setText(path)

    def set_background(self, key: str) -> None:
        index = self.background.findData(key)
        if index < 0:
            raise ValueError(f"unknown background {key!r}")
        self.background.setCurrentIndex(index)

    def options(self) -> PictureOptions:
        path = os.path.expanduser(self.path.text().strip())
        if path and not path.lower().endswith(".png"):
            path += ".png"
        return PictureOptions(path, int(self.scale.value()), str(self.background.currentData()),
                              self.colour_bar.isChecked())
