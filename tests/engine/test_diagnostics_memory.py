"""Bounded memory of the diagnostics (docs/diagnostics.md "Peak memory"): the spur test's
neighbour search against a brute-force answer, and a traced neuron with an edge between two far
leaves evaluated under a memory cap."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from skelcore.diagnostics import spurs

NEURONS = Path(__file__).resolve().parents[2] / "resources" / "neurons"


def _brute(pts, pb, reach, q, own):
    d = np.linalg.norm(q[:, None, :] - pts[None], axis=2)
    return ((d <= reach[None]) & (pb[None] != own[:, None])).any(axis=1)


@pytest.mark.parametrize("k_max", [16, 256])
def test_explained_elsewhere_matches_brute_force(monkeypatch, k_max):
    """Small balls on five branches and one branch of huge balls (an edge through the air): the
    answer does not depend on how far the k-nearest search goes before the per-branch search."""
    monkeypatch.setattr(spurs, "_K_MAX", k_max)
    rng = np.random.default_rng(1)
    pts = rng.uniform(0, 1, (1500, 3))
    pb = rng.integers(0, 5, len(pts))
    reach = rng.uniform(0.01, 0.08, len(pts))
    pb[:300] = 5
    reach[:300] = rng.uniform(0.5, 2.0, 300)
    q = rng.uniform(0, 1, (2000, 3))
    own = rng.integers(0, 6, len(q))
    got = spurs._explained_elsewhere(pts, pb, reach, q, own)
    np.testing.assert_array_equal(got, _brute(pts, pb, reach, q, own))
    assert 0 < got.sum() < len(q)


_CHILD = textwrap.dedent("""
    import json, resource, sys
    import numpy as np
    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))


    def _peak_mb():
        # this process's own high-water mark (VmHWM); getrusage's ru_maxrss keeps the forking parent's
        # peak across exec, so a child of a large test worker reads the worker's size
        for line in open("/proc/self/status"):
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024


    from skelcore.curve import CurveSkeleton
    from skelcore.diagnostics.defects import find_curve_defects
    from skelcore.io.loaders import load_curve

    base = sys.argv[1]
    v, f = [], []
    for line in open(base + ".obj"):
        if line.startswith("v "):
            v.append(line.split()[1:4])
        elif line.startswith("f "):
            f.append([int(t.split("/")[0]) - 1 for t in line.split()[1:4]])
    v, f = np.asarray(v, float), np.asarray(f)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    area = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    rng = np.random.default_rng(0)
    tri = rng.choice(len(f), 60000, p=area / area.sum())
    u, w = rng.random((2, 60000, 1))
    flip = u + w > 1
    u, w = np.where(flip, 1 - u, u), np.where(flip, 1 - w, w)
    cloud = a[tri] + u * (b[tri] - a[tri]) + w * (c[tri] - a[tri])
    curve = load_curve(base + ".swc")
    leaves = np.flatnonzero(curve.degrees() == 1)
    lv = curve.vertices[leaves]
    far = np.unravel_index(np.argmax(np.linalg.norm(lv[:, None] - lv[None], axis=2)), (len(lv), len(lv)))
    edges = np.vstack([curve.edges, np.sort(leaves[list(far)])[None]])
    lo, s = cloud.min(0), 1.0 / np.ptp(cloud, axis=0).max()
    curve = CurveSkeleton.from_raw((curve.vertices - lo) * s, edges)
    found = find_curve_defects((cloud - lo) * s, curve)
    print(json.dumps({"codes": [w.code for w in found.warnings()], "cycles": len(found.branches.cycles),
                      "peak_mb": _peak_mb()}))
""")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS caps memory on Linux")
def test_far_shortcut_on_a_neuron_stays_under_a_memory_cap():
    """A traced neuron (60k cloud points) with one edge between its two farthest leaves: the curve's
    diagnostics end under a 3 GB address-space cap with a verdict."""
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    run = subprocess.run([sys.executable, "-c", _CHILD, str(NEURONS / "754534424")], capture_output=True,
                         text=True, timeout=120, env=env)
    assert run.returncode == 0, run.stderr[-2000:]
    out = json.loads(run.stdout.strip().splitlines()[-1])
    assert "spurious_branches" in out["codes"] and out["cycles"] >= 1
    assert out["peak_mb"] < 1024
