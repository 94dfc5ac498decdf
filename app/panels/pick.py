"""Shows the picked skeleton element: index, coordinates and every local value."""

from __future__ import annotations

from typing import Any

from PySide6 import QtWidgets

from ..scene import format_element_info


class PickPanel(QtWidgets.QWidget):
    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.text = QtWidgets.QPlainTextEdit(self)
        self.text.setReadOnly(True)
        self.text.setMaximumHeight(180)  # a curve pick adds its branch (three lines)
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(2, 2, 2, 2)
        layout.addWidget(self.text)
        self.show_info(None)

    def show_info(self, info: dict[str, Any] | None) -> None:
        self.info = info
        if info is None:
            self.text.setPlainText("Click a skeletal point, curve vertex or curve sample to see its values.")
        else:
            self.text.setPlainText(format_element_info(info))
