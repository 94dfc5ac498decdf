"""Curve centeredness' compiled rings (``_rings.c``) and ellipse sums against the array code they replace
(docs/performance.md 6.5): the same bits, ties and degenerate slabs included."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore.curve import CurveSkeleton
from skelcore.metrics import _rings, centeredness
from skelcore.metrics.curve_sampling import sample_curve
from skelcore.metrics.ellipse_fit import _reference_sums, ellipse_sums
from skelcore.params import Params
from skelcore.shapes import torus, y_shape


def _lattice() -> np.ndarray:
    """Square rings of integer points stacked along z: exact ties of 2-D distance."""
    side = [(x, y) for x in range(-4, 5) for y in range(-4, 5) if max(abs(x), abs(y)) == 4]
    return np.array([(x, y, z) for z in range(20) for x, y in side], dtype=float)


def _cases(scans):
    """(name, cloud, sample points, directions, slab factor)."""
    from plyfile import PlyData

    from skelcore.geometry import Normalization

    rng = np.random.default_rng(21)
    vertex = PlyData.read(str(scans / "hammer_4096.ply"))["vertex"]
    raw = np.column_stack([vertex["x"], vertex["y"], vertex["z"]]).astype(float)
    hammer = Normalization.from_cloud(raw).apply(raw)
    branch = y_shape(6000, seed=2)
    on_axis = sample_curve(CurveSkeleton.from_raw(branch.curve_vertices, branch.curve_edges), 60)
    ring = torus(5000, 1.0, 0.3, seed=3).cloud
    lattice = _lattice()
    lat_pts = np.column_stack([rng.integers(-2, 3, (40, 2)), rng.integers(1, 19, 40)]).astype(float)
    twice = np.repeat(rng.normal(size=(1500, 3)), 3, axis=0)  # every point three times
    sheet = np.column_stack([rng.uniform(0, 1, 3000), rng.uniform(0, 0.3, 3000), np.zeros(3000)])
    blob = rng.normal(size=(4000, 3))
    far = np.vstack([blob[:20] * 0.5, [[40.0, 0, 0], [0, -40.0, 0], [0, 0, 60.0]]])  # slabs empty or far away
    return [
        ("y on its axis", branch.cloud, on_axis.points, on_axis.directions, 0.02),  # exact ties on the tube
        ("y, random", branch.cloud, branch.cloud[rng.choice(6000, 40)] * 0.5, rng.normal(size=(40, 3)), 0.05),
        ("torus", ring, ring[rng.choice(len(ring), 40)] * 0.9, rng.normal(size=(40, 3)), 0.02),
        ("hammer", hammer, hammer[rng.choice(len(hammer), 40)] * 0.8, rng.normal(size=(40, 3)), 0.02),
        ("lattice, z", lattice, lat_pts, np.tile([0.0, 0.0, 1.0], (40, 1)), 0.05),
        ("lattice, thick", lattice * 0.1, lat_pts * 0.1, np.tile([0.0, 0.0, 1.0], (40, 1)), 0.3),
        ("lattice, tilted", lattice, lat_pts, rng.normal(size=(40, 3)) * [0.1, 0.1, 1.0], 0.05),
        ("duplicates", twice, twice[rng.choice(len(twice), 40)] * 0.5, rng.normal(size=(40, 3)), 0.02),
        ("sheet across", sheet, sheet[rng.choice(3000, 20)], np.tile([1.0, 0.0, 0.0], (20, 1)), 0.02),
        ("sheet in plane", sheet, sheet[rng.choice(3000, 20)], np.tile([0.0, 0.0, 1.0], (20, 1)), 0.02),
        ("blob, far samples", blob, far, rng.normal(size=(len(far), 3)), 0.02),
    ]


def _rings_both_ways(monkeypatch, cloud, points, dirs, slab, flag="_COMPILED_RINGS"):
    """The rings with ``centeredness.<flag>`` False (the array code; hypot for every point) and True."""
    params = Params(slab_factor=slab)
    grid = centeredness.slab_grid(cloud, params)
    half = 0.5 * slab * float(np.linalg.norm(grid.hi - grid.lo))
    u = centeredness.unit_rows(dirs)
    g, h = centeredness._orthonormal_complement(u)
    out = []
    for on in (False, True):
        monkeypatch.setattr(centeredness, flag, on)
        out.append(centeredness._ring_columns(grid, points, u, g, h, half, params.ring_growth))
    return out


def test_compiled_rings_are_the_array_codes_bit_for_bit(monkeypatch, scans):
    """Every sample's ring (plane coordinates in ring order, and the starts) from the kernel equals the array
    code's: a branching shape on and off its axis, a torus, the hammer scan, an integer lattice (exact ties,
    rings cut inside a tie run), repeated points, a flat sheet cut across and in its plane, samples whose
    slab is empty; the rings must hold ties between distinct points, so a kernel that orders equal distances
    otherwise than the grid's rows fails here."""
    tied = 0
    for name, cloud, points, dirs, slab in _cases(scans):
        (x0, y0, s0), (x1, y1, s1) = _rings_both_ways(monkeypatch, cloud, points, dirs, slab)
        assert s1.tobytes() == s0.tobytes(), name
        assert x1.tobytes() == x0.tobytes() and y1.tobytes() == y0.tobytes(), name
        d = np.hypot(x0, y0)
        same = (d[1:] == d[:-1]) & ((x0[1:] != x0[:-1]) | (y0[1:] != y0[:-1]))
        cut = s0[(s0 > 0) & (s0 < len(d))]
        same[cut - 1] = False  # not across two rings
        tied += int(same.sum())
    assert tied > 1000


