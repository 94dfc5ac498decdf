"""The viewer's colours in one place. NaN's magenta comes from skelcore.colors (SPEC 5), so the
screen and the exported PLY files agree."""

from __future__ import annotations

try:
    from skelcore.colors import MAGENTA as _MAGENTA
except ImportError:  # TEMPORARY until skelcore.colors lands
    _MAGENTA = (255, 0, 255)

MAGENTA: tuple[int, int, int] = tuple(int(v) for v in _MAGENTA)  # type: ignore[assignment]
COLORMAP = "viridis"  # perceptually uniform and free of magenta, so NaN stands out
CLOUD_GREY = (150, 150, 150)
SKELETAL_PLAIN = (230, 120, 20)  # orange: not on viridis, so uncoloured skeletons read as such
CURVE_EDGE = (40, 40, 40)
CURVE_VERTEX = (40, 40, 40)
PICK_MARKER = (230, 20, 20)
