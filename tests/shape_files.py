"""A Shape (skelcore.shapes) written as the files a user would open: cloud, skeletal set and curve as PLY."""

from __future__ import annotations

from pathlib import Path


def write_shape_files(folder: Path, shape, stem: str = "y") -> dict[str, str]:
    """Write a Shape's cloud, skeletal set and curve as PLY files; returns their paths by role."""
    from skelcore.io import write_curve_ply, write_points_ply

    paths = {k: Path(folder) / f"{stem}_{k}.ply" for k in ("cloud", "skeletal", "curve")}
    write_points_ply(paths["cloud"], shape.cloud)
    write_points_ply(paths["skeletal"], shape.skeletal)
    write_curve_ply(paths["curve"], shape.curve_vertices, shape.curve_edges)
    return {k: str(v) for k, v in paths.items()}