def test_compiled_rings_a_neuron(monkeypatch):
    """A real neuron at 30k points with its traced curve (thin branches, a soma's rings of thousands)."""
    from skelcore.benchmark.neurons import MeshSampler, load_neuron

    nr = load_neuron("722817260")
    sampler = MeshSampler(nr.mesh, nr.skeleton.vertices, nr.skeleton.radius)
    cloud = sampler.sample(30_000, np.random.default_rng(0)).points
    samples = sample_curve(nr.skeleton, 300)
    keep = np.all(np.isfinite(samples.directions), axis=1)
    points, dirs = samples.points[keep][::3], samples.directions[keep][::3]
    (x0, y0, s0), (x1, y1, s1) = _rings_both_ways(monkeypatch, cloud, points, dirs, 0.02)
    assert s1.tobytes() == s0.tobytes() and x1.tobytes() == x0.tobytes() and y1.tobytes() == y0.tobytes()
    assert np.diff(s0).max() > 1000 and (np.diff(s0) >= 3).sum() > 20


@pytest.mark.parametrize("at_once", [0, 10**12])
def test_compiled_centeredness_is_the_array_codes(monkeypatch, scans, at_once):
    """curve_centeredness with the kernel equals the array code on both paths (spans on threads, batches)."""
    monkeypatch.setattr(centeredness, "_CURVE_AT_ONCE", at_once)
    finite = 0
    for name, cloud, points, dirs, slab in _cases(scans):
        dirs = dirs.copy()
        dirs[3] = np.nan
        got = []
        for compiled in (False, True):
            monkeypatch.setattr(centeredness, "_COMPILED_RINGS", compiled)
            got.append(centeredness.curve_centeredness(cloud, points, dirs, params=Params(slab_factor=slab)))
        assert got[1].tobytes() == got[0].tobytes(), name
        finite += int(np.isfinite(got[0]).sum())
    assert finite > 200


def test_rings_kernel_rejects_inconsistent_arrays():
    grid = centeredness.slab_grid(np.random.default_rng(0).normal(size=(100, 3)))
    p = np.zeros((1, 3))
    u = np.array([[0.0, 0.0, 1.0]])
    fx, fy, bounds = np.empty(200), np.empty(200), np.zeros(2, np.int64)
    args = [grid.columns, grid.keys, grid.starts, grid.counts, grid.lines, grid.centres, grid.frame, grid.dims,
            p, u, np.array([[1.0, 0, 0]]), np.array([[0.0, 1, 0]]), 0.1, 1.5, 0.05, fx, fy, bounds, 0]
    assert _rings.rings(*args) == (1, 0)
    bad = list(args)
    bad[1] = grid.keys[::-1].copy()  # keys out of order
    with pytest.raises(ValueError, match="rings"):
        _rings.rings(*bad)
    bad = list(args)
    bad[9] = np.zeros((2, 3))  # directions for another number of samples
    with pytest.raises(ValueError, match="rings"):
        _rings.rings(*bad)
    for at, value in ((15, np.empty(100)), (17, np.zeros(3, np.int64)), (18, 201)):  # unequal buffers, bounds, offset
        bad = list(args)
        bad[at] = value
        with pytest.raises(ValueError, match="rings"):
            _rings.rings(*bad)


