"""Evaluate > Map skeleton into the cloud's frame…: a scale and an offset applied to the loaded
skeleton layers, ``v * scale + offset`` (:mod:`skelcore.skeleton_mapping`, the map the CLI's
``--skeleton-scale`` / ``--skeleton-offset`` apply), filled in with a ``frame`` warning's suggestion.
The window's own remedy for skeletons written in another tool's units or origin."""

from __future__ import annotations

from typing import Any

from PySide6 import QtWidgets

__all__ = ["MapSkeletonDialog", "suggested_mapping"]


def suggested_mapping(evaluation: Any) -> tuple[float, tuple[float, float, float]] | None:
    """The ``(scale, offset)`` the shown evaluation's first frame warning suggests, if any."""
    for w in getattr(evaluation, "warnings", None) or []:
        mapping = getattr(w, "mapping", None)
        if mapping is not None:
            return mapping
    return None


class MapSkeletonDialog(QtWidgets.QDialog):
    def __init__(self, parent: QtWidgets.QWidget | None = None,
                 mapping: tuple[float, tuple[float, float, float]] | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Map skeleton into the cloud's frame")
        scale, offset = mapping or (1.0, (0.0, 0.0, 0.0))
        self.scale = self._number(scale, 1e-12, 1e12)
        self.offset = [self._number(v, -1e12, 1e12) for v in offset]
        form = QtWidgets.QFormLayout(self)
        note = QtWidgets.QLabel("Every skeletal point and curve vertex becomes v × scale + offset."
                                + (" Filled in with the frame warning's suggestion." if mapping else ""))
        note.setWordWrap(True)
        form.addRow(note)
        form.addRow("scale", self.scale)
        for axis, box in zip("xyz", self.offset):
            form.addRow(f"offset {axis}", box)
        buttons = QtWidgets.QDialogButtonBox(
            QtWidgets.QDialogButtonBox.StandardButton.Ok | QtWidgets.QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        form.addRow(buttons)

    def _number(self, value: float, lo: float, hi: float) -> QtWidgets.QDoubleSpinBox:
        box = QtWidgets.QDoubleSpinBox(self)
        box.setDecimals(6)
        box.setRange(lo, hi)
        box.setValue(float(value))
        return box

    def mapping(self) -> tuple[float, tuple[float, float, float]]:
        return float(self.scale.value()), tuple(float(b.value()) for b in self.offset)  # type: ignore[return-value]
