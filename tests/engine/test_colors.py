"""Colour maps without matplotlib: NaN is magenta, range from finite values, tables match matplotlib."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import colors
from skelcore.colors import MAGENTA, NAN_COLOR, finite_range, lookup_table, map_to_rgb


def test_nan_is_magenta():
    rgb = map_to_rgb(np.array([0.2, np.nan, 0.8]), 0.0, 1.0)
    assert rgb.dtype == np.uint8 and rgb.shape == (3, 3)
    assert tuple(rgb[1]) == MAGENTA == NAN_COLOR == (255, 0, 255)
    assert tuple(rgb[0]) != MAGENTA and tuple(rgb[2]) != MAGENTA


def test_default_range_comes_from_finite_values_only():
    values = np.array([np.nan, 10.0, np.inf, 20.0, -np.inf, 15.0])
    assert finite_range(values) == (10.0, 20.0)
    rgb = map_to_rgb(values)
    lut = lookup_table("viridis")
    assert tuple(rgb[1]) == tuple(lut[0]) and tuple(rgb[3]) == tuple(lut[-1])
    # +-inf are clamped to the ends, not magenta.
    assert tuple(rgb[2]) == tuple(lut[-1]) and tuple(rgb[4]) == tuple(lut[0])
    assert tuple(rgb[0]) == MAGENTA


def test_explicit_range_clamps_outside_values():
    rgb = map_to_rgb(np.array([-1.0, 0.0, 1.0, 2.0]), 0.0, 1.0)
    np.testing.assert_array_equal(rgb[0], rgb[1])
    np.testing.assert_array_equal(rgb[2], rgb[3])


def test_constant_values_map_to_the_middle_colour():
    rgb = map_to_rgb(np.full(4, 0.3))
    np.testing.assert_array_equal(rgb, np.tile(lookup_table("viridis", 3)[1], (4, 1)))


def test_all_nan_and_empty_inputs():
    assert (map_to_rgb(np.full(3, np.nan)) == MAGENTA).all()
    assert map_to_rgb(np.array([])).shape == (0, 3)


def test_viridis_is_monotone_in_lightness_and_has_its_known_ends():
    lut = lookup_table("viridis").astype(float)
    assert tuple(lut[0]) == (68, 1, 84) and tuple(lut[-1]) == (253, 231, 37)
    luma = lut @ np.array([0.2126, 0.7152, 0.0722])
    assert np.all(np.diff(luma) > -1.0)  # perceptual map: lightness never drops (uint8 rounding aside)


@pytest.mark.parametrize("cmap", colors.COLORMAPS)
def test_tables_match_matplotlib_within_two_levels(cmap):
    mpl = pytest.importorskip("matplotlib")
    ref = np.round(mpl.colormaps[cmap](np.linspace(0, 1, 256))[:, :3] * 255)
    assert np.abs(lookup_table(cmap).astype(float) - ref).max() <= 2


def test_bad_arguments_fail_loudly():
    with pytest.raises(ValueError, match="unknown colour map"):
        map_to_rgb(np.zeros(2), cmap="jet")
    with pytest.raises(ValueError, match="reversed"):
        map_to_rgb(np.zeros(2), 1.0, 0.0)
    with pytest.raises(ValueError, match="finite"):
        map_to_rgb(np.zeros(2), 0.0, np.inf)


def test_colors_module_does_not_import_matplotlib():
    import subprocess
    import sys

    code = "import sys, skelcore.colors, skelcore.io.export, skelcore.io; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_defect_colours_are_on_no_colour_map_and_apart_from_the_scene_and_each_other():
    """The defects are drawn in colours the metric map does not use (METRIC_COLORMAP, at
    least 80 RGB units from every entry), not magenta (NaN), not the pick marker's, apart from the
    skeleton's, the cloud's and the supports' (45), and distinct from one another (60)."""
    from skelcore.colors import (
        CLOUD_GREY, CURVE_COLOR, DEFECT_COLORS, MAGENTA, METRIC_COLORMAP, PICK_COLOR, SKELETAL_COLOR, SUPPORT_COLORS,
        lookup_table,
    )

    maps = lookup_table(METRIC_COLORMAP, 256).astype(float)
    fixed = np.array([CURVE_COLOR, SKELETAL_COLOR, MAGENTA, PICK_COLOR, CLOUD_GREY, (255, 255, 255),
                      *SUPPORT_COLORS.values()], dtype=float)
    colours = np.array(list(DEFECT_COLORS.values()), dtype=float)
    for name, c in zip(DEFECT_COLORS, colours):
        assert np.linalg.norm(maps - c, axis=1).min() > 80, name
        assert np.linalg.norm(fixed - c, axis=1).min() > 45, name
    d = np.linalg.norm(colours[:, None] - colours[None], axis=2)
    assert d[np.triu_indices(len(colours), 1)].min() > 60


