"""Cancel is honoured in every stage of an evaluation, and the progress label names the stage that runs.

A cancel callback that flips after N calls stands in for the user's button (no timed asserts): the
first pass counts the checks made while each stage runs (the progress label tells which); then, for
every stage, a cancel at its first and at its middle check must stop the evaluation in that stage.  The
checkpoints themselves are spaced by chunking (KD-tree queries, raster batches), see
docs/performance.md for the measured latencies at 1M points.
"""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import evaluate
from skelcore.errors import Cancelled
from skelcore.shapes import torus

# the order of the stages run one after the other (workers=1): the curve's boundedness first and the
# skeletal set's after it (with more workers they share a lane, the Python stages beside them)
STAGES = [
    "curve boundedness",
    "skeletal boundedness",
    "topology",
    "skeletal centeredness",
    "skeletal smoothness",
    "curve centeredness",
    "curve smoothness",
    "skeletal coverage",
    "curve coverage",
    "stray points",  # the real-scan check's search (docs/metrics.md 6.4), a stage beside the others
    "curve defects",  # the diagnostics
    "skeletal outside",
    "skeletal missing parts",
    "curve missing parts",
]


@pytest.fixture(scope="module")
def case():
    shape = torus(3000, 1.0, 0.3, n_curve=48, seed=3)
    rng = np.random.default_rng(3)
    skeletal = shape.skeletal + rng.normal(scale=0.01, size=shape.skeletal.shape)
    return shape.cloud, skeletal, (shape.curve_vertices, shape.curve_edges)


def _calls_per_stage(case) -> dict[str, int]:
    """Cancel checks made while each stage's label was shown (the label changes at a stage's first
    check, which calls cancel just before it, so that one counts for the previous stage)."""
    current = [""]
    per_stage: dict[str, int] = {}

    def cancel() -> bool:
        per_stage[current[0]] = per_stage.get(current[0], 0) + 1
        return False

    def progress(_fraction: float, stage: str) -> None:
        current[0] = stage

    evaluate(*case, progress=progress, cancel=cancel, workers=1)
    return per_stage


def test_progress_names_every_stage_as_it_starts(case):
    seen: list[str] = []
    evaluate(*case, progress=lambda _f, stage: seen.append(stage) if not seen or seen[-1] != stage else None,
             workers=1)
    assert seen == STAGES  # each stage reported, in the order they run


@pytest.mark.parametrize("where", ["first", "middle"])
def test_cancel_stops_in_every_stage(case, where):
    """The callback flips at the first (or a later) check made while a stage runs: the evaluation
    stops there, naming that stage.  (The number of checks varies a little between runs: the raster
    batches are sized by time, so the flip is keyed to the stage, not to a global call count.)"""
    per_stage = _calls_per_stage(case)
    for stage in STAGES:
        n = per_stage.get(stage, 0)
        assert n >= 1, (stage, per_stage)
        # "middle": the second check seen in the stage when it had at least 4 in the first pass (the
        # counts vary with timing; the last one counted belongs to the next stage's first check)
        flip = 1 if where == "first" or n < 4 else 2
        current = [""]
        calls = [0]

        def progress(_fraction: float, name: str) -> None:
            current[0] = name

        def cancel() -> bool:
            if current[0] == stage:
                calls[0] += 1
            return calls[0] >= flip

        with pytest.raises(Cancelled, match=f"during {stage}$"):
            evaluate(*case, progress=progress, cancel=cancel, workers=1)


def test_stages_side_by_side_report_every_stage_and_a_cancel_stops_them_all(case):
    import threading

    seen: list[str] = []
    evaluate(*case, progress=lambda _f, stage: seen.append(stage), workers=2)
    assert set(seen) == set(STAGES)
    lanes_at_cancel = []

    def cancel() -> bool:
        lanes = [t for t in threading.enumerate() if t.name.startswith("skelscope-lane")]
        if lanes:  # a second stage runs beside the first
            lanes_at_cancel.append(len(lanes))
        return bool(lanes)

    with pytest.raises(Cancelled, match="^cancelled during "):
        evaluate(*case, cancel=cancel, workers=2)
    assert lanes_at_cancel and not [t for t in threading.enumerate() if t.name.startswith("skelscope-lane")]


@pytest.mark.parametrize("n", [20000])
def test_every_stage_checks_often_on_a_bigger_cloud(n):
    """At 20k points every metric stage reaches its checkpoint many times (chunked queries and
    batches), so a cancel does not wait for a whole stage."""
    shape = torus(n, 1.0, 0.3, n_curve=48, seed=4)
    skeletal = shape.skeletal + np.random.default_rng(4).normal(scale=0.01, size=shape.skeletal.shape)
    per_stage: dict[str, int] = {}
    current = [""]

    def progress(_fraction: float, stage: str) -> None:
        current[0] = stage

    def cancel() -> bool:
        per_stage[current[0]] = per_stage.get(current[0], 0) + 1
        return False

    evaluate(shape.cloud, skeletal, (shape.curve_vertices, shape.curve_edges), progress=progress, cancel=cancel,
             workers=1)
    for stage in ["topology", "skeletal boundedness", "skeletal centeredness", "skeletal smoothness",
                  "curve boundedness", "curve centeredness"]:
        assert per_stage.get(stage, 0) >= 3, (stage, per_stage)
