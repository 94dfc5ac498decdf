"""skelcore compare end to end on generated shapes: a process pool and a Dask LocalCluster give the
same table, failing methods are recorded without stopping the others, a rerun recomputes nothing,
and a run killed by SIGTERM resumes without losing or duplicating a job."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from compare_helpers import command, make_dataset, manifest
from skelcore.compare import Backend, run_compare
from skelcore.cli import main as main_cli
from skelcore.compare.results_csv import COLUMNS

ROOT = Path(__file__).resolve().parents[2]
SCORES = ["d_B", "d_Wp", "boundedness_skeletal", "boundedness_curve", "centeredness_skeletal",
          "centeredness_curve", "smoothness_skeletal", "smoothness_curve"]


def _body() -> str:
    return f"""
    [evaluation]
    beta_star = 0.75
    curve_samples = 120
    [[shapes]]
    path = "clouds/*.ply"
    [[methods]]
    name = "builtin"
    kind = "builtin"
    [[methods]]
    name = "line"
    kind = "command"
    command = "{command('line')}"
    timeout = 60
    [[methods]]
    name = "truth"
    kind = "files"
    curve = "skeletons/{{stem}}_curve.ply"
    skeletal = "skeletons/{{stem}}_skeletal.ply"
    [[conditions]]
    name = "normal"
    [[conditions]]
    name = "sparse"
    sparse = 400
    seeds = [0]
    """


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    root = make_dataset(tmp_path_factory.mktemp("cmp"))
    return root, manifest(root, _body())


@pytest.fixture(scope="module")
def pool_run(data):
    root, m = data
    return run_compare(m, root / "out_pool", Backend("pool", 2), report=False)


def _csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_every_job_ran_on_the_pool_and_results_csv_has_the_columns(pool_run, data):
    root, _m = data
    # 2 shapes x (builtin 2 conditions + line 2 + truth: clean clouds only, 1) = 10 jobs
    assert pool_run.summary.total == 10 and pool_run.summary.ok == 10 and pool_run.summary.failed == 0
    rows = _csv(root / "out_pool" / "results.csv")
    assert list(rows[0])[: len(COLUMNS)] == list(COLUMNS)
    assert {(r["shape"], r["method"], r["condition"]) for r in rows} == {
        (s, m, c) for s in ("cyl", "yshape") for m in ("builtin", "line") for c in ("normal", "sparse")
    } | {("cyl", "truth", "normal"), ("yshape", "truth", "normal")}
    assert all(r["status"] == "ok" and r["error"] == "" for r in rows)
    assert {r["n_points"] for r in rows if r["condition"] == "sparse"} == {"400"}
    # the curve-only command has no skeletal scores: empty cells, never "nan" or "None"
    line = [r for r in rows if r["method"] == "line"]
    assert all(r["d_B"] == "" and r["boundedness_skeletal"] == "" and r["boundedness_curve"] != "" for r in line)
    # the principal axis of a cylinder is its true curve skeleton: inside the shape everywhere
    assert all(float(r["boundedness_curve"]) > 0.9 for r in line if r["shape"] == "cyl")


def test_results_csv_reads_with_pandas_as_it_is(pool_run, data):
    pd = pytest.importorskip("pandas")
    root, _m = data
    df = pd.read_csv(root / "out_pool" / "results.csv")
    assert len(df) == 10
    for col in SCORES + ["seconds", "n_warnings", "coverage_skeletal"]:
        assert df[col].dtype == np.float64, col
    assert df.loc[df.method == "line", "d_B"].isna().all()
    assert (df.loc[df.method == "builtin", "d_B"] > 0).all()


def test_the_true_skeleton_scores_as_the_engine_says(pool_run, data):
    """The files method's row equals evaluate() on the same files (the job adds nothing)."""
    import skelcore

    root, _m = data
    row = next(r for r in pool_run.rows if r["method"] == "truth" and r["shape"] == "cyl")
    ev = skelcore.evaluate(skelcore.load_cloud(root / "clouds/cyl.ply"),
                           skelcore.load_points(root / "skeletons/cyl_skeletal.ply"),
                           skelcore.load_curve(root / "skeletons/cyl_curve.ply"),
                           skelcore.Params(curve_samples=120))
    s = ev.summary()
    assert row["d_B"] == pytest.approx(s["topology"]["bottleneck"])
    assert row["centeredness_curve"] == pytest.approx(s["centeredness"]["curve"])
    doc = json.loads((root / "out_pool" / "jobs" / f"{row['key']}.json").read_text())
    assert doc["evaluation"]["boundedness"]["skeletal"] == pytest.approx(s["boundedness"]["skeletal"])
    assert doc["evaluation"]["params"]["curve_samples"] == 120


