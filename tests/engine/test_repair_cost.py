"""The repair's first look without the real-scan trust checks (docs/repair.md "The repair's cost"):
it reads no warning, and the whole update runs them, so the repair keeps and refuses the same actions
and gives the same curve and log as the slower path that runs them at every first look. Checked on an
open cylinder (the ``open_surface`` warning fires on its axis) whose axis has a spur through the wall."""

from __future__ import annotations

import numpy as np
import pytest

import skelcore
from skelcore import shapes
from skelcore.curve import CurveSkeleton
from skelcore.skeleton_repair import repair, screen


@pytest.fixture(scope="module")
def open_tube() -> tuple[np.ndarray, CurveSkeleton]:
    cyl = shapes.cylinder(2500, radius=0.5, length=4.0, capped=False, seed=4)
    v, e = np.asarray(cyl.curve_vertices, float), np.asarray(cyl.curve_edges)
    mid, n = len(v) // 2, len(v)
    spur = v[mid] + np.array([[0.3, 0, 0], [0.6, 0, 0], [0.9, 0, 0]])
    return cyl.cloud, CurveSkeleton.from_raw(np.vstack([v, spur]), np.vstack([e, [[mid, n], [n, n + 1], [n + 1, n + 2]]]))


def _codes(ev: skelcore.Evaluation) -> list[str]:
    return sorted(w.code for w in ev.warnings)


def test_the_first_phase_without_scan_checks_completes_to_the_whole_update(open_tube):
    """update(diagnostics=False, scan_checks=False) has no scan warning; completed, it has the whole
    update's warnings, measures and defects (the scan checks run in complete_update)."""
    cloud, curve = open_tube
    ev = skelcore.evaluate(cloud, curve=curve)
    assert "open_surface" in _codes(ev)
    n = curve.n_vertices - 3  # the spur's three vertices last
    pruned = CurveSkeleton.from_raw(curve.vertices[:n], curve.edges[(curve.edges < n).all(axis=1)])
    quick = ev.update(pruned, diagnostics=False, scan_checks=False)
    assert "open_surface" not in _codes(quick)
    assert "open_surface" in _codes(ev.update(pruned, diagnostics=False))  # the default runs them
    whole, done = ev.update(pruned), quick.complete_update()
    assert _codes(done) == _codes(whole) and "open_surface" in _codes(done)
    assert done.summary() == whole.summary()
    assert done.diagnostics.to_dict() == whole.diagnostics.to_dict()


def test_the_repair_is_the_same_with_and_without_scan_checks_at_first_look(open_tube, monkeypatch):
    """The same log (kept and refused, with their measures), the same curve to the bit and the same
    warnings after, with the first looks' scan checks left out (the default) and run."""
    cloud, curve = open_tube
    assert screen.SCAN_CHECKS is False
    fast = repair(cloud, curve)
    monkeypatch.setattr(screen, "SCAN_CHECKS", True)
    slow = repair(cloud, curve)
    assert fast.accepted >= 1 and fast.log == slow.log
    assert np.array_equal(fast.curve.vertices, slow.curve.vertices) and np.array_equal(fast.curve.edges, slow.curve.edges)
    assert _codes(fast.after) == _codes(slow.after) and "open_surface" in _codes(fast.after)
