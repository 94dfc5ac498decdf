"""A deliberately simple external skeletonizer for `skelcore compare` examples: the cloud's principal
axis as a 16-vertex polyline (right for a straight tube, wrong for anything that branches or bends).

    python axis_skeleton.py CLOUD OUT_CURVE.ply
"""

import sys

import numpy as np

from skelcore.io import load_cloud, write_curve_ply

cloud = load_cloud(sys.argv[1])
mean = cloud.mean(axis=0)
axis = np.linalg.svd(cloud - mean, full_matrices=False)[2][0]
t = (cloud - mean) @ axis
vertices = mean + np.outer(np.linspace(t.min(), t.max(), 16), axis)
write_curve_ply(sys.argv[2], vertices, np.column_stack([np.arange(15), np.arange(1, 16)]))
