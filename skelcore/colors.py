"""The one place for SkelScope's colours: perceptual colour maps (no matplotlib needed), the NaN colour
(docs/metrics.md 5.5: magenta) and the fixed colours of the scene.

The maps are matplotlib's viridis and plasma (public domain, by Stéfan van der Walt and Nathaniel
Smith), stored as every 5th entry of their 256-entry tables and linearly interpolated in between;
the result is within 1/255 (viridis) and 2/255 (plasma) of matplotlib's tables.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "METRIC_COLORMAP",
    "MAGENTA",
    "NAN_COLOR",
    "CLOUD_GREY",
    "SKELETAL_COLOR",
    "CURVE_COLOR",
    "REFERENCE_COLOR",
    "PICK_COLOR",
    "SUPPORT_COLORS",
    "DEFECT_COLORS",
    "hex_color",
    "COLORMAPS",
    "lookup_table",
    "map_to_rgb",
    "finite_range",
    "DEFECT_SKELETON",
]

MAGENTA: tuple[int, int, int] = (255, 0, 255)
#: Invalid local values (NaN) are drawn in this colour (docs/metrics.md 5.5).
NAN_COLOR: tuple[int, int, int] = MAGENTA
#: The original cloud, drawn as context behind the skeleton.
CLOUD_GREY: tuple[int, int, int] = (170, 170, 170)
#: Uncoloured skeletal points (no metric selected).
SKELETAL_COLOR: tuple[int, int, int] = (31, 119, 180)
#: The curve skeleton's edges (always, as lines: beside vertices coloured by a metric) and its vertices
#: (no metric selected): an olive that no defect colour, the pick marker or magenta can be mistaken for
#: (at least 100 RGB units and 45 CIELAB units from each: a red curve beside the rose spurious-branch
#: halo and the dark-red stray points read as flagged all over), off the colour map (40 CIELAB units
#: from every viridis entry: an edge must not read as a value), with a contrast ratio of at least 3 on
#: the white and black backgrounds and 45 CIELAB units from the grey cloud.
CURVE_COLOR: tuple[int, int, int] = (145, 125, 0)
#: The skeleton in report.html's defect picture (skelcore/compare/render_defects.py), under the defects
#: drawn in DEFECT_COLORS (below, the viewer's too): a neutral grey, darker than the cloud's.
DEFECT_SKELETON: tuple[int, int, int] = (110, 110, 110)
#: A ground-truth (reference) curve, drawn as a thin line under the skeleton: a grey darker
#: than the cloud's, so it reads against the cloud and never as a skeleton colour.
REFERENCE_COLOR: tuple[int, int, int] = (90, 90, 90)
#: The colour map of the local metrics, over [0, 1], on screen and in exported files.
METRIC_COLORMAP = "viridis"
#: The picked element's marker: on neither colour map, not magenta, not a skeleton colour.
PICK_COLOR: tuple[int, int, int] = (255, 140, 0)
#: The picked element's support (the viewer's Support dock and 3-D overlay, the same colour for the
#: same thing in both), chosen apart from the skeleton's and the cloud's colours above, from magenta,
#: from the pick marker and from the viridis map (dark purple -> teal -> yellow): browns, black and a
#: light sky blue (a slab in the curve's colour would be mistaken for the curve).
SUPPORT_COLORS: dict[str, tuple[int, int, int]] = {
    "slab": (214, 160, 90),  # the slab's cloud points; a skeletal point's corresponding cloud points
    "ring": (120, 66, 18),  # the ring kept; a skeletal point's or vertex's neighbours
    "ellipse": (0, 0, 0),  # the fitted ellipse; the picked point's tangent; the vertex's edges
    "centre": (0, 176, 240),  # the ellipse's centre; m_s; the neighbour that sets the smoothness
    "m_o": (120, 66, 18),  # the cloud centroid m_o (shape tells it from the neighbours)
    "links": (90, 90, 90),  # skeletal point -> its cloud point
}

#: The viewer's defects and scan findings, each drawn in a style of its own (halo,
#: dashes, loop, large points) in a colour on neither colour map (at least 80 RGB units from every viridis
#: entry), not magenta (NaN), not the pick marker's and apart from the skeleton's and the supports';
#: the selected defect is redrawn in PICK_COLOR.
DEFECT_COLORS: dict[str, tuple[int, int, int]] = {
    "incomplete": (255, 160, 200),  # a missing part's cloud points (pink)
    "spurious_branches": (230, 0, 110),  # halo around a spurious branch (rose)
    "spurious_cycles": (0, 100, 0),  # halo around a spurious cycle's branches (dark green)
    "outside": (120, 0, 200),  # dashes over the curve's edges outside the shape (violet)
    "disconnected": (120, 135, 255),  # the curve's pieces beyond one per piece of the cloud (periwinkle)
    "along_surface": (0, 240, 255),  # halo around a branch running along the surface (cyan)
    "open_surface": (0, 0, 140),  # an opening's boundary loop (navy)
    "outliers": (128, 0, 0),  # stray points (dark red, large)
}


def hex_color(rgb: tuple[int, int, int]) -> str:
    """``#rrggbb`` for plotting libraries.

    >>> hex_color((255, 0, 255))
    '#ff00ff'
    """
    return "#{:02x}{:02x}{:02x}".format(*(int(v) for v in rgb))

_ANCHORS_HEX = {
    "viridis": (
        "44015446085c471063481769481d6f482475472a7a46307e453781433d844142873f48893d4e8a3a538b38598c355e8d"
        "33638d31688e2e6d8e2c718e2a768e297b8e27808e25848e23898e218e8d20928c1f978b1e9c891fa18821a58524aa83"
        "28ae802eb37c35b7793dbc7446c06f50c46a5ac86465cb5e70cf577cd25089d54895d840a2da37b0dd2fbddf26cae11f"
        "d8e219e5e419f1e51dfde725"
    ),
    "plasma": (
        "0d08871b068d2605912f059638049a41049d4903a05102a35901a56100a76900a87100a87801a88004a88707a68e0ca4"
        "9511a19c179ea21d9aa82296ae2892b42e8dba3388bf3984c43e7fc9447acd4a76d24f71d6556dda5b69de6164e26660"
        "e66c5ce97257ed7953f07f4ff3854bf58c46f79342f99a3efba139fca835fdaf31feb72dfebe2afdc627fcce25fbd724"
        "f8df25f6e826f3f027f0f921"
    ),
}


def _anchors(hex_table: str) -> np.ndarray:
    raw = bytes.fromhex(hex_table)
    return np.frombuffer(raw, dtype=np.uint8).reshape(-1, 3).astype(np.float64)


_ANCHORS = {name: _anchors(h) for name, h in _ANCHORS_HEX.items()}
#: Names accepted by ``cmap=``.
COLORMAPS: tuple[str, ...] = tuple(_ANCHORS)


def _anchor_table(cmap: str) -> np.ndarray:
    try:
        return _ANCHORS[cmap]
    except KeyError:
        raise ValueError(f"unknown colour map {cmap!r} (known: {', '.join(COLORMAPS)})") from None


def _interpolate(t: np.ndarray, cmap: str) -> np.ndarray:
    """t in [0, 1] -> (N, 3) float RGB in 0..255 by linear interpolation between the anchors."""
    table = _anchor_table(cmap)
    x = t * (len(table) - 1)
    i = np.clip(np.floor(x).astype(np.int64), 0, len(table) - 2)
    f = (x - i)[:, None]
    return table[i] * (1.0 - f) + table[i + 1] * f


def lookup_table(cmap: str = "viridis", n: int = 256) -> np.ndarray:
    """(n, 3) uint8 table of the colour map, for renderers that take a lookup table (VTK, pyvista)."""
    if n < 2:
        raise ValueError("a lookup table needs at least 2 entries")
    return np.rint(_interpolate(np.linspace(0.0, 1.0, n), cmap)).astype(np.uint8)


def finite_range(values: np.ndarray) -> tuple[float, float] | None:
    """(min, max) over the finite values only (Polyscope's robustMinMax idea); None if there are none."""
    v = np.asarray(values, dtype=np.float64).ravel()
    v = v[np.isfinite(v)]
    if v.size == 0:
        return None
    return float(v.min()), float(v.max())


def map_to_rgb(
    values: np.ndarray,
    vmin: float | None = None,
    vmax: float | None = None,
    cmap: str = "viridis",
) -> np.ndarray:
    """Colour scalar values: (N,) -> (N, 3) uint8.

    The range defaults to the finite values' min and max (pass ``vmin=0, vmax=1`` for the metrics,
    whose values live in [0, 1]); values outside the range are clamped, +-inf go to the ends, NaN is
    magenta (docs/metrics.md 5.5). A degenerate range (vmin == vmax) maps every finite value to the middle colour.

    >>> map_to_rgb(np.array([0.0, np.nan, 1.0]), 0, 1).tolist()
    [[68, 1, 84], [255, 0, 255], [253, 231, 37]]
    """
    v = np.asarray(values, dtype=np.float64).ravel()
    _anchor_table(cmap)  # reject unknown names even for empty input
    if vmin is None or vmax is None:
        rng = finite_range(v) or (0.0, 1.0)
        vmin = rng[0] if vmin is None else vmin
        vmax = rng[1] if vmax is None else vmax
    lo, hi = float(vmin), float(vmax)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise ValueError(f"colour range must be finite, got [{vmin}, {vmax}]")
    if hi < lo:
        raise ValueError(f"colour range is reversed: vmin {lo} > vmax {hi}")
    nan = np.isnan(v)
    if hi > lo:
        with np.errstate(invalid="ignore", over="ignore"):
            t = np.clip((v - lo) / (hi - lo), 0.0, 1.0)
    else:
        t = np.full(v.shape, 0.5)
        t[v < lo] = 0.0
        t[v > hi] = 1.0
    t[nan] = 0.0
    rgb = np.rint(_interpolate(t, cmap)).astype(np.uint8)
    rgb[nan] = NAN_COLOR
    return rgb
