"""False alarms of the "skeletal outside" stage (docs/diagnostics.md "Outside").

Skeletal sets of both built-in skeletonizers on the real scans (resources/scans) and on
generated shapes (2k / 20k points, 0 / 3 % isotropic noise): the share of skeletal points outside,
the largest cluster's share (``outside`` fires above Params.outside_skeletal_share) and the stage's time.

    python benchmarks/bench_skeletal_outside.py
"""

from __future__ import annotations

from pathlib import Path

import skelcore
from skelcore import shapes
from skelcore.io import load_cloud
from skelcore.skeleton.degrade import add_noise
from skelcore.skeleton.pipeline import skeletonize

SCANS = Path(__file__).resolve().parents[1] / "resources" / "scans"


def cases():
    for name in ("hammer_4096.ply", "apple_tree_22367.ply", "cave_27375.ply", "horse_1987_mesh.ply"):
        yield name, load_cloud(SCANS / name)
    for family in ("cylinder", "y_shape", "torus"):
        for n in (2000, 20000):
            for noise in (0.0, 0.03):
                cloud = getattr(shapes, family)(n, seed=2).cloud
                if noise:
                    cloud = add_noise(cloud, noise, model="isotropic", seed=3)
                yield f"{family} {n} noise {noise}", cloud


def main() -> None:
    threshold = skelcore.Params().outside_skeletal_share
    print(f"| cloud | method | outside share | largest cluster (fires > {threshold:.0%}) | warnings | stage s |")
    print("|---|---|---|---|---|---|")
    for name, cloud in cases():
        for method in ("cao", "skelscope"):
            skeletal, _curve = skeletonize(cloud, method=method)
            ev = skelcore.evaluate(cloud, skeletal)
            so = ev.diagnostics.summary["skeletal_outside"]
            codes = ", ".join(w.code for w in ev.warnings) or "-"
            print(f"| {name} | {method} | {so['share']:.4f} | {so['largest_cluster_share']:.4f} | {codes} | "
                  f"{ev.timings.get('skeletal outside', float('nan')):.2f} |", flush=True)


if __name__ == "__main__":
    main()
