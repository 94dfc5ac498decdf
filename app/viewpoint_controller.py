"""The scan's viewpoint in the window: Evaluate > "Viewpoint from the camera" takes the
3-D view's camera position as the sensor's, "Viewpoint…" types one or more (x y z; several separated by
";"), "Clear viewpoints" goes back to the paper's scores. The session passes them to the engine's
``viewpoints=`` (viewpoint-aware boundedness and centeredness, docs/metrics.md 6) at the next
evaluation; until then the shown results are marked stale. Saved in sessions (:mod:`skelscope.saved_sessions`).
A feature controller on :class:`skelscope.window_api.WindowApi`.
"""

from __future__ import annotations

import math

from PySide6 import QtCore, QtWidgets

from .window_api import ActionSpec, WindowApi

__all__ = ["ViewpointController", "parse_viewpoints", "format_viewpoints"]


def parse_viewpoints(text: str) -> list[tuple[float, float, float]]:
    """"x y z" or "x y z; x y z; ..." (commas allowed between numbers) -> positions; "" -> [] (none).
    ValueError with one line saying what is wrong."""
    out = []
    for part in (p.strip() for p in text.replace("\n", ";").split(";")):
        if not part:
            continue
        fields = part.replace(",", " ").split()
        try:
            xyz = tuple(float(f) for f in fields)
        except ValueError:
            raise ValueError(f"{part!r}: a viewpoint is three numbers x y z") from None
        if len(xyz) != 3 or not all(math.isfinite(v) for v in xyz):
            raise ValueError(f"{part!r}: a viewpoint is three finite numbers x y z")
        out.append(xyz)
    return out


def format_viewpoints(points: list[tuple[float, float, float]]) -> str:
    return "; ".join(" ".join(f"{v:.6g}" for v in p) for p in points)


class ViewpointController(QtCore.QObject):
    def __init__(self, window: WindowApi) -> None:
        super().__init__(window.widget)
        self.window = window
        has_cloud = lambda: window.scene.cloud is not None  # noqa: E731
        window.add_action(ActionSpec("viewpoint_camera", "Viewpoint from the camera", "evaluate.run",
                                     self.from_camera, enabled=has_cloud))
        window.add_action(ActionSpec("viewpoint_typed", "Viewpoint…", "evaluate.run", self.dialog, enabled=has_cloud))
        window.add_action(ActionSpec("viewpoint_clear", "Clear viewpoints", "evaluate.run", self.clear,
                                     enabled=lambda: bool(window.session.viewpoints)))

    def from_camera(self) -> tuple[float, float, float]:
        """The 3-D view's camera position becomes the one viewpoint."""
        position = tuple(float(v) for v in self.window.view.camera_state()["position"])
        self.window.session.set_viewpoints([position])
        return position  # type: ignore[return-value]

    def set_text(self, text: str) -> bool:
        """Viewpoints typed as text (:func:`parse_viewpoints`); an error dialog and False when it does not parse."""
        try:
            points = parse_viewpoints(text)
        except ValueError as exc:
            self.window.show_error("Viewpoint", str(exc))
            return False
        self.window.session.set_viewpoints(points)
        return True

    def dialog(self) -> None:
        text, ok = QtWidgets.QInputDialog.getText(
            self.window.widget, "Viewpoint",
            "Sensor position(s) in the cloud's units: x y z, several separated by ';' (empty: none)",
            text=format_viewpoints(self.window.session.viewpoints))
        if ok:
            self.set_text(text)

    def clear(self) -> None:
        self.window.session.set_viewpoints([])
