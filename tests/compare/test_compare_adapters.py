"""Other skeletonizers by name: ``kind = "pygel"``, ``"kimimaro"``, ``"skimage"`` in a
compare manifest, run with the real libraries (the ``[skeletonizers]`` extra, in the ``test`` extra) on a
cylinder and a Y whose exact skeletons are known (skelcore.shapes)."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from compare_helpers import manifest
from skelcore import shapes
from skelcore.adapters import EXTRA, run
from skelcore.adapters.registry import ADAPTER_REVISION, ADAPTERS
from skelcore.cli import main
from skelcore.compare.finished_run import open_run
from skelcore.compare.jobs import Job, _job_key, make_jobs
from skelcore.compare.manifest import load_manifest
from skelcore.correspondence import densify_curve, project_onto_curve
from skelcore.curve import CurveSkeleton
from skelcore.errors import SkelInputError
from skelcore.io import write_points_ply

ROOT = Path(__file__).resolve().parents[2]
SHAPES = {"cyl": lambda: shapes.cylinder(1500, seed=3), "yshape": lambda: shapes.y_shape(2000, seed=4)}
TOOLS = """
[[shapes]]
path = "clouds/*.ply"
[[methods]]
name = "pg"
kind = "pygel"
[[methods]]
name = "kimi"
kind = "kimimaro"
timeout = 300
[[methods]]
name = "thin"
kind = "skimage"
"""


def _dataset(root: Path) -> Path:
    (root / "clouds").mkdir(parents=True, exist_ok=True)
    for stem, make in SHAPES.items():
        write_points_ply(root / "clouds" / f"{stem}.ply", make().cloud)
    return root


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """One compare run of the three tools on both shapes (6 jobs)."""
    root = _dataset(tmp_path_factory.mktemp("adapters"))
    out = root / "out"
    assert main(["compare", str(manifest(root, TOOLS)), "--out", str(out), "--jobs", "2", "--no-report"]) == 0
    return open_run(out)


def _distance_to(points: np.ndarray, curve: CurveSkeleton) -> np.ndarray:
    proj, _ = project_onto_curve(points, curve)
    return np.linalg.norm(points - proj, axis=1)


def _radius_at(shape: shapes.Shape, points: np.ndarray) -> np.ndarray:
    """The shape's local radius at the skeletal point nearest each point."""
    return shapes.local_radius(shape)[cKDTree(shape.skeletal).query(points)[1]]


def test_every_tool_job_finishes_with_its_correspondence(run_dir):
    for job in run_dir.jobs:
        assert run_dir.status(job) == ("ok", ""), job.label
        ev = run_dir.evaluation(job)
        if job.method == "pg":  # PyGEL maps every point to a skeleton node: a pointwise skeletal set
            assert ev.correspondence == "pointwise" and len(ev.skeletal.points) == len(ev.cloud)
        else:  # the voxel tools map no point: the cloud is projected onto their curve
            assert ev.correspondence == "reverse" and ev.curve is not None
            report = run_dir.record(job)["adapter"]  # the voxel size used is in the job's record
            assert report["voxel_size_source"] == "spacing" and report["voxel_size"] > 0
            assert report["voxels"] > 0 and len(report["grid"]) == 3


@pytest.mark.parametrize("method", ["kimi", "thin"])
@pytest.mark.parametrize("stem", list(SHAPES))
def test_voxel_tools_follow_the_true_axis(run_dir, method, stem):
    """Mean distance of the curve to the exact skeleton < 0.5 local radius, both ways (the curve lies on
    the axis, and the axis is near the curve), and no cycle on these tree shapes."""
    shape = SHAPES[stem]()
    truth = CurveSkeleton.from_raw(shape.curve_vertices, shape.curve_edges)
    curve = run_dir.evaluation(run_dir.find(stem, method)).curve.curve
    out = _distance_to(curve.vertices, truth) / _radius_at(shape, curve.vertices)
    samples, _ = densify_curve(truth, 0.02)
    back = _distance_to(samples, curve) / _radius_at(shape, samples)
    assert out.mean() < 0.5 and back.mean() < 0.5, (out.mean(), back.mean())
    assert curve.n_edges - curve.n_vertices + 1 == 0  # one connected tree


@pytest.mark.parametrize("stem", list(SHAPES))
def test_pygel_maps_each_point_to_the_centroid_of_its_separator_region(run_dir, stem):
    """What PyGEL's LS skeleton of a surface kNN graph honestly gives (docs/skeletonizers.md): a graph of
    nodes each standing for a region of the surface, at the centroid of the points mapped to it (so inside
    the convex tube, within the local radius of the axis), not a curve on the axis."""
    shape = SHAPES[stem]()
    ev = run_dir.evaluation(run_dir.find(stem, "pg"))
    np.testing.assert_array_equal(ev.cloud, shape.cloud)
    nodes, which = np.unique(ev.skeletal.points, axis=0, return_inverse=True)
    which = which.ravel()
    centroids = np.stack([np.bincount(which, weights=shape.cloud[:, d]) for d in range(3)], axis=1)
    centroids /= np.bincount(which)[:, None]
    np.testing.assert_allclose(nodes, centroids, atol=1e-9)
    curve = ev.curve.curve
    assert len(nodes) <= curve.n_vertices < len(shape.cloud) / 2  # a node may stand for no point
    assert cKDTree(curve.vertices).query(nodes)[0].max() == 0.0  # every mapped position is a curve vertex
    truth = CurveSkeleton.from_raw(shape.curve_vertices, shape.curve_edges)
    assert np.all(_distance_to(curve.vertices, truth) <= 1.1 * _radius_at(shape, curve.vertices))


