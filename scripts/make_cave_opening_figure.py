"""docs/img/cave_opening.png: the real cave scan's one opening, as skelcore.scan finds it.

Why the cave gets ``open_surface`` (docs/metrics.md 6): its passage ends open where the
scan stops at y = +0.8. The scan is resources/scans/cave_27375.ply.

    python scripts/make_cave_opening_figure.py [OUT.png]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from skelcore.io import load_cloud
from skelcore.io.atomic import atomic_open
from skelcore.scan.openings import find_openings

ROOT = Path(__file__).resolve().parents[1]
CAVE = ROOT / "resources" / "scans" / "cave_27375.ply"


def main(out: Path) -> None:
    import pyvista as pv

    cloud = load_cloud(CAVE)
    openings = find_openings(cloud)
    for o in openings:
        print(o.to_dict())
    pl = pv.Plotter(off_screen=True, window_size=(1200, 900))
    pl.set_background("white")
    pl.add_points(cloud, color=(0.6, 0.6, 0.6), point_size=2, opacity=0.35)
    for o in openings:
        pl.add_points(cloud[o.rows], color=(0.1, 0.5, 0.9), point_size=7, render_points_as_spheres=True,
                      label=f"rim of the opening ({o.kind}, {len(o.rows)} points)")
        if len(o.fill):
            pl.add_points(o.fill, color=(0.95, 0.55, 0.1), point_size=4,
                          label=f"missing surface ({len(o.fill)} fill points)")
    pl.add_legend(bcolor="white", size=(0.42, 0.12), loc="upper left")
    pl.camera_position = [(0.9, 2.6, 0.9), (0, 0.2, 0), (0, 0, 1)]
    print("cloud y range", float(np.min(cloud[:, 1])), float(np.max(cloud[:, 1])))
    image = pl.screenshot(return_img=True)
    pl.close()
    from PIL import Image

    with atomic_open(out, "wb") as fh:
        Image.fromarray(image).save(fh, format="PNG")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "docs" / "img" / "cave_opening.png")
