"""Coloured PLY export of an Evaluation: files, properties, colours, NaN magenta, user units, guards."""

from __future__ import annotations

import os

import numpy as np
import pytest
from plyfile import PlyData

from skelcore.colors import MAGENTA, map_to_rgb
from skelcore.curve import CurveSkeleton
from skelcore.errors import SkelInputError
from skelcore.io.export import export_ply
from skelcore.geometry import Normalization
from skelcore.io import load_curve
from skelcore.params import Params
from skelcore.evaluation import CurveLocal, Evaluation, SkeletalLocal


def _evaluation(inputs: dict | None = None) -> Evaluation:
    rng = np.random.default_rng(5)
    cloud = rng.uniform(100, 200, size=(20, 3))  # user units, far from the unit box
    skel_pts = cloud * 0.5 + 50
    skeletal = SkeletalLocal(
        points=skel_pts,
        boundedness=np.array([0.9] * 10 + [0.5] * 10),  # last ten unbounded
        centeredness_raw=np.array([0.8, np.nan] + [0.3] * 18),
        smoothness=np.array([np.nan] + [0.9] * 19),
    )
    curve = CurveSkeleton.from_raw(
        np.array([[100, 100, 100], [150, 100, 100], [200, 100, 100], [150, 150, 100]], dtype=float),
        np.array([[0, 1], [1, 2], [1, 3]]),
    )
    samples = np.array([[125, 100, 100], [150, 100, 100], [175, 100, 100], [200, 100, 100], [150, 150, 100]], float)
    curve_local = CurveLocal(
        curve=curve,
        samples=samples,
        sample_edge=np.array([0, 0, 1, 1, 2]),
        sample_t=np.array([0.5, 1.0, 0.5, 1.0, 1.0]),
        sample_boundedness=np.array([0.9, 0.9, 0.2, 0.9, 0.9]),
        sample_centeredness_raw=np.array([0.95, np.nan, np.nan, 0.4, 0.8]),
        vertex_degree=np.array([1, 3, 1, 1]),
        vertex_smoothness=np.full(4, np.nan),
        smoothness_overall=1.0,
        smoothness_count=0,
    )
    return Evaluation(
        params=Params(),
        normalization=Normalization.from_cloud(cloud),
        cloud=cloud,
        skeletal=skeletal,
        curve=curve_local,
        inputs=inputs or {},
    )


def _vertex(path):
    return PlyData.read(str(path))["vertex"]


def _rgb(vert) -> np.ndarray:
    return np.column_stack([vert["red"], vert["green"], vert["blue"]])


def test_export_writes_three_coloured_files_in_user_units(tmp_path):
    ev = _evaluation()
    written = export_ply(ev, tmp_path / "out")
    assert [p.rsplit("/", 1)[-1] for p in written] == ["skeletal.ply", "curve.ply", "curve_samples.ply"]

    sk = _vertex(tmp_path / "out" / "skeletal.ply")
    np.testing.assert_array_equal(np.column_stack([sk["x"], sk["y"], sk["z"]]), ev.skeletal.points)
    assert {"boundedness", "centeredness", "smoothness"} <= {p.name for p in sk.properties}
    c = np.asarray(sk["centeredness"], dtype=float)
    # docs/metrics.md 3: unbounded points get c = 0; point 1 is bounded with NaN c, which stays NaN.
    assert c[0] == pytest.approx(0.8) and np.isnan(c[1]) and np.all(c[10:] == 0.0)
    np.testing.assert_array_equal(_rgb(sk), map_to_rgb(ev.skeletal.centeredness(0.75), 0, 1))
    assert tuple(_rgb(sk)[1]) == MAGENTA

    curve = load_curve(tmp_path / "out" / "curve.ply")
    np.testing.assert_array_equal(curve.vertices, ev.curve.curve.vertices)
    np.testing.assert_array_equal(curve.edges, ev.curve.curve.edges)
    cv = _vertex(tmp_path / "out" / "curve.ply")
    assert cv["degree"].tolist() == [1, 3, 1, 1]
    assert (_rgb(cv) == MAGENTA).all()  # no degree-2 vertex: every smoothness is NaN

    cs = _vertex(tmp_path / "out" / "curve_samples.ply")
    sc = np.asarray(cs["centeredness"], dtype=float)
    # Sample 2 is unbounded: 0 even though its raw value is NaN (the reference tool's order).
    assert sc[2] == 0.0 and np.isnan(sc[1]) and sc[0] == pytest.approx(0.95)
    assert tuple(_rgb(cs)[1]) == MAGENTA and tuple(_rgb(cs)[2]) != MAGENTA
    assert cs["edge"].tolist() == [0, 0, 1, 1, 2]


