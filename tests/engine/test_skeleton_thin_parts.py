"""The default pipeline's start on thin parts (docs/skeletonize.md "Thin parts"): the axis curve at the
cloud's spacing is taken only when cao's sampling ball exceeds ``AxisParams.thin_ratio`` local
thicknesses; it follows a thin tube's axis end to end, as a tree; a stout shape keeps cao's curve."""

from __future__ import annotations

import numpy as np

from skelcore import shapes
from skelcore.skeleton import CaoParams, skeletonize
from skelcore.skeleton.default import default_skeleton
from skelcore.skeleton.local_axis import axis_contract, axis_curve, local_thickness


def test_a_thin_tube_takes_the_axis_curve_along_its_whole_length():
    cloud = shapes.cylinder(3000, radius=0.01, length=4.0, capped=False, seed=1).cloud
    skeletal, curve, info, choice = default_skeleton(cloud)
    assert choice.method == "axis" and info.method == "axis" and choice.ratio > 4.0
    assert 0.005 < choice.thickness < 0.015  # about the radius
    assert skeletal.shape == cloud.shape
    off_axis = np.linalg.norm(curve.vertices[:, :2], axis=1)
    assert off_axis.max() < 0.01  # on the axis, not on the wall
    z = curve.vertices[:, 2]
    assert z.min() < 0.1 and z.max() > 3.9  # not shortened
    assert curve.n_edges == curve.n_vertices - 1  # a spanning tree of one component


def test_a_stout_shape_keeps_caos_curve_exactly():
    cloud = shapes.cylinder(1500, radius=0.5, length=4.0, seed=2).cloud
    _sk, curve, info, choice = default_skeleton(cloud)
    assert choice.method == "cao" and choice.ratio < 1.0
    _sk2, raw = skeletonize(cloud, CaoParams(), method="cao")
    assert np.array_equal(curve.vertices, raw.vertices) and np.array_equal(curve.edges, raw.edges)


def test_the_axis_moves_keep_a_thin_tube_its_length():
    cloud = shapes.cylinder(2000, radius=0.02, length=2.0, capped=False, seed=3).cloud
    moved = axis_contract(cloud)
    assert np.ptp(moved.points[:, 2]) > 1.9
    assert np.median(np.linalg.norm(moved.points[:, :2], axis=1)) < 0.005
    assert abs(local_thickness(cloud, moved) - 0.02) < 0.005
    assert axis_curve(moved).n_vertices > 10


