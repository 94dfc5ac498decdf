"""Plain-text description of one picked skeleton element, for the pick panel and the status bar.

It formats the dict :meth:`skelscope.scene.model.Scene.element_info` returns; no Qt, so it is testable alone.
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
    b = info.get("branch")
    if b is not None:
        r = b["radius"]
        lines.append(f"branch #{b['branch']} ({b['kind']}, {b['n_vertices']} vertices): length {b['length']:.4g}, "
                     f"local radius {_num(r.get('median'))} (min {_num(r.get('min'))}, max {_num(r.get('max'))})")
        lines.append("  means along it: " + ", ".join(f"{k} {_num(v, 4)}" for k, v in b["means"].items()))
        lines.append("  flags: " + (", ".join(b["flags"]) if b["flags"] else "none"))
    return "\n".join(lines)


def _num(v: Any, digits: int = 0) -> str:
    if v is None or not math.isfinite(v):
        return "nan"
    return f"{v:.{digits}f}" if digits else f"{v:.4g}"
