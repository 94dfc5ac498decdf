"""Plain-text description of one picked skeleton element, for the pick panel and the status bar.

It formats the dict :meth:`app.scene.model.Scene.element_info` returns; no Qt, so it is testable alone.
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["format_element_info"]


def format_element_info(info: dict[str, Any]) -> str:
    """Plain-text rendering of :meth:`Scene.element_info` (pick panel and status bar)."""
    x, y, z = info["xyz"]
    lines = [f"{info['element']} #{info['index']}", f"x = {x:.6g}, y = {y:.6g}, z = {z:.6g}"]
    if "degree" in info:
        lines.append(f"degree = {info['degree']}")
    if "edge" in info:
        lines.append(f"edge = {info['edge']}, t = {info['t']:.3f}")
    for name, value in info["values"].items():
        lines.append(f"{name} = {'nan (invalid)' if not math.isfinite(value) else f'{value:.4f}'}")
    if not info["values"]:
        lines.append("no local values (run an evaluation)")
    return "\n".join(lines)