def test_rings_that_outgrow_the_buffers_go_on_from_the_sample_that_did_not_fit(monkeypatch, scans):
    """The kernel writes into kept buffers and stops at a ring that does not fit; the buffers grow and it
    goes on from there: buffers of 8 rows (a regrowth at nearly every sample) and a sample with an empty
    ring first give the rings of one call with room for all; the grid lends its kept buffers again."""
    name, cloud, points, dirs, slab = _cases(scans)[0]
    params = Params(slab_factor=slab)
    grid = centeredness.slab_grid(cloud, params)
    half = 0.5 * slab * float(np.linalg.norm(grid.hi - grid.lo))
    u = centeredness.unit_rows(np.vstack([[1.0, 0, 0], dirs]))
    g, h = centeredness._orthonormal_complement(u)
    points = np.vstack([[1e3, 1e3, 1e3], points])  # an empty slab: a ring of no point
    got = []
    for rows in (1 << 20, 8):
        monkeypatch.setattr(centeredness, "_RING_ROWS", rows)
        bufs = centeredness._RingBuffers()
        x, y, s = centeredness._kernel_rings(grid, points, u, g, h, half, params.ring_growth, bufs)
        got.append((x.copy(), y.copy(), s.copy()))
        assert rows > 8 or len(bufs.fx) >= s[-1] > 8
    (x0, y0, s0), (x1, y1, s1) = got
    assert s0[1] == 0 and s0.tobytes() == s1.tobytes() and x0.tobytes() == x1.tobytes() and y0.tobytes() == y1.tobytes()
    with grid.ring_buffers() as lent:
        centeredness._kernel_rings(grid, points, u, g, h, half, params.ring_growth, lent)
        with grid.ring_buffers() as other:  # a second caller at the same time gets its own
            assert other is not lent
    with grid.ring_buffers() as again:
        assert again is other or again is lent


def test_rings_ordered_by_square_roots_are_those_by_hypot(monkeypatch, scans):
    """The kernel orders distances by the square roots of their squares and takes libm's hypot only where two
    come within 1e-13, or one within 1e-13 of R or of a ring's growth: the same rings as hypot for every
    point on every case (exact ties, repeated points, a tube's exact radius, where it falls back to hypot),
    and where the ring's growth rule reads the two differently: a point at hypot distance exactly 1.5 x the
    last one's hypot (so not in the ring), whose square root is below 1.5 x that one's square root."""
    a = np.array([0.04746668208702611, 0.06957808520711659])  # sqrt(x^2 + y^2) one unit above its hypot
    reach = 1.5 * float(np.hypot(*a))
    assert np.sqrt(a @ a) > np.hypot(*a) and 1.5 * np.sqrt(a @ a) > reach
    corners = np.array([[x, y, z] for x in (-10.0, 10.0) for y in (-10.0, 10.0) for z in (-10.0, 10.0)])
    ring = np.array([[a[0], a[1], 0.0], [0.9 * a[1], -0.9 * a[0], 0.0], [-0.8 * a[0], 0.8 * a[1], 0.0],
                     [0.7 * a[1], 0.7 * a[0], 0.0], [-0.6 * a[1], -0.6 * a[0], 0.0], [0.0, reach, 0.0]])
    edge = (np.vstack([corners, ring]), np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), 0.02)
    cases = [c[1:] for c in _cases(scans)] + [edge]
    for cloud, points, dirs, slab in cases:
        (x0, y0, s0), (x1, y1, s1) = _rings_both_ways(monkeypatch, cloud, points, dirs, slab, "_BY_ROOTS")
        assert s1.tobytes() == s0.tobytes() and x1.tobytes() == x0.tobytes() and y1.tobytes() == y0.tobytes()
    assert s1.tolist() == [0, 5]  # the edge case's ring stops before the point at 1.5 x