def test_the_command_says_it_took_the_axis_curve(tmp_path, capsys):
    from skelcore.cli.main import main
    from skelcore.io import load_curve, write_points_ply

    cloud = shapes.cylinder(2000, radius=0.01, length=4.0, capped=False, seed=4).cloud
    src, out = tmp_path / "thin.ply", tmp_path / "c.ply"
    write_points_ply(src, cloud)
    assert main(["skeletonize", str(src), "--out-curve", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "thin parts" in printed and "(axis)" in printed and "repaired:" in printed
    assert np.ptp(load_curve(out).vertices[:, 2]) > 3.8


def test_the_ring_curve_follows_a_thin_y_to_its_three_tips():
    from skelcore.correspondence import project_onto_curve
    from skelcore.curve import CurveSkeleton

    s = shapes.y_shape(12000, radius=0.01, seed=5)
    _sk, curve, _info, choice = default_skeleton(s.cloud)
    assert choice.method == "axis"
    truth = CurveSkeleton.from_raw(s.curve_vertices, s.curve_edges)
    off = np.linalg.norm(curve.vertices - project_onto_curve(curve.vertices, truth)[0], axis=1)
    assert off.max() < 0.01  # every vertex inside the tube, on its axis
    tips = s.curve_vertices[np.bincount(s.curve_edges.ravel(), minlength=len(s.curve_vertices)) == 1]
    assert all(np.linalg.norm(curve.vertices - t, axis=1).min() < 0.01 for t in tips)
    deg = np.bincount(curve.edges.ravel(), minlength=curve.n_vertices)
    assert np.linalg.norm(curve.vertices[deg >= 3], axis=1).min() < 0.03  # the junction at the origin
    assert curve.n_edges == curve.n_vertices - 1


def test_the_ball_curve_is_kept_as_an_option_and_chains_are_thinned_not_moved():
    from skelcore.skeleton.axis_rings import simplify_chains
    from skelcore.skeleton.skeleton_params import AxisParams
    from skelcore.curve import CurveSkeleton

    cloud = shapes.cylinder(2000, radius=0.02, length=2.0, capped=False, seed=3).cloud
    moved = axis_contract(cloud)
    rings, balls = axis_curve(moved), axis_curve(moved, AxisParams(curve="balls"))
    assert rings.n_vertices > 10 and balls.n_vertices > 10
    line = CurveSkeleton.from_raw(np.column_stack([np.zeros((11, 2)), np.linspace(0, 1, 11)]),
                                  np.column_stack([np.arange(10), np.arange(1, 11)]))
    thin = simplify_chains(line, 1e-9, 0.25)
    assert thin.n_vertices == 6 and thin.n_edges == 5  # every other inner vertex, the ends kept
    assert set(map(float, thin.vertices[:, 2])) <= set(map(float, line.vertices[:, 2]))


def _rod_and_wall(keep_from: float, radius: float = 0.05, step: float = 0.01):
    """A rod of moved points inside a tube's wall: every grid point of the tube's cross-sections with
    x >= keep_from x radius (all of it for -1), and the wall (the cloud) around them."""
    g = np.arange(-radius, radius + 1e-9, step)
    x, y = np.meshgrid(g, g)
    keep = (x * x + y * y < (0.95 * radius) ** 2) & (x >= keep_from * radius)
    z = np.arange(0.0, 2.0, step)
    section = np.column_stack([x[keep], y[keep]])
    points = np.column_stack([np.tile(section, (len(z), 1)), np.repeat(z, len(section))])
    a = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    zw = np.arange(0.0, 2.0, step / 2)
    wall = np.column_stack([np.tile(radius * np.cos(a), len(zw)), np.tile(radius * np.sin(a), len(zw)), np.repeat(zw, len(a))])
    return points, wall


def test_the_ring_centres_weight_deep_points_and_leave_a_lopsided_rods_centroid():
    from skelcore.skeleton.axis_rings import ring_curve
    from skelcore.skeleton.skeleton_params import AxisParams

    points, wall = _rod_and_wall(-0.3)  # a disk less a segment on one side: its centroid is off the axis
    plain = ring_curve(points, 0.01, AxisParams(ring_depth_power=0.0), cloud=wall)
    deep = ring_curve(points, 0.01, cloud=wall)
    mid = lambda c: c.vertices[(c.vertices[:, 2] > 0.3) & (c.vertices[:, 2] < 1.7)]
    off_plain = np.median(np.linalg.norm(mid(plain)[:, :2], axis=1))
    off_deep = np.median(np.linalg.norm(mid(deep)[:, :2], axis=1))
    assert off_plain > 0.005  # a tenth of the radius off the axis
    assert off_deep < 0.5 * off_plain  # the deep points sit near the axis
    no_cloud = ring_curve(points, 0.01)
    assert np.array_equal(no_cloud.vertices, plain.vertices) and np.array_equal(no_cloud.edges, plain.edges)


def test_the_ring_centres_of_a_symmetric_rod_stay_on_its_axis():
    from skelcore.skeleton.axis_rings import ring_curve

    points, wall = _rod_and_wall(-1.0)
    deep = ring_curve(points, 0.01, cloud=wall)
    inner = deep.vertices[(deep.vertices[:, 2] > 0.3) & (deep.vertices[:, 2] < 1.7)]
    assert len(inner) > 20
    assert np.linalg.norm(inner[:, :2], axis=1).max() < 0.002  # weighting a symmetric ring moves nothing
