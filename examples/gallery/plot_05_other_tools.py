"""
Another tool's skeleton: its frame and its correspondence
=========================================================

Skeletons from other tools rarely match the cloud row for row, and often live in their own frame
(voxel indices, another scale). :func:`skelcore.evaluate` says so instead of scoring nonsense: the
``frame`` warning (with a suggested mapping) and ``no_correspondence`` (topology and skeletal
centeredness need one). Here a T shape's skeleton is sampled with 400 points, as a tool might return
it, and written in "voxel" units (x 100, shifted).
"""

import textwrap

import matplotlib.pyplot as plt
import numpy as np

import skelcore
from skelcore import colors, shapes
from skelcore.skeleton_mapping import map_skeleton

t = shapes.t_shape(n=2500, seed=0)
rng = np.random.default_rng(0)
a, b = t.curve_vertices[t.curve_edges[:, 0]], t.curve_vertices[t.curve_edges[:, 1]]
edge = rng.integers(0, len(a), 400)
along = rng.uniform(size=(400, 1))
tool_points = (a[edge] + along * (b[edge] - a[edge])) * 100 + 50  # the tool's frame

# %%
# As the tool wrote it: in another frame, and 400 points for a 2,500-point cloud.
ev = skelcore.evaluate(t.cloud, skeletal=tool_points)
for w in ev.warnings:
    print(textwrap.fill(f"{w.code}: {w.message}", 88), end="\n\n")

# %%
# Mapped back (``--skeleton-scale 0.01 --skeleton-offset -0.5 -0.5 -0.5`` on the command line; the
# warning's own estimate is close), and matched to the cloud by the paper's reverse projection
# (``--correspondence reverse``: each cloud point goes to its nearest skeletal point, docs/metrics.md 5.1):
mapped, _ = map_skeleton(tool_points, None, scale=0.01, offset=(-0.5, -0.5, -0.5))
ev = skelcore.evaluate(t.cloud, skeletal=mapped, correspondence="reverse")
print("warnings:", [w.code for w in ev.warnings] or "none")
print("correspondence:", ev.correspondence)
summary = ev.summary()
for metric in ("boundedness", "centeredness", "smoothness"):
    print(f"{metric:13s} {summary[metric]['skeletal']:.3f}")
topo = summary["topology"]
print(f"d_B / d_Wp    {topo['bottleneck']:.4f} / {topo['wasserstein']:.4f}")

# %%
# Each skeletal point's centeredness is the mean over the cloud points mapped to it; magenta: no
# cloud point maps to it (NaN, docs/metrics.md 5.1), as happens where a tool samples its skeleton densely.
fig, ax = plt.subplots(figsize=(7, 4.2))
grey = colors.hex_color(colors.CLOUD_GREY)
ax.scatter(t.cloud[:, 0], t.cloud[:, 2], s=1, color=grey, alpha=0.35)
c = ev.skeletal.centeredness(ev.params.beta_star)
ax.scatter(mapped[:, 0], mapped[:, 2], s=12, c=colors.map_to_rgb(c, 0, 1) / 255)
ax.set_aspect("equal")
ax.set_xlabel("x")
ax.set_ylabel("z")
sm = plt.cm.ScalarMappable(cmap=colors.METRIC_COLORMAP, norm=plt.Normalize(0, 1))
fig.colorbar(sm, ax=ax, shrink=0.7, label="skeletal point centeredness (reverse projection)")
plt.show()
