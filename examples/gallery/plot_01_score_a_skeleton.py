"""
Score a skeleton and colour it by centeredness
==============================================

A torus sampled with 2,000 points, scored twice: against its exact skeleton (the core circle) and
against a skeleton whose points drifted halfway toward the surface. :func:`skelcore.evaluate` gives
every skeletal point a local centeredness (paper Eq. 10; 1 = in the middle of the shape) and the
overall score is the share above the threshold ``c_star`` (Eq. 12).
"""

import matplotlib.pyplot as plt
import numpy as np

import skelcore
from skelcore import colors, shapes
from skelcore.scores import paper_table

torus = shapes.torus(n=2000, R=1.0, r=0.3, seed=0)

# the exact skeleton: each surface point projected onto the core circle
# (pointwise correspondence: row i of the skeleton is where cloud row i went)
exact = torus.skeletal
# a drifted one: each skeletal point moved halfway toward its own surface point,
# plus a little jitter
rng = np.random.default_rng(1)
drifted = exact + 0.5 * (torus.cloud - exact) + rng.normal(scale=0.01, size=exact.shape)

evaluations = {
    "exact skeleton": skelcore.evaluate(torus.cloud, skeletal=exact),
    "drifted halfway to the surface": skelcore.evaluate(torus.cloud, skeletal=drifted),
}

# %%
# The paper's table for each (rows d_B / d_Wp, boundedness, centeredness, smoothness; the number of
# elements each score counted in brackets):
for name, ev in evaluations.items():
    print(name)
    for row, skeletal_cell, _curve_cell in paper_table(ev.scores()):
        print(f"  {row:14s} {skeletal_cell}")

# %%
# The local values, drawn over the faint cloud with the viewer's colours (viridis over [0, 1],
# magenta for an invalid value, docs/metrics.md 5.5):
fig = plt.figure(figsize=(9, 4.2))
for i, (name, ev) in enumerate(evaluations.items()):
    ax = fig.add_subplot(1, 2, i + 1, projection="3d")
    grey = colors.hex_color(colors.CLOUD_GREY)
    ax.scatter(*torus.cloud[::3].T, s=1, color=grey, alpha=0.3)
    c = ev.skeletal.centeredness(ev.params.beta_star)
    rgb = colors.map_to_rgb(c, 0, 1) / 255
    ax.scatter(*ev.skeletal.points.T, s=3, c=rgb)
    score = ev.summary()["centeredness"]["skeletal"]
    ax.set_title(f"{name}\ncenteredness {score:.3f}", fontsize=10)
    ax.set_box_aspect((1, 1, 0.35))
    ax.view_init(elev=35, azim=-60)
    ax.set_axis_off()
sm = plt.cm.ScalarMappable(cmap=colors.METRIC_COLORMAP, norm=plt.Normalize(0, 1))
fig.colorbar(sm, ax=fig.axes, shrink=0.6, label="skeletal point centeredness")
plt.show()
