"""The compare manifest: what it accepts, and a one-line error (exit 2, nothing run) for every
mistake; job keys; conditions; the leaderboard's statistics and ranks; the profiles."""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from compare_helpers import make_dataset, manifest
from skelcore.cli import main
from skelcore.errors import SkelInputError
from skelcore.compare.conditions import degrade
from skelcore.compare.jobs import make_jobs
from skelcore.compare.leaderboard import build_leaderboard
from skelcore.compare.manifest import ConditionSpec, load_manifest
from skelcore.compare.profiles import load_profiles

ROOT = Path(__file__).resolve().parents[2]

GOOD = """
[evaluation]
beta_star = 0.7
[[shapes]]
path = "clouds/*.ply"
[[methods]]
name = "builtin"
kind = "builtin"
[methods.params]
max_iterations = 5
[[methods]]
name = "truth"
kind = "files"
curve = "skeletons/{stem}_curve.ply"
[[conditions]]
name = "normal"
[[conditions]]
name = "noise"
noise = 0.05
[[conditions]]
name = "sparse"
sparse = 300
seeds = [0]
"""


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    return make_dataset(tmp_path_factory.mktemp("man"), n=300)


def test_the_issues_example_layout_parses(root):
    m = load_manifest(manifest(root, GOOD))
    assert [s.name for s in m.shapes] == ["cyl", "yshape"]
    assert m.params.beta_star == 0.7
    assert m.methods[0].params == {"max_iterations": 5}
    # TOML puts a trailing `seeds` into the last [[conditions]] table: that condition's seeds
    assert [c.name for c in m.conditions] == ["normal", "noise", "sparse"] and m.conditions[2].seeds == (0,)
    jobs = make_jobs(m)
    assert len(jobs) == 2 * (3 + 1) and len({j.key for j in jobs}) == len(jobs)


def test_job_keys_follow_the_inputs_and_nothing_else(root, tmp_path):
    a = {(j.shape.name, j.method.name, j.condition.name): j.key for j in make_jobs(load_manifest(manifest(root, GOOD)))}
    # the same manifest in another folder with the same bytes: the same keys
    for sub in ("clouds", "skeletons"):
        shutil.copytree(root / sub, tmp_path / sub)
    b = {k: j.key for k, j in ((k2, j2) for j2 in make_jobs(load_manifest(manifest(tmp_path, GOOD)))
                                for k2 in [(j2.shape.name, j2.method.name, j2.condition.name)])}
    assert a == b
    changed = make_jobs(load_manifest(manifest(tmp_path, GOOD.replace("beta_star = 0.7", "beta_star = 0.8"))))
    assert not ({j.key for j in changed} & set(a.values()))  # every job depends on the evaluation params
    changed = make_jobs(load_manifest(manifest(tmp_path, GOOD.replace("max_iterations = 5", "max_iterations = 6"))))
    keys = {(j.shape.name, j.method.name, j.condition.name): j.key for j in changed}
    assert [k for k in keys if keys[k] != a[k]] == [k for k in a if k[1] == "builtin"]


