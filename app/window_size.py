"""A top-level window's first size: its default shrunk to the free area of the screen it opens on, so
the main window and the A/B view fit a 1366 x 768 laptop screen (docs/guide/viewer.md)."""

from __future__ import annotations

from PySide6 import QtCore

DEFAULT_SIZE = (1500, 950)
FRAME_ALLOWANCE = (16, 48)
"""Room left on the screen for a window manager's frame and title bar (device-independent pixels)."""


def initial_size(available: QtCore.QSize, default: tuple[int, int] = DEFAULT_SIZE) -> tuple[int, int]:
    """The window's first size: ``default`` (DEFAULT_SIZE), shrunk to the screen's free area (minus a frame)."""
    return (max(200, min(default[0], available.width() - FRAME_ALLOWANCE[0])),
            max(200, min(default[1], available.height() - FRAME_ALLOWANCE[1])))