@pytest.mark.parametrize("chunk, rows", [(1, 1), (3, 50), (1000, 1 << 18)])
def test_a_spans_rings_in_chunks_give_the_same_centeredness(monkeypatch, scans, chunk, rows):
    """A span's samples go to the kernel in chunks (``_RING_CHUNK`` first, then about ``_RING_CHUNK_ROWS``
    ring points each), their fits' sums joined: the same bits for chunks of one sample, of a few and of all
    (spans of 7 samples on threads, the array code the reference)."""
    monkeypatch.setattr(centeredness, "_CURVE_AT_ONCE", 0)
    monkeypatch.setattr(centeredness, "_RING_CHUNK", chunk)
    monkeypatch.setattr(centeredness, "_RING_CHUNK_ROWS", rows)
    name, cloud, points, dirs, slab = _cases(scans)[3]
    got = []
    for compiled in (False, True):
        monkeypatch.setattr(centeredness, "_COMPILED_RINGS", compiled)
        got.append(centeredness.curve_centeredness(cloud, points, dirs, params=Params(slab_factor=slab), span=7))
    assert got[1].tobytes() == got[0].tobytes() and np.isfinite(got[0]).sum() > 20


def test_ellipse_sums_are_the_numpy_loops_bit_for_bit():
    """The compiled centroids, radii and design rows (docs/performance.md 6.5) give numpy's sums: running
    sums, a pairwise mean at sizes below, at and above numpy's blocks (8, 128, 8192), sets of fewer than 5
    points, non-finite points, finite points whose sum overflows, a zero radius, sets spread over several calls."""
    rng = np.random.default_rng(4)
    for trial in range(24):
        sizes = rng.integers(0, int(rng.choice([12, 300, 20000])), size=int(rng.integers(1, 120)))
        if trial % 3 == 0:
            sizes = np.r_[sizes, 7, 8, 9, 127, 128, 129, 8192, 8193]
        starts = np.r_[0, np.cumsum(sizes)]
        t = rng.uniform(0, 2 * np.pi, starts[-1])
        x = np.cos(t) * rng.uniform(0.5, 2.0) * 10.0 ** rng.integers(-3, 3) + rng.normal(scale=0.05, size=len(t))
        y = np.sin(t) + rng.normal(scale=0.05, size=len(t))
        if len(sizes) > 3:
            x[starts[1] : starts[2]], y[starts[1] : starts[2]] = 1.0, 2.0  # all points equal: radius 0
            x[starts[2]] = np.nan
        if len(sizes) > 6 and sizes[3:6].min() >= 2:
            # inf and -inf (a NaN sum), one inf, finite points whose sum overflows
            x[starts[3]], x[starts[3] + 1], y[starts[4]] = np.inf, -np.inf, np.inf
            x[starts[5] : starts[6]] = 1e308
        with np.errstate(over="ignore", invalid="ignore"):  # the overflowing set's numpy reference
            got, want = ellipse_sums(x, y, starts), _reference_sums(x, y, starts)
        for a, b in zip(got, want):
            assert a.shape == b.shape and a.tobytes() == b.tobytes()
        assert len(want.use) > 0 or sizes.max() < 5


def test_a_ring_that_reaches_the_first_ball_s_edge_keeps_its_outer_points(monkeypatch):
    """The kernel computes a pool point's distance only when its squared plane distance does not put it
    beyond the ball's reach R already (REACH_SLACK in _rings.c). Two circles about the sample, the inner at
    R / growth (the ring would end there if nothing lay between it and R) and the outer just inside R: a
    bound that left out points at up to 1 % below R would drop the outer circle from the first ball and end
    the ring at the inner one."""
    params = Params()
    growth = float(params.ring_growth)
    corners = np.array([[x, y, z] for x in (-10.0, 10.0) for y in (-10.0, 10.0) for z in (-10.0, 10.0)])
    grid = centeredness.slab_grid(corners, params)
    half = 0.5 * params.slab_factor * float(np.linalg.norm(grid.hi - grid.lo))
    first = centeredness._BALL_FIRST * half
    angle = np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)
    circle = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(24)])
    inner, outer = 0.998 * first / growth, 0.995 * first
    assert outer < growth * inner
    cloud = np.vstack([corners, inner * circle, outer * circle + [0.0, 0.0, 1e-3 * half]])
    points, dirs = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    (x0, y0, s0), (x1, y1, s1) = _rings_both_ways(monkeypatch, cloud, points, dirs, params.slab_factor)
    assert s0.tolist() == [0, 48]  # both circles in the ring
    assert s1.tobytes() == s0.tobytes() and x1.tobytes() == x0.tobytes() and y1.tobytes() == y0.tobytes()


