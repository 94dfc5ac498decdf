"""The Defects panel's rows (app/scene/defects.py, Qt-free) for the scan's ``thin_parts`` and
``sparse_boundedness`` warnings, from evaluations that raise them (the cases of
tests/engine/test_scan_real_data.py and tests/engine/golden/make_golden.py): neither makes a skeleton
unsound."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skelscope.scene.defects import DEFECT_TITLES, defect_counts, defect_rows, sound_line
from skelcore import evaluate
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics.trust import DEFECT_CODES

ROOT = Path(__file__).resolve().parents[2]


def test_the_apple_tree_has_a_thin_parts_row_framing_their_box():
    """The paper's synthetic tree (8936 points) and its stored "cao" skeletons: its twigs are too thin."""
    from skelcore.io import load_cloud
    from skelcore.skeleton.degrade import voxel_grid_average

    cloud = voxel_grid_average(load_cloud(ROOT / "resources" / "scans" / "apple_tree_22367.ply"), 0.02)[0]
    with np.load(ROOT / "tests" / "engine" / "golden" / "scan_skeletons.npz") as z:
        skeletal = z["tree_skeletal"]
        curve = CurveSkeleton.from_raw(z["tree_curve_vertices"], z["tree_curve_edges"])
    ev = evaluate(cloud, skeletal=skeletal, curve=curve)
    assert "thin_parts" in {w.code for w in ev.warnings}
    (row,) = [r for r in defect_rows(ev) if r.code == "thin_parts"]
    thin = ev.scan.thin_parts
    assert row.title == f"{thin['parts']} thin parts" and f"{thin['points']} boundary points" in row.size
    lo, hi = row.bounds()
    assert np.allclose(lo, thin["box"][0]) and np.allclose(hi, thin["box"][1])
    assert row.column == "" and defect_counts(ev)["thin_parts"] == 1
    assert "thin_parts" not in sound_line(ev)


def test_a_torus_half_ten_times_sparser_has_a_sparse_boundedness_row():
    from skelcore.benchmark.validity import _shape
    from skelcore.correspondence import project_onto_curve

    rng = np.random.default_rng(0)
    _, sampler, (v, e, _) = _shape("torus", 0)
    curve = CurveSkeleton.from_raw(v, e)
    first = sampler.sample(1200, rng).points  # one half (beyond the median of its longest side) keeps a tenth
    axis = int(np.argmax(np.ptp(first, axis=0)))
    median = float(np.median(first[:, axis]))
    parts, have, pts = [], 0, first
    while have < 1200:
        keep = (pts[:, axis] < median) | (rng.uniform(size=len(pts)) < 0.1)
        parts.append(pts[keep])
        have += int(keep.sum())
        pts = sampler.sample(1200, rng).points
    half = np.vstack(parts)[:1200]
    ev = evaluate(half, skeletal=project_onto_curve(half, curve)[0], curve=curve)
    (w,) = [w for w in ev.warnings if w.code == "sparse_boundedness"]
    (row,) = [r for r in defect_rows(ev) if r.code == "sparse_boundedness"]
    assert row.size == w.message and row.bounds() is None  # no place: the camera frames the whole scene
    assert "sparse_boundedness" not in sound_line(ev)


def test_the_scan_codes_are_titled_and_no_defects():
    for code in ("open_surface", "outliers", "thin_parts", "sparse_boundedness"):
        assert code in DEFECT_TITLES and code not in DEFECT_CODES
