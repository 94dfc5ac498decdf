"""
Topology: the two H0 barcodes
=============================

Topological similarity (paper Sec. 2.1, Eq. 1-4) compares how the cloud and the skeletal point set
fall apart into clusters as a radius grows: the H0 barcodes of their Vietoris-Rips filtrations. The
K longest bars are compared (K from the threshold eps*, Eq. 2) by the bottleneck distance d_B and
the normalized Wasserstein distance d_Wp; 0 means the same clustering structure.

A cylinder's exact skeleton (its axis) against a skeleton that collapsed into 6 clumps: the clumps'
long bars stand out in the second barcode and both distances grow.
"""

import matplotlib.pyplot as plt
import numpy as np

import skelcore
from skelcore import shapes
from skelcore.compare.render import draw_barcodes

cyl = shapes.cylinder(n=2000, radius=0.5, length=4.0, seed=0)

# the clumped skeleton: every skeletal point snapped to the nearest of 6 points on the axis
centres = np.linspace(0.3, 3.7, 6)
z = centres[np.abs(cyl.skeletal[:, 2:3] - centres).argmin(axis=1)]
rng = np.random.default_rng(0)
clumped = np.column_stack([np.zeros_like(z), np.zeros_like(z), z])
clumped += rng.normal(scale=0.004, size=clumped.shape)

fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
for ax, (name, skeletal) in zip(axes, [("axis", cyl.skeletal), ("6 clumps", clumped)]):
    t = skelcore.evaluate(cyl.cloud, skeletal=skeletal).topology
    draw_barcodes(ax, {"cloud_barcode": t.cloud_barcode,
                       "skeletal_barcode": t.skeletal_barcode,
                       "n_bars": np.array([t.n_bars]),
                       "eps_star": np.array([t.eps_star])})
    title = f"{name}: d_B {t.bottleneck:.4f}, d_Wp {t.wasserstein:.4f}  (K = {t.n_bars})"
    ax.set_title(title, fontsize=9)
fig.tight_layout()
plt.show()