def test_leaderboard_ranks_the_truth_above_a_straight_line_on_the_yshape(pool_run, data):
    root, _m = data
    board = {(r["method"], r["condition"]): r for r in _csv(root / "out_pool" / "leaderboard.csv")}
    assert set(board) == {("builtin", "normal"), ("line", "normal"), ("truth", "normal"),
                          ("builtin", "sparse"), ("line", "sparse")}
    assert board[("truth", "normal")]["n_ok"] == "2"
    # a straight line through a Y misses a branch: its curve centeredness cannot beat the true curve
    assert float(board[("truth", "normal")]["centeredness_curve_mean"]) > float(board[("line", "normal")]["centeredness_curve_mean"])
    assert board[("truth", "normal")]["centeredness_curve_rank"] == "1"
    md = (root / "out_pool" / "leaderboard.md").read_text()
    assert "d_B ↓" in md and "centeredness_curve ↑" in md and "grasping" in md
    tex = (root / "out_pool" / "leaderboard.tex").read_text()
    assert tex.startswith(r"\begin{tabular}") and r"$d_B$$\downarrow$" in tex and r"\pm" in tex


def test_a_local_dask_cluster_gives_the_same_table(pool_run, data):
    root, m = data
    dask_run = run_compare(m, root / "out_dask", Backend("dask", 2), report=False)
    assert dask_run.summary.ok == 10 and "LocalCluster of 2" in dask_run.summary.backend
    pids = {r["pid"] for r in dask_run.summary.records}
    assert os.getpid() not in pids  # worker processes did the work
    a = {r["key"]: r for r in _csv(root / "out_pool" / "results.csv")}
    b = {r["key"]: r for r in _csv(root / "out_dask" / "results.csv")}
    assert set(a) == set(b)
    for key in a:
        for col in SCORES:
            assert a[key][col] == b[key][col], (a[key]["method"], col)


def test_a_rerun_recomputes_nothing_and_an_edited_input_only_its_jobs(pool_run, data):
    root, m = data
    out = root / "out_pool"
    before = {p.name: p.stat().st_mtime_ns for p in (out / "jobs").iterdir()}
    csv_before = (out / "results.csv").read_text()
    seen = []
    again = run_compare(m, out, Backend("pool", 2), report=False, on_record=seen.append)
    assert seen == [] and again.summary.skipped == 10 and again.summary.ok == 0
    assert {p.name: p.stat().st_mtime_ns for p in (out / "jobs").iterdir()} == before
    assert (out / "results.csv").read_text() == csv_before


def test_editing_a_shape_reruns_exactly_its_jobs(data, tmp_path):
    root, _m = data
    import shutil

    for sub in ("clouds", "skeletons"):
        shutil.copytree(root / sub, tmp_path / sub)
    m = manifest(tmp_path, """
    [[shapes]]
    path = "clouds/*.ply"
    [[methods]]
    name = "truth"
    kind = "files"
    curve = "skeletons/{stem}_curve.ply"
    [[conditions]]
    name = "normal"
    [[conditions]]
    name = "noisy"
    noise = 0.01
    seeds = [0, 1]
    [[methods]]
    name = "truth_per_condition"
    kind = "files"
    curve = "skeletons/{stem}_curve.ply"
    skeletal = "skeletons/{stem}_skeletal.ply"
    """)
    first = run_compare(m, tmp_path / "out", Backend("serial"), report=False)
    assert first.summary.ok == 4  # files of clean clouds: only the condition that does not degrade
    src = tmp_path / "clouds/yshape.ply"
    text = src.read_bytes()
    (tmp_path / "edited.ply").write_bytes(text.replace(b"\nend_header\n", b"\ncomment edited\nend_header\n", 1))
    os.replace(tmp_path / "edited.ply", src)  # same points, other bytes
    seen = []
    run_compare(m, tmp_path / "out", Backend("serial"), report=False, on_record=seen.append)
    assert sorted((r["shape"], r["method"]) for r in seen) == [("yshape", "truth"), ("yshape", "truth_per_condition")]


