"""The viewer's colours. Everything shared with the files skelcore writes (NaN magenta, SPEC 5; the
colour maps; the cloud and skeleton colours) comes from :mod:`skelcore.colors`, so the screen and an
exported PLY agree; only view-only colours live here."""

from __future__ import annotations

import pyvista as pv

from skelcore.colors import CLOUD_GREY, CURVE_COLOR, MAGENTA, METRIC_COLORMAP, SKELETAL_COLOR, lookup_table

__all__ = [
    "MAGENTA", "CLOUD_GREY", "SKELETAL_PLAIN", "CURVE_EDGE", "CURVE_VERTEX", "PICK_MARKER", "make_lut", "plain_lut",
]

SKELETAL_PLAIN = SKELETAL_COLOR
CURVE_EDGE = CURVE_COLOR
CURVE_VERTEX = CURVE_COLOR
PICK_MARKER = (255, 140, 0)  # orange: on neither colour map, not magenta
COLORMAP = METRIC_COLORMAP


def make_lut(clim: tuple[float, float], cmap: str = COLORMAP) -> pv.LookupTable:
    """A VTK lookup table of skelcore's colour map over ``clim``, NaN drawn magenta."""
    table = lookup_table(cmap, 256)
    lut = pv.LookupTable()
    lut.values = [(int(r), int(g), int(b), 255) for r, g, b in table]
    lut.scalar_range = (float(clim[0]), float(clim[1]))
    lut.nan_color = MAGENTA
    return lut


def plain_lut(colour: tuple[int, int, int]) -> pv.LookupTable:
    """A lookup table that maps every value to one colour (exactly: no lighting on points)."""
    lut = pv.LookupTable()
    lut.values = [(int(colour[0]), int(colour[1]), int(colour[2]), 255)] * 256
    lut.scalar_range = (0.0, 1.0)
    return lut