@pytest.mark.parametrize("kind", list(ADAPTERS))
def test_the_skeleton_follows_a_scaled_and_shifted_cloud(kind):
    """Frame round trip: the tool's skeleton of ``cloud * s + t`` is its skeleton of ``cloud``, mapped."""
    cloud = shapes.y_shape(1200, seed=7).cloud
    s, t = 2.5, np.array([10.0, -20.0, 5.0])
    a, b = run(kind, cloud), run(kind, cloud * s + t)
    assert a.curve.n_vertices == b.curve.n_vertices
    np.testing.assert_array_equal(a.curve.edges, b.curve.edges)
    np.testing.assert_allclose(b.curve.vertices, a.curve.vertices * s + t, atol=1e-9 * s)
    if a.skeletal is not None:
        np.testing.assert_allclose(b.skeletal, a.skeletal * s + t, atol=1e-9 * s)


def test_a_compare_job_scores_the_tools_own_skeleton(run_dir):
    """The child process hands back exactly what the tool gives in this process."""
    mine = run("skimage", SHAPES["yshape"]().cloud).curve
    stored = run_dir.evaluation(run_dir.find("yshape", "thin")).curve.curve
    np.testing.assert_array_equal(stored.vertices, mine.vertices)
    np.testing.assert_array_equal(stored.edges, mine.edges)


def test_the_job_key_holds_the_tools_version(tmp_path):
    root = _dataset(tmp_path)
    jobs = make_jobs(load_manifest(manifest(root, TOOLS)))
    for job in jobs:
        a = ADAPTERS[job.method.kind]
        assert job.method.tool == f"{a.tool} {version(a.tool)}; adapter {ADAPTER_REVISION}"
        upgraded = dataclasses.replace(job, method=dataclasses.replace(job.method, tool=f"{a.tool} 999.0; adapter 1"),
                                       key="")
        assert _job_key(upgraded) != job.key
        assert _job_key(dataclasses.replace(job, key="")) == job.key


MISSING = [("pygel", "pygel3d"), ("kimimaro", "kimimaro"), ("skimage", "skimage")]

# One interpreter imports the command line (none of the tools: checked) and forks a child per tool, which
# blocks that tool's import and runs ``skelcore compare``: each child a real process with its own exit
# status and stderr, one interpreter start and one import of skelcore instead of three.
_MISSING_RUNS = r"""
import json, os, sys
from skelcore.cli import main
cases = json.loads(sys.argv[1])
loaded = [module for _kind, module, _m, _out in cases if module in sys.modules]
if loaded:
    sys.exit(f"imported before the children block them: {loaded}")
done = {}
for kind, module, m, out in cases:
    err = os.path.join(os.path.dirname(m), "stderr.txt")
    pid = os.fork()
    if pid == 0:
        fd = os.open(err, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
        os.dup2(fd, 2)
        os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
        sys.modules[module] = None
        try:
            code = main(["compare", m, "--out", out])
        except BaseException as exc:
            print(repr(exc), file=sys.stderr)
            code = 99
        sys.stderr.flush()
        os._exit(code)
    status = os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])
    done[kind] = {"returncode": status, "stderr": open(err).read()}
print(json.dumps(done))
"""