def test_each_ring_of_one_call_is_its_ring_alone():
    """What a kernel call carries from sample to sample (its buffers, the order by square roots given up
    after rings of one exact radius) changes no ring: samples alternating between a thick and a thin tube,
    and a sample whose slab is empty, in one call give the rings each gives alone, bit for bit."""
    rng = np.random.default_rng(5)
    t = rng.uniform(0.0, 2.0 * np.pi, 8000)
    z = rng.uniform(0.0, 10.0, 8000)
    thick = np.column_stack([np.cos(t), np.sin(t), z])
    thin = np.column_stack([0.05 * np.cos(t), 0.05 * np.sin(t), z + 20.0])
    cloud = np.vstack([thick, thin, [[0.0, 0.0, 60.0]]])
    params = Params(slab_factor=0.01)
    grid = centeredness.slab_grid(cloud, params)
    half = 0.5 * params.slab_factor * float(np.linalg.norm(grid.hi - grid.lo))
    points = np.array([[0.0, 0.0, 3.0], [0.0, 0.0, 23.0], [0.0, 0.0, 5.0], [0.0, 0.0, 45.0], [0.0, 0.0, 25.0],
                       [0.0, 0.0, 27.0], [0.1, 0.0, 7.0], [0.0, 0.0, 8.0]])
    u = centeredness.unit_rows(np.tile([0.0, 0.0, 1.0], (len(points), 1)) + rng.normal(0, 0.01, (len(points), 3)))
    g, h = centeredness._orthonormal_complement(u)
    x, y, s = (a.copy() for a in centeredness._kernel_rings(grid, points, u, g, h, half, params.ring_growth))
    size = [float(np.hypot(x[a:b], y[a:b]).max()) if b > a else 0.0 for a, b in zip(s[:-1], s[1:])]
    assert size[3] == 0.0 and min(size[0], size[2]) > 10 * max(size[1], size[4], size[5]) > 0  # empty; thick, thin
    for i in range(len(points)):
        xi, yi, si = centeredness._kernel_rings(grid, points[i:i + 1], u[i:i + 1], g[i:i + 1], h[i:i + 1], half,
                                                params.ring_growth)
        assert xi.tobytes() == x[s[i]:s[i + 1]].tobytes() and yi.tobytes() == y[s[i]:s[i + 1]].tobytes()


def test_rings_of_slabs_along_and_across_the_grid_s_lines(monkeypatch):
    """The kernel narrows each line of cells (along x) to the cells that may meet the slab and the ball: slabs
    square to the lines (u along x), along them (u with no x part, or a tiny one), oblique, around a torus
    whose large rings need several balls and a hint from the sample before; the rings equal the array code's
    and one call's rings are each sample's alone."""
    shape = torus(12_000, R=1.0, r=0.3, n_curve=8, seed=3)
    rng = np.random.default_rng(8)
    cloud = shape.cloud + rng.normal(scale=1e-3, size=shape.cloud.shape)
    angle = np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)
    points = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(24)])
    tangent = np.column_stack([-np.sin(angle), np.cos(angle), np.zeros(24)])
    dirs = np.vstack([tangent, [[1.0, 0.0, 0.0]] * 3, [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1e-9, 1.0, 0.0],
                                                        [1e-5, 0.0, 1.0], [0.3, 0.4, 0.5]]])
    points = np.vstack([points, [[0.0, 1.0, 0.0], [0.0, -1.0, 0.1], [1.0, 0.0, 0.0]], points[:5]])
    for slab in (0.02, 0.06):
        (x0, y0, s0), (x1, y1, s1) = _rings_both_ways(monkeypatch, cloud, points, dirs, slab)
        assert s1.tobytes() == s0.tobytes() and x1.tobytes() == x0.tobytes() and y1.tobytes() == y0.tobytes()
        assert (np.diff(s0) >= 100).sum() > 20
    params = Params()
    grid = centeredness.slab_grid(cloud, params)
    half = 0.5 * params.slab_factor * float(np.linalg.norm(grid.hi - grid.lo))
    u = centeredness.unit_rows(dirs)
    g, h = centeredness._orthonormal_complement(u)
    x, y, s = (a.copy() for a in centeredness._kernel_rings(grid, points, u, g, h, half, params.ring_growth))
    for i in range(len(points)):
        xi, yi, _ = centeredness._kernel_rings(grid, points[i:i + 1], u[i:i + 1], g[i:i + 1], h[i:i + 1], half,
                                               params.ring_growth)
        assert xi.tobytes() == x[s[i]:s[i + 1]].tobytes() and yi.tobytes() == y[s[i]:s[i + 1]].tobytes()
