"""The viewer's colours. Everything shared with the files skelcore writes (NaN magenta, docs/metrics.md 5.5; the
colour maps; the cloud and skeleton colours) comes from :mod:`skelcore.colors`, so the screen and an
exported PLY agree; only view-only colours live here."""

from __future__ import annotations

import pyvista as pv

from skelcore.colors import CLOUD_GREY, CURVE_COLOR, MAGENTA, METRIC_COLORMAP, PICK_COLOR, SKELETAL_COLOR, lookup_table

__all__ = [
    "MAGENTA", "CLOUD_GREY", "SKELETAL_PLAIN", "CURVE_EDGE", "CURVE_VERTEX", "PICK_MARKER", "make_lut", "plain_lut",
    "greyed", "STALE_MIX",
]

SKELETAL_PLAIN = SKELETAL_COLOR
CURVE_EDGE = CURVE_COLOR
CURVE_VERTEX = CURVE_COLOR
PICK_MARKER = PICK_COLOR
COLORMAP = METRIC_COLORMAP


STALE_MIX = 0.7
"""How far stale results' colours are washed toward light grey (a setting changed, so the
colours on screen are not those a re-run would give)."""


def greyed(rgb: tuple[int, int, int]) -> tuple[int, int, int]:
    """A colour washed toward light grey (215) by STALE_MIX: still readable, plainly out of date."""
    return tuple(int(round(v + STALE_MIX * (215 - v))) for v in rgb)  # type: ignore[return-value]


def make_lut(clim: tuple[float, float], cmap: str = COLORMAP, stale: bool = False) -> pv.LookupTable:
    """A VTK lookup table of skelcore's colour map over ``clim``, NaN drawn magenta; ``stale``: both
    washed toward grey (:func:`greyed`)."""
    table = lookup_table(cmap, 256)
    lut = pv.LookupTable()
    shade = greyed if stale else (lambda c: c)
    lut.values = [(*shade((int(r), int(g), int(b))), 255) for r, g, b in table]
    lut.scalar_range = (float(clim[0]), float(clim[1]))
    lut.nan_color = shade(MAGENTA)
    return lut


_PLAIN: dict[tuple[int, int, int], pv.LookupTable] = {}


def plain_lut(colour: tuple[int, int, int]) -> pv.LookupTable:
    """A lookup table that maps every value to one colour (exactly: no lighting on points). One
    table per colour, shared: every plain recolouring (an edit's curve) would otherwise build one."""
    key = (int(colour[0]), int(colour[1]), int(colour[2]))
    lut = _PLAIN.get(key)
    if lut is None:
        lut = _PLAIN[key] = pv.LookupTable()
        lut.values = [(*key, 255)] * 256
        lut.scalar_range = (0.0, 1.0)
    return lut
