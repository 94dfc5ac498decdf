"""Shared set-up of the compare tests: a small dataset of generated shapes with their true skeletons
as precomputed files, and tiny external skeletonizers (good, crashing, hanging, garbage-writing)."""

from __future__ import annotations

import shlex
import sys
import textwrap
from pathlib import Path

from skelcore import shapes
from skelcore.io import write_curve_ply, write_points_ply

PY = shlex.quote(sys.executable)

# a straight line along the cloud's principal axis: quick, valid, and clearly not the built-in
LINE = """
import sys, os, time, numpy as np
from skelcore.io import load_cloud, write_curve_ply
if os.environ.get("SKEL_PIDS"):
    open(os.path.join(os.environ["SKEL_PIDS"], str(os.getpid())), "w").close()
time.sleep(float(os.environ.get("SKEL_SLEEP", "0")))
c = load_cloud(sys.argv[1])
m = c.mean(axis=0)
u = np.linalg.svd(c - m, full_matrices=False)[2][0]
t = (c - m) @ u
v = m + np.outer(np.linspace(t.min(), t.max(), 12), u)
write_curve_ply(sys.argv[2], v, np.column_stack([np.arange(11), np.arange(1, 12)]))
"""
CRASH = "import sys\nprint('segmentation fault (pretend)', file=sys.stderr)\nsys.exit(139)\n"
HANG = """
import os, sys, time
open(os.path.join("hang_pids", str(os.getpid())), "w").close()  # the manifest's folder is the cwd
time.sleep(600)
"""
GARBAGE = "import sys\nopen(sys.argv[2], 'w').write('this is not a skeleton\\n')\n"


def make_dataset(root: Path, n: int = 700) -> Path:
    """clouds/{cyl,yshape}.ply, skeletons/{stem}_{skeletal,curve}.ply (the true ones), scripts."""
    (root / "clouds").mkdir(parents=True, exist_ok=True)
    (root / "skeletons").mkdir(exist_ok=True)
    (root / "bin").mkdir(exist_ok=True)
    for stem, shape in (("cyl", shapes.cylinder(n, seed=3)), ("yshape", shapes.y_shape(n, seed=4))):
        write_points_ply(root / "clouds" / f"{stem}.ply", shape.cloud)
        write_points_ply(root / "skeletons" / f"{stem}_skeletal.ply", shape.skeletal)
        write_curve_ply(root / "skeletons" / f"{stem}_curve.ply", shape.curve_vertices, shape.curve_edges)
    for name, text in (("line", LINE), ("crash", CRASH), ("hang", HANG), ("garbage", GARBAGE)):
        (root / "bin" / f"{name}.py").write_text(textwrap.dedent(text))
    return root


def manifest(root: Path, body: str, name: str = "m.toml") -> Path:
    path = root / name
    path.write_text(textwrap.dedent(body))
    return path


def command(script: str, extra: str = "") -> str:
    """A TOML-safe command line running bin/SCRIPT.py with the test's interpreter."""
    return f"{sys.executable} bin/{script}.py {{in}} {{out_curve}}{extra}"
