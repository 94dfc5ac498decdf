"""Where a picture can go: into a Jupyter notebook, into a window, or only into a file.

Nothing is imported to find out: a notebook kernel has imported IPython already, and a window needs
a display server (``DISPLAY`` / ``WAYLAND_DISPLAY`` on Linux; macOS and Windows always have one).
"""

from __future__ import annotations

import os
import sys

__all__ = ["in_notebook", "has_display"]


def in_notebook() -> bool:
    """True inside a Jupyter kernel (an IPython shell with a kernel), False in a script or a terminal IPython."""
    ipython = sys.modules.get("IPython")
    if ipython is None:
        return False
    try:
        shell = ipython.get_ipython()
    except Exception:  # noqa: BLE001 - an IPython without a shell is no notebook
        return False
    return shell is not None and getattr(shell, "kernel", None) is not None


def has_display() -> bool:
    """True when a window can be opened."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
