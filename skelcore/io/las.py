"""LAS/LAZ point clouds (airborne and terrestrial lidar) through ``laspy``, an optional extra:
``pip install 'skelscope[las]'`` (laspy with the lazrs LAZ backend). Scaled x, y, z only."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..errors import SkelInputError
from ._common import RawData

EXTRA_HINT = "reading LAS/LAZ needs the optional extra: pip install 'skelscope[las]'"


def is_las(head: bytes) -> bool:
    return head.startswith(b"LASF")


def read_las(path: Path, data: bytes) -> RawData:
    try:
        import laspy
    except ImportError:
        raise SkelInputError(EXTRA_HINT, path) from None
    try:
        las = laspy.read(io.BytesIO(data))
    except laspy.errors.LaspyException as exc:
        text = " ".join(str(exc).split())
        if "backend" in text.lower() or "laz" in text.lower():
            raise SkelInputError(f"{EXTRA_HINT} (LAZ: {text[:120]})", path) from None
        raise SkelInputError(f"malformed LAS/LAZ file: {text[:160]}", path) from None
    pts = np.column_stack([np.asarray(las.x, dtype=np.float64), np.asarray(las.y, dtype=np.float64),
                           np.asarray(las.z, dtype=np.float64)])
    return RawData(vertices=pts, edges=None, format="LAS")
