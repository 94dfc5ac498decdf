"""An element the interior rejects explains nothing only when its ball is wider than the shape's
(``missing_air_ball``, docs/diagnostics.md "Completeness"): the axis of a tube seen from one side lies
in no solid voxel yet keeps the tube's radius; an edge through the air does not."""

from __future__ import annotations

import numpy as np

from skelcore import shapes
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics.missing_parts import missing_parts
from skelcore.params import Params


def _half_tube():
    """A cylinder's points with y > 0 (one side seen), its axis, and an interior test that holds the
    solid tube for z < 2 only (the voxels of a half tube are not solid there; the tube runs along z;
    the air beside the tube is outside, as in a voxelized interior)."""
    s = shapes.cylinder(n=4000, radius=0.25, length=4.0, capped=False, seed=3)
    cloud = s.cloud[s.cloud[:, 1] > 0]
    return cloud, s.curve_vertices, s.curve_edges, lambda p: (np.asarray(p)[:, 2] < 2.0) & (
        np.linalg.norm(np.asarray(p)[:, :2], axis=1) < 0.25 + 0.01)


def test_a_half_seen_tube_axis_keeps_its_balls():
    cloud, v, e, inside = _half_tube()
    axis = CurveSkeleton.from_raw(v, e)
    got = missing_parts(cloud, axis, inside=inside)
    assert got.outside_elements == 0 and got.completeness > 0.95 and not got.incomplete
    # every rejected element dropped (the rule before): the half tube under the rejected axis is lost
    old = missing_parts(cloud, axis, Params(missing_air_ball=1e-9), inside=inside)
    assert old.outside_elements > 0 and old.completeness < 0.7 and old.incomplete


def test_an_edge_through_the_air_still_explains_nothing():
    """A hub 8 tube radii above the half tube joined to both ends: its elements have balls as wide
    as the gap, and without the axis the hub's star is incomplete."""
    cloud, v, e, inside = _half_tube()
    ends = [int(np.argmin(v[:, 2])), int(np.argmax(v[:, 2]))]
    hub = np.array([[0.0, 2.0, 2.0]])
    star = CurveSkeleton.from_raw(np.vstack([hub, v[ends]]), np.array([[0, 1], [0, 2]]))
    got = missing_parts(cloud, star, inside=lambda p: np.linalg.norm(np.asarray(p)[:, :2], axis=1) < 0.3)
    assert got.outside_elements > 0 and got.incomplete