def _lab(rgb) -> np.ndarray:
    """sRGB (0..255) -> CIELAB (D65): the distance in it is what the eye sees as a colour difference."""
    c = np.asarray(rgb, dtype=float) / 255.0
    c = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]) @ c
    f = xyz / np.array([0.95047, 1.0, 1.08883])
    f = np.where(f > 216 / 24389, np.cbrt(f), (24389 / 27 * f + 16) / 116)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def _contrast(a, b) -> float:
    """WCAG contrast ratio of two sRGB colours (1 = none, 21 = black on white)."""
    def lum(rgb):
        c = np.asarray(rgb, dtype=float) / 255.0
        return float(np.where(c <= 0.03928, c / 12.92, ((c + 0.055) / 1.055) ** 2.4) @ [0.2126, 0.7152, 0.0722])
    lo, hi = sorted((lum(a), lum(b)))
    return (hi + 0.05) / (lo + 0.05)


def test_the_colour_helpers_give_the_known_values():
    assert np.allclose(_lab((255, 255, 255)), (100, 0, 0), atol=0.05)
    assert np.allclose(_lab((255, 0, 0)), (53.24, 80.09, 67.20), atol=0.05)  # the standard sRGB red
    assert _contrast((0, 0, 0), (255, 255, 255)) == pytest.approx(21.0)
    assert _contrast((118, 118, 118), (255, 255, 255)) == pytest.approx(4.54, abs=0.01)  # WCAG's AA grey


def test_the_curve_colour_is_no_defect_s_no_value_s_and_reads_on_every_background():
    """The plain curve is never taken for a flagged one: at least 100 RGB and 45 CIELAB units from
    every defect colour, the pick marker and magenta (the former red was 82 RGB / 40 CIELAB units
    from the rose spurious-branch halo and 28 CIELAB units from the dark-red stray points); its edges,
    drawn beside vertices coloured by a metric, are off the colour map (40 CIELAB units: a teal was 5
    from viridis); it reads on the white and black backgrounds (contrast >= 3) and on the grey cloud
    (45 CIELAB units)."""
    from skelcore.colors import CLOUD_GREY, CURVE_COLOR, DEFECT_COLORS, METRIC_COLORMAP, PICK_COLOR

    flagged = {**DEFECT_COLORS, "pick": PICK_COLOR, "magenta": MAGENTA}
    for name, c in flagged.items():
        assert np.linalg.norm(np.subtract(CURVE_COLOR, c)) >= 100, name
        assert np.linalg.norm(_lab(CURVE_COLOR) - _lab(c)) >= 45, name
    for background in ((255, 255, 255), (0, 0, 0)):
        assert _contrast(CURVE_COLOR, background) >= 3, background
    assert np.linalg.norm(_lab(CURVE_COLOR) - _lab(CLOUD_GREY)) >= 45
    assert min(np.linalg.norm(_lab(CURVE_COLOR) - _lab(c)) for c in lookup_table(METRIC_COLORMAP, 256)) >= 40
    old_red = (214, 39, 40)  # the check tells the fault it guards against
    assert min(np.linalg.norm(_lab(old_red) - _lab(c)) for c in flagged.values()) < 45