def test_crashing_hanging_and_garbage_methods_are_recorded_and_the_rest_finish(data, tmp_path):
    root, _m = data
    m = manifest(root, f"""
    [[shapes]]
    path = "clouds/*.ply"
    [[methods]]
    name = "crash"
    kind = "command"
    command = "{command('crash')}"
    [[methods]]
    name = "hang"
    kind = "command"
    command = "{command('hang')}"
    timeout = 1.5
    [[methods]]
    name = "garbage"
    kind = "command"
    command = "{command('garbage')}"
    [[methods]]
    name = "truth"
    kind = "files"
    curve = "skeletons/{{stem}}_curve.ply"
    [[conditions]]
    name = "normal"
    """, name="bad.toml")
    (root / "hang_pids").mkdir(exist_ok=True)
    res = run_compare(m, tmp_path / "out", Backend("pool", 2), report=False)
    rows = {(r["shape"], r["method"]): r for r in _csv(tmp_path / "out" / "results.csv")}
    assert len(rows) == 8 and res.summary.ok == 2 and res.summary.failed == 6
    for shape in ("cyl", "yshape"):
        assert rows[(shape, "truth")]["status"] == "ok"
        crash, hang, garbage = (rows[(shape, k)] for k in ("crash", "hang", "garbage"))
        assert crash["status"] == hang["status"] == garbage["status"] == "failed"
        assert "exited with status 139: segmentation fault (pretend)" in crash["error"]
        assert "timed out after 1.5 s" in hang["error"]
        assert "curve" in garbage["error"] and "\n" not in garbage["error"]
        for r in (crash, hang, garbage):
            assert r["d_B"] == "" and r["profile_grasping"] == "fail" and r["profile_grasping_reason"] == "job failed"
    # the hung programs were killed, not left behind
    hung = [int(p.name) for p in (root / "hang_pids").iterdir()]
    assert len(hung) == 2 and not [pid for pid in hung if _alive(pid)]
    # failed jobs are finished jobs: a rerun runs nothing, --retry-failed runs exactly them
    seen = []
    run_compare(m, tmp_path / "out", Backend("serial"), report=False, on_record=seen.append)
    assert seen == []
    run_compare(m, tmp_path / "out", Backend("serial"), report=False, retry_failed=True, on_record=seen.append)
    assert sorted(r["method"] for r in seen) == ["crash", "crash", "garbage", "garbage", "hang", "hang"]


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie is dead
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split()[2] != "Z"
    except OSError:
        return False


def test_a_run_killed_by_sigterm_resumes_without_losing_or_duplicating_a_job(data, tmp_path):
    root, _m = data
    m = manifest(root, f"""
    seeds = [0, 1]
    [evaluation]
    curve_samples = 60
    [[shapes]]
    path = "clouds/*.ply"
    [[methods]]
    name = "slow"
    kind = "command"
    command = "{command('line')}"
    [[conditions]]
    name = "sparse"
    sparse = 300
    [[conditions]]
    name = "fps"
    fps = 300
    """, name="slow.toml")
    out = tmp_path / "out"
    pids = tmp_path / "pids"
    pids.mkdir()
    env = dict(os.environ, PYTHONPATH=str(ROOT), SKEL_SLEEP="0.6", SKEL_PIDS=str(pids))
    proc = subprocess.Popen([sys.executable, "-m", "skelcore", "compare", str(m), "--out", str(out), "--jobs", "2",
                             "--quiet", "--no-report"], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list((out / "jobs").glob("*.json"))) < 2:
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _out, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGTERM, err.decode()[-500:]
    done = {p.stem for p in (out / "jobs").glob("*.json")}
    assert 2 <= len(done) < 8
    assert not list((out / "jobs").glob(".*.tmp"))
    time.sleep(0.3)
    assert not [p for p in pids.iterdir() if _alive(int(p.name))]  # no skeleton command outlived the run
    records = {k: json.loads((out / "jobs" / f"{k}.json").read_text()) for k in done}
    assert all(r["status"] == "ok" for r in records.values())

    seen = []
    os.environ["SKEL_SLEEP"] = "0"
    try:
        res = run_compare(m, out, Backend("pool", 2), report=False, on_record=seen.append)
    finally:
        del os.environ["SKEL_SLEEP"]
    assert res.summary.total == 8 and res.summary.skipped == len(done)
    assert len(seen) == 8 - len(done) and not ({r["key"] for r in seen} & done)  # nothing twice
    rows = _csv(out / "results.csv")
    assert len(rows) == 8 and len({r["key"] for r in rows}) == 8 and all(r["status"] == "ok" for r in rows)
    # what ran before the kill was kept as it was
    for k in done:
        assert json.loads((out / "jobs" / f"{k}.json").read_text()) == records[k]


