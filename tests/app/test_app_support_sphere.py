"""The boundedness support's directions also on a small 3-D sphere beside the equal-area
map, on a shape with a known answer (a point above a sphere sees the cap below it)."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import evaluate, shapes
from skelcore.params import Params

pytestmark = pytest.mark.gui


@pytest.mark.parametrize("method", ["rays", "paper"])
def test_the_direction_sphere_shows_the_cap_below_a_point_above_a_sphere(window, method, qtbot):
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    radius, dist = 1.0, 2.0
    cloud = shapes.sphere_surface(2000, radius, seed=3)
    skeletal = np.array([[0.0, 0.0, dist], [0.0, 0.0, 0.0], [0.2, 0.1, 0.0]])
    ev = evaluate(cloud, skeletal, params=Params(boundedness_method=method))
    window.session.show_arrays(cloud, skeletal, None, ev)
    window.scene.set_metric("boundedness")
    window.pick_element(window.scene.element_info("skeletal", "points", 0))
    panel = window.supports.panel
    fig = panel.figure
    assert len(fig.axes) == 2 and fig.axes[1].name == "3d"
    polys = [c for c in fig.axes[1].collections if isinstance(c, Poly3DCollection)]
    assert len(polys) == 1
    centres, covered = panel.sphere_faces
    colours = np.asarray(polys[0].get_facecolor())
    assert len(colours) == len(covered) == len(centres)
    blue = colours[:, 2] > colours[:, 0] + 0.1  # the covered colour, shaded; the others grey or pink
    assert blue.sum() == covered.sum() > 0  # as many faces drawn blue as covered (matplotlib depth-sorts them)
    if method == "rays":
        # equal-area cells: the covered share of the faces is beta, the same cells as the map's
        np.testing.assert_array_equal(covered, panel.support.detail.covered.reshape(-1))
        assert covered.mean() == pytest.approx(ev.skeletal.boundedness[0], abs=0.01)
        h = panel.support.detail.radius / ev.normalization.scale
        cap_cos = np.cos(np.arcsin((radius + h) / dist))  # the cap's half-angle around -z
        assert np.all(centres[covered, 2] < -cap_cos + 0.1)  # every covered face points down, into the cap
        assert np.all(covered[centres[:, 2] < -cap_cos - 0.1])  # and the cap's core is all covered
    else:
        # the paper estimator's directions are q - p: from the sphere below up to the query
        assert covered.any() and np.all(centres[covered, 2] > 0.5)
    panel.draw_now()
    qtbot.wait(50)
    # the centre of the sphere sees (nearly) every direction
    window.pick_element(window.scene.element_info("skeletal", "points", 1))
    _c, inside = panel.sphere_faces
    assert inside.mean() > 0.85
    # other supports have no sphere
    window.scene.set_metric("smoothness")
    assert panel.sphere_faces is None and len(panel.figure.axes) == 1
