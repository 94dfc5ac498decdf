"""A ``skelcore compare`` run (docs/compare.md): three generated 4096-point shapes (a cylinder, a torus,
a Y shape) x two methods (the built-in skeletonizer, and an external command drawing the principal
axis) under the normal condition, six jobs into a fresh folder each round (no job skipped), no report,
in this process (the serial backend: the jobs' own time and the driver's, without a pool's start-up)."""

from __future__ import annotations

import shlex
import sys
import tempfile
from pathlib import Path

import pytest

from skelcore import shapes
from skelcore.compare import Backend, run_compare
from skelcore.io import write_points_ply

N_POINTS = 4096
JOBS = 6

AXIS = """
import sys, numpy as np
from skelcore.io import load_cloud, write_curve_ply
c = load_cloud(sys.argv[1]); m = c.mean(axis=0); u = np.linalg.svd(c - m, full_matrices=False)[2][0]
t = (c - m) @ u; v = m + np.outer(np.linspace(t.min(), t.max(), 16), u)
write_curve_ply(sys.argv[2], v, np.column_stack([np.arange(15), np.arange(1, 16)]))
"""


@pytest.fixture(scope="module")
def manifest(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("compare")
    (root / "clouds").mkdir()
    for name, shape in (("cylinder", shapes.cylinder(N_POINTS, seed=0)), ("torus", shapes.torus(N_POINTS, seed=0)),
                        ("yshape", shapes.y_shape(N_POINTS, seed=0))):
        write_points_ply(root / "clouds" / f"{name}.ply", shape.cloud)
    (root / "axis.py").write_text(AXIS)
    cmd = f"{shlex.quote(sys.executable)} axis.py {{in}} {{out_curve}}"
    (root / "m.toml").write_text(f"""
[[shapes]]
path = "clouds/*.ply"
[[methods]]
name = "builtin"
kind = "builtin"
[[methods]]
name = "axis"
kind = "command"
command = "{cmd}"
[[conditions]]
name = "normal"
""")
    return root / "m.toml"


def test_compare_run_serial(measure, benchmark, manifest):
    backend = Backend("serial")

    def fresh_folder():
        return (manifest, Path(tempfile.mkdtemp(prefix="bench-compare-", dir=manifest.parent)) / "out", backend), \
            {"report": False}

    res = measure(run_compare, setup=fresh_folder, rounds=3)
    assert res.summary.ok == JOBS, [r.get("error") for r in res.summary.records if r["status"] != "ok"][:3]
    recs = [r for r in res.summary.records if "started" in r]
    benchmark.extra_info.update(jobs=JOBS, n_points=N_POINTS, sum_of_job_s=round(sum(r["seconds"] for r in recs), 3))