def test_coverage_warnings_and_correspondence_reach_results_csv(data, tmp_path):
    """The trust fields: coverage fractions and the number of trust warnings are columns; a point
    set that does not match the cloud row for row is scored with ``correspondence = "reverse"``."""
    root, _m = data
    m = manifest(root, """
    [[shapes]]
    path = "clouds/*.ply"
    [[methods]]
    name = "truth"
    kind = "files"
    curve = "skeletons/{stem}_curve.ply"
    skeletal = "skeletons/{stem}_skeletal.ply"
    [[methods]]
    name = "vertices_auto"
    kind = "files"
    skeletal = "skeletons/{stem}_curve.ply"
    [[methods]]
    name = "vertices_reverse"
    kind = "files"
    skeletal = "skeletons/{stem}_curve.ply"
    correspondence = "reverse"
    [[conditions]]
    name = "normal"
    """, name="corr.toml")
    run_compare(m, tmp_path / "out", Backend("serial"), report=False)
    rows = {(r["shape"], r["method"]): r for r in _csv(tmp_path / "out" / "results.csv")}
    for shape in ("cyl", "yshape"):
        truth, auto, rev = (rows[(shape, k)] for k in ("truth", "vertices_auto", "vertices_reverse"))
        assert all(r["status"] == "ok" for r in (truth, auto, rev)), (auto["error"], rev["error"])
        assert float(truth["coverage_curve"]) > 0.9 and float(truth["coverage_skeletal"]) > 0.9
        assert truth["n_warnings"] == "0.0"
        # 21 vertices for ~700 cloud points: no row-for-row correspondence, a warning, no topology
        assert auto["d_B"] == "" and float(auto["n_warnings"]) >= 1
        assert float(rev["d_B"]) >= 0 and rev["centeredness_skeletal"] != ""
        doc = json.loads((tmp_path / "out" / "jobs" / f"{rev['key']}.json").read_text())
        assert doc["evaluation"]["correspondence"] == "reverse"


def test_an_existing_dask_scheduler_by_address(data, tmp_path, capsys):
    """``--dask tcp://HOST:PORT`` submits to a scheduler somebody else started."""
    from distributed import LocalCluster

    root, _m = data
    m = manifest(root, """
    [[shapes]]
    path = "clouds/*.ply"
    [[methods]]
    name = "truth"
    kind = "files"
    curve = "skeletons/{stem}_curve.ply"
    [[conditions]]
    name = "normal"
    """, name="tcp.toml")
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp",
                      dashboard_address=None) as cluster:
        assert cluster.scheduler_address.startswith("tcp://")
        rc = main_cli(["compare", str(m), "--out", str(tmp_path / "out"), "--dask", cluster.scheduler_address,
                       "--quiet", "--no-report"])
    out = capsys.readouterr().out
    assert rc == 0 and "2 ran ok, 0 failed; dask tcp://" in out
    assert len(_csv(tmp_path / "out" / "results.csv")) == 2