@pytest.mark.parametrize(
    "edit, message",
    [
        (("[evaluation]", "[evaluation]\nbeta_stra = 1"), "unknown key 'beta_stra'"),
        (("beta_star = 0.7", "beta_star = 7"), "beta_star"),
        (("clouds/*.ply", "nothing/*.ply"), "matches no file"),
        (("clouds/*.ply", "clouds/missing.ply"), "'clouds/missing.ply' not found"),
        (('kind = "builtin"', 'kind = "builtin"\ntimeout = 3'), "unknown key 'timeout'"),
        (('kind = "builtin"', 'kind = "magic"'), "kind must be"),
        (("max_iterations = 5", "max_iterationz = 5"), "max_iterationz"),
        (('curve = "skeletons/{stem}_curve.ply"', 'curve = "skeletons/{stem}_nope.ply"'), "curve file for shape 'cyl' not found"),
        (('curve = "skeletons/{stem}_curve.ply"', 'curve = "skeletons/cyl_curve.ply"'), "{stem}"),
        (("noise = 0.05", "noise = -1"), "noise must be a number >= 0"),
        (("sparse = 300", "sparse = 300\ngrid = 0.1"), "only one of sparse, grid and fps"),
        (("sparse = 300", "sparse = 3.5"), "positive whole number"),
        (("noise = 0.05", "noise = 0.05\nmodel = 'gauss'"), "model must be"),
        (("seeds = [0]", "seeds = [0, 0]"), "listed twice"),
        (('name = "truth"', 'name = "builtin"'), "two methods have this name"),
        (("[evaluation]", "colour = 1\n[evaluation]"), "top level: unknown key 'colour'"),
        (("[[conditions]]\nname = \"noise\"", "[[conditions]]\nname = \"normal\""), "two conditions"),
        # evaluate() takes auto or reverse: "pointwise" fails the check, not every job
        (('curve = "skeletons/{stem}_curve.ply"', 'curve = "skeletons/{stem}_curve.ply"\ncorrespondence = "pointwise"'),
         "correspondence must be one of auto, reverse"),
    ],
)
def test_every_mistake_is_one_line_naming_the_manifest_and_nothing_runs(root, tmp_path, capsys, edit, message):
    m = manifest(root, GOOD.replace(*edit), name="bad.toml")
    assert GOOD.replace(*edit) != GOOD
    out = tmp_path / "out"
    rc = main(["compare", str(m), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2
    assert len(err.strip().splitlines()) == 1 and "bad.toml" in err and message in err, err
    assert not out.exists()  # checked before any job (or folder) was made


@pytest.mark.parametrize(
    "cmd, message",
    [
        ("no-such-skeletonizer {in} {out_curve}", "'no-such-skeletonizer' is not on PATH"),
        ("./bin/missing.py {in} {out_curve}", "not found or not executable"),
        ("python3 {out_curve}", "{in} placeholder"),
        ("python3 {in}", "{out_skeletal} and/or {out_curve}"),
        ("python3 '{in} {out_curve}", "cannot be split"),
    ],
)
def test_unusable_commands_are_refused_up_front(root, cmd, message):
    body = GOOD + f'[[methods]]\nname = "ext"\nkind = "command"\ncommand = "{cmd}"\n'
    with pytest.raises(SkelInputError, match=message.replace("{", r"\{").replace("}", r"\}")):
        load_manifest(manifest(root, body.replace('"\'', "\"'")))


def test_a_missing_or_broken_manifest_is_one_line(tmp_path, capsys):
    assert main(["compare", str(tmp_path / "none.toml"), "--out", str(tmp_path / "o")]) == 2
    assert "none.toml: manifest not found" in capsys.readouterr().err
    bad = tmp_path / "b.toml"
    bad.write_text("[[shapes]\npath=1")
    assert main(["compare", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "not valid TOML" in err and len(err.strip().splitlines()) == 1


def test_an_unwritable_output_folder_is_one_line(root, tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    rc = main(["compare", str(manifest(root, GOOD)), "--out", str(blocker / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2 and "cannot create the output folder" in err and len(err.strip().splitlines()) == 1


def test_bad_backends_are_one_line(root, tmp_path, capsys):
    for flag in ("local:0", "localhost:8786"):
        assert main(["compare", str(manifest(root, GOOD)), "--out", str(tmp_path / "o"), "--dask", flag]) == 2
        assert "--dask" in capsys.readouterr().err


def test_conditions_compose_in_order_and_repeat_from_the_seed():
    from skelcore import shapes
    from skelcore.skeleton.degrade import voxel_grid_average

    cloud = shapes.cylinder(2000, seed=0).cloud
    assert degrade(cloud, ConditionSpec("normal"), 0) is cloud
    a = degrade(cloud, ConditionSpec("n", noise=0.05, sparse=500), 3)
    b = degrade(cloud, ConditionSpec("n", noise=0.05, sparse=500), 3)
    c = degrade(cloud, ConditionSpec("n", sparse=500), 3)
    assert a.shape == (500, 3) and np.array_equal(a, b)
    # same rows kept with and without noise (independent streams), then moved by the noise
    assert np.abs(a - c).max() < 0.05 * np.abs(c).max() * 6 and not np.allclose(a, c)
    g = degrade(cloud, ConditionSpec("g", base_grid=0.2, grid=0.4), 0)
    assert np.allclose(g, voxel_grid_average(voxel_grid_average(cloud, 0.2)[0], 0.4)[0])
    f = degrade(cloud, ConditionSpec("f", fps=100), 0)
    assert f.shape == (100, 3) and len(np.unique(f, axis=0)) == 100


def _row(method, condition, **scores):
    base = {k: math.nan for k in ("d_B", "d_Wp", "boundedness_skeletal", "boundedness_curve", "centeredness_skeletal",
                                  "centeredness_curve", "smoothness_skeletal", "smoothness_curve", "coverage_skeletal",
                                  "coverage_curve", "n_warnings", "seconds")}
    base.update(scores)
    return {"method": method, "condition": condition, "status": "ok", **base}


def test_leaderboard_means_stds_and_ranks_by_hand():
    profiles = load_profiles()
    rows = [_row("a", "normal", d_B=0.01, centeredness_curve=0.9), _row("a", "normal", d_B=0.03, centeredness_curve=0.7),
            _row("b", "normal", d_B=0.015, centeredness_curve=0.95), _row("b", "normal", d_B=0.015, centeredness_curve=0.95),
            _row("c", "normal", d_B=0.02, centeredness_curve=0.8), {**_row("c", "normal"), "status": "failed"}]
    for r in rows:
        for p in profiles:
            v = p.verdict(r, {}, ok=r["status"] == "ok")
            r[f"profile_{p.name}"] = v.status
    board = build_leaderboard(rows, profiles, ["a", "b", "c"], ["normal"])
    a, b, c = board.entries
    assert a.mean["d_B"] == pytest.approx(0.02) and a.std["d_B"] == pytest.approx(np.std([0.01, 0.03], ddof=1))
    assert b.std["d_B"] == 0.0 and c.std["d_B"] == 0.0 and c.n_ok == 1 and c.n_jobs == 2
    # d_B: lower is better -> b (0.015) 1st, a and c (0.02) tie for 2nd; centeredness: higher is better
    assert (b.rank["d_B"], a.rank["d_B"], c.rank["d_B"]) == (1, 2, 2)
    assert (b.rank["centeredness_curve"], a.rank["centeredness_curve"], c.rank["centeredness_curve"]) == (1, 2, 2)
    assert a.rank["smoothness_curve"] is None  # nobody has it
    md = board.to_markdown()
    assert "0.0150 ± 0.0000 (1)" in md and "smoothness_curve" not in md.splitlines()[0]
    assert re.search(r"\| c\s+\| normal\s+\| 1/2\s+\|", md)
    # grasping needs d_B, d_Wp <= 0.02 and centeredness >= 0.5: d_Wp is missing, so nobody passes
    assert a.profiles["grasping"] == (0, 2) and c.profiles["grasping"] == (0, 2)


def test_profile_verdicts_give_the_reason(tmp_path):
    p = {q.name: q for q in load_profiles()}
    good = {"d_B": 0.01, "d_Wp": 0.012, "centeredness_curve": 0.8, "smoothness_curve": 0.9, "boundedness_curve": 1.0}
    v = p["grasping"].verdict(good, {})
    assert v.status == "pass" and v.score == 1.0 and "d_B 0.01 <= 0.02" in v.reason
    v = p["grasping"].verdict({**good, "centeredness_curve": 0.3}, {})
    assert v.status == "fail" and v.score == pytest.approx(0.5) and v.reason == "centeredness_curve 0.3 < 0.5"
    # the skeletal score stands in when there is no curve
    v = p["grasping"].verdict({**good, "centeredness_curve": math.nan, "centeredness_skeletal": 0.6}, {})
    assert v.status == "pass" and "centeredness_skeletal 0.6 >= 0.5" in v.reason
    assert p["agriculture"].verdict(good, {"noise": None}).status == "n/a"
    assert p["agriculture"].verdict(good, {"noise": 0.05}).status == "pass"
    bad = tmp_path / "p.toml"
    bad.write_text('[[profiles]]\nname = "x"\n[[profiles.require]]\nmetric = "speed"\nmax = 1\n')
    with pytest.raises(SkelInputError, match="p.toml: profile 'x': metric must be"):
        load_profiles(bad)


def test_the_users_copy_of_the_profiles_is_the_shipped_file():
    shipped = ROOT / "skelcore" / "compare" / "data" / "profiles.toml"
    assert (ROOT / "resources" / "profiles.toml").read_bytes() == shipped.read_bytes()
    assert "our reading" in shipped.read_text().lower()
    assert [p.name for p in load_profiles(ROOT / "resources" / "profiles.toml")] == [
        "grasping", "navigation", "agriculture", "reconstruction"]


def test_the_shipped_samples_manifest_is_valid():
    """resources/compare/samples.toml: the bundled samples, named without their "_cloud" suffix."""
    m = load_manifest(ROOT / "resources" / "compare" / "samples.toml")
    assert [s.name for s in m.shapes] == ["cylinder", "torus", "yshape"]
    assert [x.name for x in m.methods] == ["builtin", "axis", "lbc_files", "truth"]
    jobs = make_jobs(m)
    # builtin and axis under 3 conditions, the two precomputed methods on the clean clouds only
    assert len(jobs) == 3 * (3 + 3 + 1 + 1)


def test_means_that_print_the_same_share_a_rank():
    from skelcore.compare.leaderboard import _ranks

    assert _ranks([0.02331, 0.02334, 0.0237, math.nan], True, 4) == [1, 1, 3, None]
    assert _ranks([0.9, 0.95, 0.95], False, 3) == [3, 1, 1]


def test_builtin_method_is_passed_only_when_skeletonize_takes_it(root, monkeypatch):
    """``kind = "builtin"`` with ``method = "cao"``: forwarded to skeletonize(method=...) when the
    installed skelcore has several skeletonizers, a one-line error otherwise."""
    import skelcore.skeleton as skeleton
    from skelcore.compare.methods import run_builtin

    body = GOOD.replace('name = "builtin"\nkind = "builtin"', 'name = "builtin"\nkind = "builtin"\nmethod = "cao"')
    real = skeleton.skeletonize
    if "method" not in __import__("inspect").signature(real).parameters:
        with pytest.raises(SkelInputError, match="has no method= option"):
            load_manifest(manifest(root, body))
    calls = []

    def fake(points, params, progress=None, cancel=None, *, method="skelscope"):
        calls.append((method, params.max_iterations))
        return points, None

    monkeypatch.setattr(skeleton, "skeletonize", fake)
    m = load_manifest(manifest(root, body))
    assert m.methods[0].method == "cao"
    pts = np.random.default_rng(0).normal(size=(50, 3))
    skeletal, curve = run_builtin(pts, m.methods[0])
    assert calls == [("cao", 5)] and skeletal is pts and curve is None
    from skelcore.skeleton.skeleton_params import method_params

    plain = load_manifest(manifest(root, GOOD))
    run_builtin(pts, plain.methods[0])
    assert calls[-1] == (method_params(None)[0], 5)  # no method given: the skeletonizer's default
    monkeypatch.setattr(skeleton, "skeletonize", real)
    with pytest.raises(SkelInputError, match="unknown skeletonize method 'magic'"):
        load_manifest(manifest(root, body.replace('method = "cao"', 'method = "magic"')))


def test_a_method_repaired_is_another_job_scored_on_its_repaired_curve(root):
    """``repair = true`` on a method: its own job key (a method without it keeps the key it had), and the
    job scores the curve ``skelcore.repair`` gives (the repair's seconds in the timings)."""
    from skelcore.compare.jobs import execute

    body = GOOD.replace('[[methods]]\nname = "truth"', '[[methods]]\nname = "builtin repaired"\nkind = "builtin"\n'
                        'repair = true\n[methods.params]\nmax_iterations = 5\n[[methods]]\nname = "truth"')
    m = load_manifest(manifest(root, body))
    assert [x.repair for x in m.methods] == [False, True, False]
    plain = {j.key for j in make_jobs(load_manifest(manifest(root, GOOD, name="plain.toml")))}
    jobs = make_jobs(m)
    assert {j.key for j in jobs if not j.method.repair} == plain
    job = next(j for j in jobs if j.method.repair and j.condition.name == "normal" and j.shape.name == "yshape")
    out = execute(job)
    assert "repair" in out.timings and out.curve is not None and out.curve.n_edges > 0
    with pytest.raises(SkelInputError, match="repair must be true or false"):
        load_manifest(manifest(root, body.replace("repair = true", 'repair = "yes"'), name="bad.toml"))
