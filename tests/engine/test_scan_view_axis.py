"""The axis a one-sided scan was seen along, read from the cloud (scan/view_axis.py), and the lone
samples in the shadow of its fronts that are no strays (docs/metrics.md 6.4)."""

from __future__ import annotations

import numpy as np

import skelcore.scan.outliers as outliers
from skelcore.scan.outliers import find_outliers
from skelcore.scan.view_axis import along_axis, view_axis


def _tube(n: int, half: bool) -> np.ndarray:
    """A tube of radius 1 along x, 10 long; ``half``: only its side facing +z (a one-sided scan)."""
    rng = np.random.default_rng(0)
    th = rng.uniform(0.0, np.pi if half else 2 * np.pi, n)
    return np.c_[rng.uniform(0.0, 10.0, n), np.cos(th), np.sin(th)]


def test_a_one_sided_scan_has_an_axis_a_closed_one_none():
    """The half tube's depth image along z keeps most of it; the whole tube keeps about half along
    any axis."""
    axis = view_axis(_tube(6000, half=True))
    assert axis is not None and abs(axis[2]) > 0.9
    assert view_axis(_tube(12000, half=False)) is None


def test_along_the_axis_from_most_nearest_surface_points():
    base = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    points = np.array([[0.2, 0.2, -2.0], [5.0, 0.2, -0.1]])
    near = np.array([[0, 1, 2], [0, 1, 2]])
    assert along_axis(points, base, near, np.array([0.0, 0.0, 1.0])).tolist() == [True, False]


def test_a_one_sided_neuron_scans_lone_sample_behind_a_saddle_is_no_stray(monkeypatch):
    """Tuning neuron 1734350908 seen from one side at 300k points (the calibration's cloud), within 400
    units of a lone sample behind a saddle: its front's rays away from it meet the same trunk 2-6
    spacings out, so it lies behind no front by the rays; along the scan's axis from that front, it lies
    in its shadow.  A stray without the rule."""
    from skelcore.benchmark.calibration.skeletons import world

    cloud = world("real", "1734350908", 300_000, "views", 0).cloud
    cloud = cloud[np.linalg.norm(cloud - np.array([15609.8, 12207.4, 10751.4]), axis=1) < 400.0]
    assert find_outliers(cloud).count == 0
    monkeypatch.setattr(outliers, "view_axis", lambda cloud, params=None: None)
    assert find_outliers(cloud).count == 1