def test_an_unreachable_scheduler_is_one_line(data, tmp_path, capsys):
    root, _m = data
    m = manifest(root, """
    [[shapes]]
    path = "clouds/cyl.ply"
    [[methods]]
    name = "truth"
    kind = "files"
    curve = "skeletons/{stem}_curve.ply"
    """, name="tcp2.toml")
    rc = main_cli(["compare", str(m), "--out", str(tmp_path / "out"), "--dask", "tcp://127.0.0.1:9", "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2 and "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in err and len(err.strip().splitlines()) == 1



def test_the_scheduler_probe_tells_a_refused_port_from_a_listening_one():
    """A port nobody listens on is refused at once (no Dask retries); a listening one, another scheme or
    no port is left to Dask's connect."""
    import socket

    from skelcore.compare.scheduler_probe import refused

    with socket.socket() as listening:
        listening.bind(("127.0.0.1", 0))
        listening.listen()
        port = listening.getsockname()[1]
        assert refused(f"tcp://127.0.0.1:{port}") is None
    assert isinstance(refused(f"tcp://127.0.0.1:{port}"), ConnectionRefusedError)  # closed now
    assert refused(f"tls://127.0.0.1:{port}") is None and refused("tcp://127.0.0.1") is None
    assert refused("local:2") is None

def test_study_is_a_compare_run_with_one_shape_and_one_method(data, tmp_path):
    """The same cloud, command, conditions and seed: the study's table equals compare's results."""
    from skelcore.experiments.study import run_study
    from skelcore.io import load_cloud

    root, _m = data
    cmd = command("line")
    m = manifest(root, f"""
    seeds = [5]
    [[shapes]]
    path = "clouds/yshape.ply"
    [[methods]]
    name = "line"
    kind = "command"
    command = "{cmd}"
    [[conditions]]
    name = "normal"
    [[conditions]]
    name = "noise"
    noise = 0.05
    [[conditions]]
    name = "sparse"
    sparse = 300
    """, name="study.toml")
    res = run_compare(m, tmp_path / "out", Backend("serial"), report=False)
    cwd = os.getcwd()
    os.chdir(root)  # the command names bin/line.py relative to the manifest's folder
    try:
        study = run_study(load_cloud(root / "clouds/yshape.ply"), noise=0.05, sparse=300, seed=5, skeleton_cmd=cmd)
    finally:
        os.chdir(cwd)
    rows = {r["condition"]: r for r in res.rows}
    assert [r.name for r in study.rows] == ["normal", "noise", "sparse"]
    for row in study.rows:
        for key, value in row.scores().items():
            got = rows[row.name][key]
            assert (value is None and np.isnan(got)) or got == pytest.approx(value, rel=1e-12, abs=1e-15), (row.name, key)


def test_editing_the_profiles_changes_verdicts_without_recomputing(pool_run, data, tmp_path):
    root, m = data
    prof = tmp_path / "mine.toml"
    prof.write_text('[[profiles]]\nname = "tube_follower"\ntitle = "t"\n'
                    '[[profiles.require]]\nmetric = "boundedness_curve"\nmin = 0.9\n')
    seen = []
    res = run_compare(m, root / "out_pool", Backend("serial"), profiles_path=prof, report=False, on_record=seen.append)
    assert seen == []
    rows = _csv(root / "out_pool" / "results.csv")
    assert "profile_grasping" not in rows[0] and "profile_tube_follower_reason" in rows[0]
    for r in rows:
        b = float(r["boundedness_curve"])
        assert r["profile_tube_follower"] == ("pass" if b >= 0.9 else "fail")
        assert r["profile_tube_follower_reason"].startswith("boundedness_curve ")
    assert "tube_follower" in (root / "out_pool" / "leaderboard.md").read_text().splitlines()[0]
    assert [p.name for p in res.leaderboard.profiles] == ["tube_follower"]
    run_compare(m, root / "out_pool", Backend("serial"), report=False)  # back to the shipped ones


def test_job_records_and_results_csv_follow_their_schemas(pool_run, data):
    """Every record and row of the run (builtin, command and files methods) validates against the shipped
    JSON Schemas (skelcore/io/schemas; more cases in test_compare_schemas.py)."""
    pytest.importorskip("jsonschema")
    from skelcore.io.schemas import validator

    root, _m = data
    for path in (root / "out_pool" / "jobs").glob("*.json"):
        assert not list(validator("compare_job").iter_errors(json.loads(path.read_text()))), path.name
    with open(root / "out_pool" / "results.csv", newline="") as fh:
        reader = csv.DictReader(fh)
        rows = list(reader)
    assert not list(validator("results_csv", "header").iter_errors(reader.fieldnames))
    assert len(rows) == 10 and not [e for r in rows for e in validator("results_csv").iter_errors(r)]