def test_color_by_and_threshold_follow_the_evaluation(tmp_path):
    ev = _evaluation()
    ev.params = ev.params.replace(beta_star=0.95)  # now every point is unbounded
    export_ply(ev, tmp_path, color_by="smoothness")
    sk = _vertex(tmp_path / "skeletal.ply")
    assert np.all(np.asarray(sk["centeredness"]) == 0.0)
    np.testing.assert_array_equal(_rgb(sk), map_to_rgb(ev.skeletal.smoothness, 0, 1))
    with pytest.raises(ValueError, match="color_by"):
        export_ply(ev, tmp_path, color_by="topology")


def test_export_skips_missing_parts(tmp_path):
    ev = _evaluation()
    ev.curve = None
    assert [p.rsplit("/", 1)[-1] for p in export_ply(ev, tmp_path)] == ["skeletal.ply"]


def test_export_never_overwrites_an_input(tmp_path):
    target = tmp_path / "skeletal.ply"
    target.write_bytes(b"the user's skeleton")
    ev = _evaluation(inputs={"skeletal": str(target)})
    with pytest.raises(SkelInputError, match="overwrite"):
        export_ply(ev, tmp_path)
    assert target.read_bytes() == b"the user's skeleton"
    with pytest.raises(SkelInputError, match="overwrite"):
        export_ply(_evaluation(), tmp_path, inputs=[str(target)])


def test_export_folder_that_is_a_file_is_an_input_error(tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(SkelInputError, match="file"):
        export_ply(_evaluation(), f)


@pytest.mark.parametrize("binary", [True, False])
@pytest.mark.parametrize("color_by", ["boundedness", "centeredness", "smoothness"])
def test_each_file_s_header_names_the_metric_its_colours_encode(tmp_path, color_by, binary):
    """A coloured PLY says which metric its RGB encodes (one header comment), and that
    metric's values are the ones its colours come from; the files still read back as before."""
    from skelcore.io.export import colour_comment

    ev = _evaluation()
    export_ply(ev, tmp_path, color_by=color_by, binary=binary)
    samples_by = color_by if color_by != "smoothness" else "centeredness"  # samples have no smoothness
    for name, metric in (("skeletal", color_by), ("curve", "smoothness"), ("curve_samples", samples_by)):
        ply = PlyData.read(str(tmp_path / f"{name}.ply"))
        said = [c for c in ply.comments if c.startswith("colors:")]
        assert said == [colour_comment(metric)] and said[0].startswith(f"colors: {metric} "), (name, ply.comments)
        vert = ply["vertex"]
        values = {"skeletal": {"boundedness": ev.skeletal.boundedness, "centeredness": ev.skeletal.centeredness(0.75),
                               "smoothness": ev.skeletal.smoothness},
                  "curve": {"smoothness": ev.curve.vertex_smoothness},
                  "curve_samples": {"boundedness": ev.curve.sample_boundedness,
                                    "centeredness": ev.curve.sample_centeredness(0.75)}}[name][metric]
        np.testing.assert_array_equal(_rgb(vert), map_to_rgb(np.asarray(values, dtype=float), 0, 1))
    # a reader of the header alone (no plyfile) sees it too, before end_header
    head = (tmp_path / "skeletal.ply").read_bytes().split(b"end_header")[0].decode("ascii")
    assert f"comment {colour_comment(color_by)}\n" in head
    from skelcore.io import load_points

    assert load_points(tmp_path / "skeletal.ply").shape == ev.skeletal.points.shape


def test_a_mapped_skeleton_s_files_say_which_map_gave_their_coordinates(tmp_path):
    """``mappings``: the files of a skeleton mapped into the cloud's frame name the map in their header;
    an identity map (or none) adds nothing."""
    from skelcore import evaluate, shapes

    s = shapes.cylinder(800, seed=0)
    ev = evaluate(s.cloud, s.skeletal, CurveSkeleton.from_raw(s.curve_vertices, s.curve_edges))

    def headers(folder, **kwargs):
        out = {}
        for path in export_ply(ev, tmp_path / folder, **kwargs):
            text = open(path, "rb").read().split(b"end_header")[0].decode("ascii")
            out[os.path.basename(path)] = [ln for ln in text.splitlines() if ln.startswith("comment mapping:")]
        return out

    got = headers("mapped", mappings={"skeletal": None, "curve": (2.5, (1.0, 0.0, -3.0))})
    assert got["skeletal.ply"] == []
    for name in ("curve.ply", "curve_samples.ply"):
        (line,) = got[name]
        assert "scale 2.5 and offset 1 0 -3" in line
    assert all(v == [] for v in headers("identity", mappings={"curve": (1.0, (0.0, 0.0, 0.0))}).values())
