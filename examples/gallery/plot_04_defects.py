"""
Defects without a reference: a spurious branch
==============================================

The paper's metrics score element by element and cannot see an extra branch. The diagnostics
(docs/diagnostics.md) read the curve skeleton as branches and flag those that explain no part of
the shape of their own. Here a Y shape's exact curve gets a short spur growing out of one arm; the
evaluation's ``defects`` find it without being told the true skeleton.
"""

import matplotlib.pyplot as plt
import numpy as np

import skelcore
from skelcore import colors, shapes
from skelcore.diagnostics.record import DEFECT_BITS

y = shapes.y_shape(n=3000, radius=0.25, arm=2.0, seed=1)
verts, edges = y.curve_vertices, y.curve_edges

# a spur: 3 vertices leaving vertex 6 of the first arm sideways, 0.21 long
# (shorter than the arm's radius, 0.25)
base = verts[6]
spur = base + np.outer([0.07, 0.14, 0.21], [1.0, 0.0, 0.0])
n = len(verts)
verts = np.vstack([verts, spur])
edges = np.vstack([edges, [[6, n], [n, n + 1], [n + 1, n + 2]]])

ev = skelcore.evaluate(y.cloud, curve=(verts, edges))
found = ev.diagnostics.summary["spurious_branches"]
print("terminal branches:", found["terminal"], " spurious:", found["spurious"])
for w in ev.warnings:
    print("warning:", w.code, "-", w.message)

flags = ev.diagnostics.arrays["curve_vertex_defects"]
spurious = (flags & DEFECT_BITS["spurious_branches"]) > 0

grey, curve, magenta = (colors.hex_color(c) for c in (colors.CLOUD_GREY, colors.CURVE_COLOR,
                                                      colors.NAN_COLOR))
fig, ax = plt.subplots(figsize=(6, 5))
ax.scatter(y.cloud[:, 0], y.cloud[:, 1], s=1, color=grey, alpha=0.3)
for a, b in edges:
    both = spurious[a] and spurious[b]
    ax.plot(*verts[[a, b], :2].T, color=magenta if both else curve, linewidth=3 if both else 1.5)
ax.scatter(*verts[~spurious, :2].T, s=10, color=curve, label="curve vertex")
ax.scatter(*verts[spurious, :2].T, s=25, color=magenta, label="on a spurious branch")
ax.set_aspect("equal")
ax.set_title(f"{found['spurious']} spurious branch found "
             f"(of {found['terminal']} terminal branches)")
ax.legend(loc="lower left", fontsize=8)
plt.show()
