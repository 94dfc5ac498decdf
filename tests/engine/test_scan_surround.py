"""The openings' surround test: the compiled first pass gives the exact test's answers
(docs/metrics.md 6.1; docs/performance.md, "The openings' surround test")."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import shapes
from skelcore.metrics import _surround
from skelcore.scan import openings as openings_module
from skelcore.scan.openings import find_openings
from skelcore.scan.surround import surrounded, surrounded_exact
from skelcore.scan.synthetic import seen_from


def test_the_first_pass_angles_stay_within_their_allowance():
    """The binning's atan2 is within 0.002 rad of numpy's at every angle and scale (the kernel allows 0.004)."""
    t = np.linspace(-np.pi, np.pi, 400_001)
    for r in (1e-200, 1.0, 1e200):
        x, y = r * np.cos(t), r * np.sin(t)
        out = np.empty_like(x)
        _surround.approx_angles(x, y, out)
        err = np.abs(np.angle(np.exp(1j * (out - np.arctan2(y, x)))))
        assert err.max() < 0.002


def _rims():
    rng = np.random.default_rng(5)
    a = rng.uniform(0, 2 * np.pi, 300)
    star = (1 + 0.6 * np.sin(5 * a))[:, None] * np.column_stack([np.cos(a), np.sin(a)])
    b = rng.uniform(0, 2 * np.pi, 400)
    annulus = np.vstack([np.column_stack([np.cos(b), np.sin(b)])[:200],
                         0.3 * np.column_stack([np.cos(b), np.sin(b)])[200:]])
    c = rng.uniform(0, np.pi, 150)  # half a circle: an open arc
    arc = np.column_stack([2 * np.cos(c), 0.5 * np.sin(c)])
    square = np.array([(i, j) for i in range(-4, 5) for j in (-4, 4)] + [(i, j) for i in (-4, 4) for j in range(-3, 4)],
                      float)  # on the grid's own lattice: directions of zero length and exact ties
    few = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0]])
    return {"star": star, "annulus": annulus, "arc": arc, "square": square, "few": few}


@pytest.mark.parametrize("name", sorted(_rims()))
@pytest.mark.parametrize("degrees", [45.0, 90.0, 170.0, 300.0])
def test_the_first_pass_answers_as_the_exact_test(name, degrees):
    """Every grid point's answer is the exact test's; the cases leave points to the exact test."""
    ring = _rims()[name]
    g = np.arange(-5.0, 5.01, 0.25) if name == "square" else np.linspace(-2.6, 2.6, 91)
    grid = np.column_stack([np.repeat(g, len(g)), np.tile(g, len(g))])
    angle = np.radians(degrees)
    np.testing.assert_array_equal(surrounded(ring, grid, angle), surrounded_exact(ring, grid, angle))


def test_the_first_pass_leaves_the_close_calls_and_decides_the_rest():
    """Near the rim of a circle the gap is close to 90 degrees: those points are undecided (-1), the
    centre is surrounded (1) and the far corners are not (0)."""
    a = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    ring = np.column_stack([np.cos(a), np.sin(a)])
    g = np.linspace(-1.5, 1.5, 61)
    grid = np.column_stack([np.repeat(g, len(g)), np.tile(g, len(g))])
    state = np.empty(len(grid), np.int8)
    _surround.surround(ring, grid, np.pi / 2, state)
    assert set(np.unique(state)) == {-1, 0, 1}
    assert state[np.argmin(np.linalg.norm(grid, axis=1))] == 1 and state[0] == 0
    exact = surrounded_exact(ring, grid, np.pi / 2)
    decided = state >= 0
    np.testing.assert_array_equal(state[decided] == 1, exact[decided])


@pytest.mark.parametrize("cloud", ["open tube", "seen from one side"])
def test_openings_are_those_of_the_exact_test(cloud, monkeypatch):
    """find_openings gives the same openings, to the bit, with the first pass and with the exact test
    alone (the code before the first pass)."""
    shape = shapes.cylinder(6000, capped=False) if cloud == "open tube" else shapes.y_shape(8000)
    pts = shape.cloud if cloud == "open tube" else shape.cloud[seen_from(shape.cloud, [[0.0, 0.0, 10.0]])]
    fast = find_openings(pts)
    monkeypatch.setattr(openings_module, "surrounded", surrounded_exact)
    slow = find_openings(pts)
    assert len(fast) == len(slow) > 0
    for o, p in zip(fast, slow):
        assert o.kind == p.kind
        for name in ("rows", "fill", "dome", "centre", "normal"):
            np.testing.assert_array_equal(getattr(o, name), getattr(p, name))
