"""
How the scores fall as a skeleton gets worse
============================================

A cylinder's exact skeletal set (its axis) with growing Gaussian jitter, scored each time: the
points leave the middle (centeredness, Eq. 10-12), then the shape (boundedness, Eq. 5-7), their
neighbours stop lining up (smoothness, Eq. 13-16) and the clusters change (d_B, Eq. 3). Each score is
the overall value of the skeletal set, as in the paper's table; the dotted lines are the exact
skeleton's scores.

Smoothness goes first: on a dense axis a jitter of a few per cent of the radius already turns the
tangents of the 8 nearest neighbours (Eq. 13) every which way. d_B does not move while the
skeleton's bars are all much shorter than the cloud's (it is then set by the cloud's longest bars),
dips when the jitter brings the skeleton's point spacing near the cloud's, and grows past it.
"""

import matplotlib.pyplot as plt
import numpy as np

import skelcore
from skelcore import shapes

cyl = shapes.cylinder(n=2000, radius=0.5, length=4.0, seed=0)
rng = np.random.default_rng(0)
sigmas = np.array([0.0, 0.005, 0.03, 0.15, 0.45])  # x the radius
rows = []
for s in sigmas:
    jittered = cyl.skeletal + rng.normal(scale=s * 0.5, size=cyl.skeletal.shape)
    summary = skelcore.evaluate(cyl.cloud, skeletal=jittered).summary()
    rows.append([summary[m]["skeletal"] for m in ("boundedness", "centeredness", "smoothness")]
                + [summary["topology"]["bottleneck"]])
rows = np.array(rows)

fig, (ax, ax_top) = plt.subplots(1, 2, figsize=(9, 3.4))
for j, name in enumerate(("boundedness", "centeredness", "smoothness")):
    ax.plot(sigmas[1:], rows[1:, j], "o-", label=name)
    ax.axhline(rows[0, j], color=ax.lines[-1].get_color(), linestyle=":", linewidth=0.8)
ax.set_xscale("log")
ax.set_xlabel("jitter (standard deviation / radius)")
ax.set_ylabel("overall score (1 = best)")
ax.set_ylim(-0.02, 1.02)
ax.legend(fontsize=8)
ax_top.plot(sigmas[1:], rows[1:, 3], "o-", color="k")
ax_top.axhline(rows[0, 3], color="k", linestyle=":", linewidth=0.8)
ax_top.set_xscale("log")
ax_top.set_xlabel("jitter (standard deviation / radius)")
ax_top.set_ylabel("d_B (0 = same H0 barcode)")
fig.tight_layout()
plt.show()