@pytest.fixture(scope="module")
def missing_runs(tmp_path_factory):
    """kind -> the exit status and stderr of ``skelcore compare`` on a manifest of that tool alone, in a
    process where the tool's import fails."""
    cases = []
    for kind, module in MISSING:
        root = _dataset(tmp_path_factory.mktemp(f"missing_{kind}"))
        m = manifest(root, f'[[shapes]]\npath = "clouds/*.ply"\n[[methods]]\nname = "t"\nkind = "{kind}"\n')
        cases.append([kind, module, str(m), str(root / "out")])
    proc = subprocess.run([sys.executable, "-c", _MISSING_RUNS, json.dumps(cases)], capture_output=True, text=True,
                          cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    return {kind: dict(run, root=Path(m).parent) for (kind, _module, m, _out), run in
            zip(cases, (json.loads(proc.stdout)[c[0]] for c in cases))}


@pytest.mark.parametrize("kind", [kind for kind, _module in MISSING])
def test_a_missing_tool_is_one_line_and_exit_2_before_any_job(missing_runs, kind):
    """The tool's import fails (sys.modules blocks it, as when it is not installed)."""
    run = missing_runs[kind]
    assert run["returncode"] == 2, run["stderr"]
    lines = run["stderr"].strip().splitlines()
    assert len(lines) == 1 and EXTRA in lines[0] and ADAPTERS[kind].tool in lines[0] and "method 't'" in lines[0]
    assert not (run["root"] / "out").exists()


@pytest.mark.parametrize("body, message", [
    ('kind = "pygel"\n[methods.params]\nneighbours = 8', "unknown parameter 'neighbours' (allowed: k, sampling, spacing)"),
    ('kind = "pygel"\n[methods.params]\nk = 1', "k must be >= 2, got 1"),
    ('kind = "pygel"\n[methods.params]\nk = 8.5', "k must be a whole number, got 8.5"),
    ('kind = "pygel"\n[methods.params]\nsampling = "yes"', "sampling must be true or false, got 'yes'"),
    ('kind = "kimimaro"\n[methods.params]\nvoxel_size = 0', "voxel_size must be > 0, got 0.0"),
    ('kind = "kimimaro"\n[methods.params]\nscale = -1', "scale must be > 0, got -1.0"),
    ('kind = "skimage"\ntimeout = 0', "timeout must be a number of seconds > 0"),
    ('kind = "skimage"\ncommand = "x"', "unknown key 'command'"),
    ('kind = "skeletor"', "kind must be 'builtin', 'command', 'files' or a tool (pygel, kimimaro, skimage)"),
])
def test_bad_tool_settings_are_one_line(tmp_path, body, message):
    root = _dataset(tmp_path)
    m = manifest(root, f'[[shapes]]\npath = "clouds/*.ply"\n[[methods]]\nname = "t"\n{body}\n')
    with pytest.raises(SkelInputError) as err:
        load_manifest(m)
    assert message in str(err.value) and "\n" not in str(err.value) and str(m) in str(err.value)


def test_a_failing_or_hanging_tool_fails_its_job_and_the_others_go_on(tmp_path):
    """A tool past its timeout is killed; a tool that refuses the input fails with its one line."""
    root = _dataset(tmp_path)
    m = manifest(root, """
        [[shapes]]
        path = "clouds/cyl.ply"
        [[methods]]
        name = "slow"
        kind = "kimimaro"
        timeout = 0.001
        [[methods]]
        name = "tiny_grid"
        kind = "skimage"
        [methods.params]
        voxel_size = 0.05
        max_voxels = 100
        [[methods]]
        name = "thin"
        kind = "skimage"
    """)
    assert main(["compare", str(m), "--out", str(root / "out"), "--jobs", "1", "--no-report"]) == 0
    rows = {r["method"]: r for r in (json.loads(p.read_text()) for p in (root / "out" / "jobs").glob("*.json"))}
    assert rows["slow"]["status"] == "failed"
    assert rows["slow"]["error"] == "method 'slow': kimimaro timed out after 0.001 s and was killed"
    assert rows["tiny_grid"]["status"] == "failed" and rows["tiny_grid"]["error"].startswith(
        "method 'tiny_grid': skimage: voxel_size 0.05 gives ") and "> max_voxels 100" in rows["tiny_grid"]["error"]
    assert rows["thin"]["status"] == "ok"


def test_a_cancelled_tool_run_stops_its_process(tmp_path):
    """Cancel (the viewer's, a study's) kills the child's process group and raises Cancelled."""
    from skelcore.compare.methods import run_adapter
    from skelcore.errors import Cancelled

    root = _dataset(tmp_path)
    spec = load_manifest(manifest(root, TOOLS)).methods[1]  # kimimaro: 2-3 s to import alone
    import psutil

    before = {p.pid for p in psutil.Process().children(recursive=True)}
    pids: set[int] = set()

    def cancel() -> bool:
        pids.update(p.pid for p in psutil.Process().children(recursive=True) if p.pid not in before)
        return True

    with pytest.raises(Cancelled):
        run_adapter(SHAPES["cyl"]().cloud, spec, cancel=cancel)
    alive = [p for p in pids if psutil.pid_exists(p) and psutil.Process(p).status() != psutil.STATUS_ZOMBIE]
    assert pids and alive == []


def test_run_in_this_process_refuses_a_bad_parameter_in_one_line():
    with pytest.raises(SkelInputError, match=r"^skimage: unknown parameter 'voxel' \(allowed: closing, max_voxels, "
                                             r"voxel_size\)$"):
        run("skimage", SHAPES["cyl"]().cloud, {"voxel": 0.1})


def test_a_tool_that_crashes_fails_with_one_line(tmp_path):
    """The child dies of a signal mid-run (SIGSEGV, as a segfault in the tool's C++ would): one line."""
    import os
    import signal

    import psutil

    from skelcore.compare.methods import run_adapter

    root = _dataset(tmp_path)
    spec = load_manifest(manifest(root, TOOLS)).methods[1]
    before = {p.pid for p in psutil.Process().children(recursive=True)}

    def crash() -> bool:
        for p in psutil.Process().children(recursive=True):
            if p.pid not in before:
                os.kill(p.pid, signal.SIGSEGV)
        return False

    with pytest.raises(SkelInputError) as err:
        run_adapter(SHAPES["cyl"]().cloud, spec, cancel=crash)
    assert str(err.value).startswith(f"method 'kimi': kimimaro was killed by signal {int(signal.SIGSEGV)}")
    assert "\n" not in str(err.value)
