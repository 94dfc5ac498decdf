"""Trust warnings (frame, collapse, trivial_smoothness), --strict, and the Wasserstein identity defect."""

import json

import numpy as np
import pytest

from skelcore import evaluate, shapes
from skelcore.cli import main
from skelcore.io import write_curve_ply, write_points_ply
from skelcore.metrics.topology import h0_barcode, wasserstein_h0


def codes(ev):
    return [w.code for w in ev.warnings]


def test_a_good_skeleton_gets_no_warning():
    sh = shapes.y_shape(1500, seed=1)
    assert codes(evaluate(sh.cloud, sh.skeletal, (sh.curve_vertices, sh.curve_edges))) == []


@pytest.mark.parametrize("scale, offset", [(10.0, 0.0), (1.0, 50.0), (0.01, 30.0)])
def test_frame_warning_for_other_units_or_offsets(scale, offset):
    sh = shapes.cylinder(1000, seed=2)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices * scale + offset, sh.curve_edges))
    assert "frame" in codes(ev)
    msg = ev.warnings[codes(ev).index("frame")].message
    assert "--skeleton-scale" in msg and "--skeleton-offset" in msg


def test_collapse_warning_for_a_skeleton_shrunk_to_the_centroid():
    sh = shapes.cylinder(1000, seed=3)
    c = np.repeat(sh.cloud.mean(axis=0)[None], len(sh.cloud), 0)
    c += np.random.default_rng(0).normal(scale=1e-6, size=c.shape)
    ev = evaluate(sh.cloud, c)
    assert codes(ev) == ["collapse", "incomplete"]  # a collapsed skeleton explains little of the cloud
    # the paper's scores reward it, which is why the warning exists
    assert ev.summary()["boundedness"]["skeletal"] > 0.9


def test_trivial_smoothness_when_no_vertex_has_degree_two():
    sh = shapes.cylinder(1000, seed=4)
    v = sh.curve_vertices[[0, len(sh.curve_vertices) - 1]]
    ev = evaluate(sh.cloud, curve=(v, [[0, 1]]))
    assert "trivial_smoothness" in codes(ev)
    assert ev.summary()["smoothness"]["curve"] == 1.0 or ev.summary()["counts"]["smoothness"]["curve"] == 0


def test_warnings_in_json_as_code_and_message():
    sh = shapes.cylinder(800, seed=5)
    doc = evaluate(sh.cloud, curve=(sh.curve_vertices * 20, sh.curve_edges)).to_json_dict()
    assert doc["warnings"] and all(set(w) == {"code", "message"} for w in doc["warnings"])


def test_strict_exits_3_and_prints_one_line_per_warning(tmp_path, capsys):
    sh = shapes.cylinder(800, seed=6)
    write_points_ply(tmp_path / "cloud.ply", sh.cloud)
    write_curve_ply(tmp_path / "far.ply", sh.curve_vertices + 100.0, sh.curve_edges)
    args = ["evaluate", str(tmp_path / "cloud.ply"), "--curve", str(tmp_path / "far.ply"), "--quiet",
            "--json", str(tmp_path / "out.json")]
    assert main(args) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("skelcore: warning [frame]:")
    assert main(args + ["--strict"]) == 3
    assert json.loads((tmp_path / "out.json").read_text())["warnings"][0]["code"] == "frame"
    # mapped back into the cloud's frame, the warning goes away
    assert main(args + ["--strict", "--skeleton-offset", "-100", "-100", "-100"]) == 0


def test_wasserstein_of_a_diagram_with_itself_is_exactly_zero():
    rng = np.random.default_rng(0)
    for n in (10, 500, 4096):
        bars = h0_barcode(rng.normal(size=(n, 3)) * rng.uniform(1e-3, 1e3))
        assert wasserstein_h0(bars, bars) == 0.0
        assert wasserstein_h0(bars, bars.copy()[::-1]) == 0.0  # order does not matter


def test_wasserstein_is_never_negative():
    rng = np.random.default_rng(1)
    for _ in range(200):
        a = np.column_stack([np.zeros(30), rng.exponential(size=30)])
        b = a.copy()
        b[:, 1] *= 1 + rng.normal(scale=1e-15, size=30)  # rounding-level differences
        assert wasserstein_h0(a, np.abs(b)) >= 0.0


def test_frame_warning_for_voxel_coordinates_inside_the_clouds_box():
    # a grid of pitch 3 laid over a torus at 0..78: voxel coordinates lie inside the cloud's box,
    # a third of its size, mostly off the tube; centred and scaled back they are bounded again
    sh = shapes.torus(2000, seed=9)
    lo = (sh.cloud * 30).min(axis=0)
    cloud, verts = sh.cloud * 30 - lo, sh.curve_vertices * 30 - lo
    ev = evaluate(cloud, curve=(verts / 3.0, sh.curve_edges))
    assert "frame" in codes(ev)
    assert "--skeleton-scale" in ev.warnings[codes(ev).index("frame")].message
    assert "frame" not in codes(evaluate(cloud, curve=(verts, sh.curve_edges)))
    half = len(verts) // 2  # an incomplete skeleton in the right frame is not a frame problem
    assert "frame" not in codes(evaluate(cloud, curve=(verts[: half + 1], sh.curve_edges[:half])))


def test_a_warning_gives_its_finding_and_suggested_mapping_apart_from_the_command_line():
    """A front end words its own remedy from ``finding`` and ``mapping``, read from the
    message (so a warning read back from a file gives the same); the suggested map undoes the one
    the skeleton was put in."""
    from skelcore.diagnostics.trust import TrustWarning, frame_warnings, no_correspondence_warning

    sh = shapes.y_shape(800, seed=1)
    (w,) = frame_warnings(sh.cloud, sh.curve_vertices * 40.0 + 7.0, "curve skeleton")
    assert "--skeleton" not in w.finding and w.message.startswith(w.finding)
    s, off = w.mapping
    mapped = (sh.curve_vertices * 40.0 + 7.0) * s + np.asarray(off)
    # the frame fit proposes a bounded and complete map near the inverse (here a scale
    # 12 % short of 1/40: the arms' ends stay inside their caps), not the bounding boxes' match
    assert np.abs(mapped - sh.curve_vertices).max() < 0.1 * np.ptp(sh.cloud)
    back = TrustWarning(w.code, w.message)  # as read from a JSON document
    assert back.finding == w.finding and back.mapping == w.mapping
    n = no_correspondence_warning(150, 1200)
    assert n.finding.endswith("need a correspondence") and "--" not in n.finding and n.mapping is None
