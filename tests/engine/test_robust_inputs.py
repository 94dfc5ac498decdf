"""Bad input ends in SkelScope's own one-line error or a result, never another exception.

Property-based (hypothesis, few small examples each): random arrays written in every supported
format and read back, random bytes under every suffix, and :func:`skelcore.evaluate` over finite,
huge, tiny, duplicate, degenerate and non-finite clouds, skeletal sets and curves.  The seeded
corruptions of valid files are in test_io_fuzz.py; the hand-written bad files in test_io_errors.py.
"""

from __future__ import annotations

import os
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from test_io_formats import CLOUD_WRITERS, CURVE_WRITERS

import skelcore
from skelcore.errors import SkelInputError
from skelcore.geometry import COORDINATE_LIMIT, EXTENT_LIMIT
from skelcore.io import load_any, load_cloud, load_curve

#: examples per property (a longer search: SKELSCOPE_FUZZ_EXAMPLES=150)
EXAMPLES = int(os.environ.get("SKELSCOPE_FUZZ_EXAMPLES", "6"))
few = settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


def _own_error_or_result(call):
    """Run ``call``; a SkelInputError must be one line. Returns the result or the error."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return call()
    except SkelInputError as err:
        assert "\n" not in str(err), str(err)
        return err


# ---- the regression: coordinates near the float maximum --------------------------------------------

def test_coordinates_near_the_float_maximum_are_refused_in_one_line():
    """points * 1e306 as cloud and skeletal set overflowed the open-surface check's KD-tree distances
    (IndexError in scan.boundary.tangent_frames); now the inputs are refused."""
    pts = np.random.default_rng(0).normal(size=(200, 3))
    with pytest.raises(SkelInputError, match=r"^cloud: coordinates reach .*rescale the points$"):
        skelcore.evaluate(pts * 1e306, pts * 1e306)
    with pytest.raises(SkelInputError, match="skeletal point set: coordinates reach"):
        skelcore.evaluate(pts, pts * 1e306)
    with pytest.raises(SkelInputError, match="curve skeleton: coordinates reach"):
        skelcore.evaluate(pts, curve=(pts[:3] * 1e306, [[0, 1], [1, 2]]))


def test_a_cloud_too_small_for_squared_distances_is_refused_in_one_line():
    pts = np.random.default_rng(0).normal(size=(200, 3))
    with pytest.raises(SkelInputError, match=r"^cloud: the points span only .*rescale the points$"):
        skelcore.evaluate(pts * 1e-160, pts * 1e-160)


def test_paper_boundedness_of_a_collinear_cloud_is_a_value_not_an_index_error():
    """From a point of a line every direction to the others is +-u up to rounding: qhull's triangulation
    of two tiny clusters used its added point at infinity (IndexError in paper_triangles)."""
    rng = np.random.default_rng(92)
    cloud = _degenerate("collinear", int(rng.integers(1, 60)), rng)  # row 22 was the failing query
    ev = skelcore.evaluate(cloud, cloud, params=skelcore.Params(boundedness_method="paper"))
    beta = ev.skeletal.boundedness
    assert np.all((beta >= 0) & (beta <= 1))


def test_the_limits_leave_ordinary_units_alone():
    """Kilometres in millimetres, or nanometres in metres, are far inside the limits."""
    pts = np.random.default_rng(1).normal(size=(60, 3))
    for scale in (1e-30, 1e30):
        ev = skelcore.evaluate(pts * scale, pts * scale)
        assert ev.scores().boundedness_skeletal is not None
    assert COORDINATE_LIMIT >= 1e100 and EXTENT_LIMIT <= 1e-100


# ---- loaders: random arrays in every format, read back ------------------------------------------

finite_coords = st.floats(-1e6, 1e6, allow_nan=False, width=32)
any_coords = st.one_of(finite_coords, st.floats(allow_nan=True, allow_infinity=True),
                       st.sampled_from([0.0, -0.0, 1e-320, 1e300, -1e300]))
clouds = st.integers(1, 8).flatmap(lambda n: st.one_of(
    arrays(np.float64, (n, 3), elements=finite_coords),
    arrays(np.float64, (n, 3), elements=any_coords)))


@pytest.mark.parametrize("name", sorted(CLOUD_WRITERS))
@few
@given(pts=clouds)
def test_random_clouds_in_every_format_load_or_fail_in_one_line(tmp_path, name, pts):
    suffix, writer = CLOUD_WRITERS[name]
    path = tmp_path / f"cloud{suffix}"
    try:
        writer(path, pts)
    except (ValueError, OverflowError):  # a test writer that cannot store the values (int PLY of NaN)
        return
    for loader in (load_cloud, load_any):
        out = _own_error_or_result(lambda: loader(path))
        if isinstance(out, SkelInputError):
            assert path.name in str(out)
        elif loader is load_cloud and np.all(np.isfinite(pts)):
            assert out.shape == pts.shape


@st.composite
def graphs(draw):
    n = draw(st.integers(1, 7))
    v = draw(arrays(np.float64, (n, 3), elements=st.one_of(finite_coords, st.just(np.nan))))
    m = draw(st.integers(0, 8))
    e = draw(arrays(np.int64, (m, 2), elements=st.integers(0, n - 1)))
    return v, e


@pytest.mark.parametrize("name", sorted(CURVE_WRITERS))
@few
@given(curve=graphs())
def test_random_curves_in_every_format_load_or_fail_in_one_line(tmp_path, name, curve):
    suffix, writer = CURVE_WRITERS[name]
    path = tmp_path / f"curve{suffix}"
    try:
        writer(path, *curve)
    except (ValueError, OverflowError, IndexError, KeyError):  # the test writers assume a tidy graph
        return
    for loader in (load_curve, load_any):
        out = _own_error_or_result(lambda: loader(path))
        if isinstance(out, SkelInputError):
            assert path.name in str(out)


SUFFIXES = sorted({s for s, _ in CLOUD_WRITERS.values()} | {s for s, _ in CURVE_WRITERS.values()}
                  | {".swc", ".las", ".mat", ".graphml", ".gexf", ".bin", ""})


@few
@given(data=st.binary(max_size=300), head=st.sampled_from([b"", b"ply\n", b"\x93NUMPY", b"PK\x03\x04", b"[",
                                                           b"# .PCD v0.7\n", b"LASF", b"<?xml", b"1 1 "]))
def test_random_bytes_under_every_suffix_load_or_fail_in_one_line(tmp_path, data, head):
    for suffix in SUFFIXES:
        path = tmp_path / f"garbage{suffix}"
        path.write_bytes(head + data)
        for loader in (load_cloud, load_curve, load_any):
            out = _own_error_or_result(lambda: loader(path))
            if isinstance(out, SkelInputError):
                assert path.name in str(out)


# ---- evaluate: random and degenerate inputs ----------------------------------------------------------

def _degenerate(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    base = rng.normal(size=(n, 3))
    if kind == "collinear":
        return np.outer(rng.normal(size=n), rng.normal(size=3)) + rng.normal(size=3)
    if kind == "coplanar":
        return np.column_stack([base[:, :2], np.full(n, 0.5)])
    if kind == "duplicates":
        return np.repeat(base[: max(1, n // 4)], 4, axis=0)[:n]
    if kind == "one point":
        return base[:1]
    if kind == "two points":
        return base[:2]
    if kind == "coincident":
        return np.tile(base[:1], (n, 1))
    return base


scales = st.sampled_from([1.0, 1e-90, 1e-120, 1e90, 1e120, 1e306])
kinds = st.sampled_from(["random", "collinear", "coplanar", "duplicates", "one point", "two points",
                         "coincident"])


@few
@given(kind=kinds, n=st.integers(1, 40), scale=scales, seed=st.integers(0, 2**16),
       spoil=st.sampled_from([None, np.nan, np.inf, -np.inf]),
       skeletal=st.sampled_from(["same", "half", "reverse", "none"]), method=st.sampled_from(["rays", "paper"]),
       scan=st.booleans())
def test_evaluate_on_degenerate_clouds_ends_in_a_result_or_one_line(kind, n, scale, seed, spoil, skeletal, method,
                                                                    scan):
    rng = np.random.default_rng(seed)
    cloud = _degenerate(kind, n, rng) * scale
    if spoil is not None:
        cloud[rng.integers(len(cloud)), rng.integers(3)] = spoil
    skel = {"same": cloud, "half": cloud[: max(1, len(cloud) // 2)], "reverse": cloud[:3], "none": None}[skeletal]
    corr = "reverse" if skeletal == "reverse" else "auto"
    params = skelcore.Params(boundedness_method=method)
    out = _own_error_or_result(lambda: skelcore.evaluate(cloud, skel, params=params, correspondence=corr,
                                                         remove_outliers=scan, cap_openings=scan))
    if not isinstance(out, SkelInputError):
        out.scores()


@few
@given(n=st.integers(1, 6), scale=scales, seed=st.integers(0, 2**16), nan_vertex=st.booleans(),
       n_cloud=st.integers(2, 30))
def test_evaluate_with_random_curves_ends_in_a_result_or_one_line(n, scale, seed, nan_vertex, n_cloud):
    rng = np.random.default_rng(seed)
    cloud = rng.normal(size=(n_cloud, 3))
    v = rng.normal(size=(n, 3)) * scale
    if nan_vertex:
        v[rng.integers(n)] = np.nan
    e = rng.integers(0, n, size=(int(rng.integers(0, 2 * n + 1)), 2))
    out = _own_error_or_result(lambda: skelcore.evaluate(cloud, curve=(v, e)))
    if not isinstance(out, SkelInputError):
        out.scores()
