"""``skelcore skeletonize``: the curve repaired by default (docs/repair.md), so every bundled sample gets a
sound skeleton; ``--raw`` writes the algorithm's curve as it is (the paper's toolbox with ``cao``)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from skelcore import evaluate, load_cloud, load_curve, skeletonize
from skelcore.cli import main
from skelcore.diagnostics.trust import DEFECT_CODES

SAMPLES = Path(__file__).resolve().parents[2] / "resources" / "samples"


@pytest.mark.parametrize("name", ["torus", "cylinder", "yshape"])
def test_every_bundled_sample_gets_a_sound_skeleton_by_default(name, tmp_path, capsys):
    cloud_file = SAMPLES / f"{name}_cloud.ply"
    out, log = tmp_path / "c.ply", tmp_path / "log.json"
    assert main(["skeletonize", str(cloud_file), "--out-curve", str(out), "--log", str(log), "--quiet"]) == 0
    cloud = load_cloud(str(cloud_file))
    ev = evaluate(cloud, curve=load_curve(str(out)))
    assert [w.code for w in ev.warnings if w.code in DEFECT_CODES] == []
    assert json.loads(log.read_text())["format"] == "skelscope-edit-log"
    assert "repaired:" in capsys.readouterr().out


def test_raw_writes_the_algorithm_s_curve(tmp_path, capsys):
    """The bundled torus: the paper's algorithm collapses part of the ring with an edge through the hole
    (flagged); ``--raw`` keeps exactly that curve, the default repairs it."""
    cloud_file = SAMPLES / "torus_cloud.ply"
    cloud = load_cloud(str(cloud_file))
    _skeletal, curve = skeletonize(cloud, method="cao")
    raw = tmp_path / "raw.ply"
    assert main(["skeletonize", str(cloud_file), "--out-curve", str(raw), "--raw", "--quiet"]) == 0
    written = load_curve(str(raw))
    assert (written.vertices == curve.vertices.astype(written.vertices.dtype)).all()
    assert written.n_edges == curve.n_edges
    assert {w.code for w in evaluate(cloud, curve=written).warnings} & set(DEFECT_CODES)
    assert "repaired:" not in capsys.readouterr().out


def test_log_needs_the_repair(tmp_path, capsys):
    cloud_file = SAMPLES / "torus_cloud.ply"
    code = main(["skeletonize", str(cloud_file), "--out-curve", str(tmp_path / "c.ply"), "--raw",
                 "--log", str(tmp_path / "l.json"), "--quiet"])
    assert code == 2 and "--log" in capsys.readouterr().err
