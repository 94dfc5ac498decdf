"""Build step for the compiled modules: the rays boundedness kernel (docs/boundedness.md, section 3), the
coverage kernel (docs/metrics.md, section 5.2), skeletal centeredness' neighbour sums, curve centeredness'
rings, the topology stage's EMST, the missing parts' connected components, the interior's passes over its
voxel grid, the passes over a removed arm's points (docs/performance.md, sections 6.4, 6.5, 6.1, 6.7 and
6.10), the first pass of the openings' surround test (docs/metrics.md 6.1) and the farthest-point sampling by spheres of cao's curve and the
repair's fills (docs/repair.md "The repair's cost").

Also here: the package list (the viewer's folder ``app/`` installs as ``skelscope``) and the package
index's long description; everything else is declared in pyproject.toml.  The kernels are plain C against the CPython API (no numpy
headers), so building needs only a C compiler and the Python headers.  On x86-64 the rays kernel is built
twice: for any x86-64 CPU, and with AVX2 as ``_raycast_avx2``, which ``rays_kernel`` imports only where
the CPU runs it (the same bits, 10-20 % faster; docs/boundedness.md 3.11).
"""

import platform
import re
from pathlib import Path

from setuptools import Extension, find_namespace_packages, setup

RAYCAST = dict(sources=["skelcore/metrics/_raycast.c"], extra_compile_args=["-O3", "-std=c99"])
X86_64 = platform.machine().lower() in ("x86_64", "amd64")


def long_description() -> str:
    """README.md for the package index, where links relative to the repository lead nowhere: a relative
    image is left out and a relative link keeps its text only (absolute links and anchors stay)."""
    text = Path(__file__).with_name("README.md").read_text(encoding="utf-8")
    text = re.sub(r"!\[[^\]]*\]\((?!https?://)[^)]*\)\n?", "", text)
    return re.sub(r"\[([^\]]+)\]\((?!https?://|#)[^)]*\)", r"\1", text)


# The viewer's folder app/ installs as the package ``skelscope`` (never a top-level ``app``).
def _packages(top: str) -> list[str]:
    return find_namespace_packages(include=[top, f"{top}.*"], exclude=["*.__pycache__"])


VIEWER = ["skelscope" + name[len("app"):] for name in _packages("app")]

setup(
    long_description=long_description(),
    long_description_content_type="text/markdown",
    packages=_packages("skelcore") + VIEWER,
    package_dir={"skelscope": "app"},
    ext_modules=[
        Extension("skelcore.metrics._raycast", **RAYCAST),
        *([Extension("skelcore.metrics._raycast_avx2", sources=RAYCAST["sources"],
                     extra_compile_args=RAYCAST["extra_compile_args"] + ["-mavx2", "-mpopcnt"],
                     define_macros=[("MODULE_NAME", "_raycast_avx2")])] if X86_64 else []),
        Extension(
            "skelcore.metrics._balls",
            sources=["skelcore/metrics/_balls.c"],
            extra_compile_args=["-O3", "-std=c99"],
        ),
        Extension(
            "skelcore.metrics._centroids",
            sources=["skelcore/metrics/_centroids.c"],
            depends=["skelcore/metrics/_pairwise_sum.h"],
            extra_compile_args=["-O3", "-std=c99", "-ffp-contract=off"],
        ),
        Extension(
            "skelcore.metrics._rings",
            sources=["skelcore/metrics/_rings.c"],
            depends=["skelcore/metrics/_pairwise_sum.h"],
            extra_compile_args=["-O3", "-std=c99", "-ffp-contract=off"],
            # linked to libm by name: glibc binds hypot to its current version, not to the old one's wrapper
            # (errno on overflow only; the same values, a fifth of hypot's instructions; docs/performance.md 6.5)
            libraries=[] if platform.system() == "Windows" else ["m"],
        ),
        Extension(
            "skelcore.metrics._components",
            sources=["skelcore/metrics/_components.c"],
            depends=["skelcore/metrics/_union_find.h"],
            extra_compile_args=["-O3", "-std=c99"],
        ),
        Extension(
            "skelcore.metrics._point_passes",
            sources=["skelcore/metrics/_point_passes.c"],
            extra_compile_args=["-O3", "-std=c99", "-ffp-contract=off"],
        ),
        Extension(
            "skelcore.metrics._region_links",
            sources=["skelcore/metrics/_region_links.c"],
            extra_compile_args=["-O3", "-std=c99"],
        ),
        Extension(
            "skelcore.metrics._voxels",
            sources=["skelcore/metrics/_voxels.c"],
            depends=["skelcore/metrics/_union_find.h"],
            extra_compile_args=["-O3", "-std=c99"],
        ),
        Extension(
            "skelcore.metrics._surround",
            sources=["skelcore/metrics/_surround.c"],
            extra_compile_args=["-O3", "-std=c99"],
        ),
        Extension(
            "skelcore.skeleton._farthest",
            sources=["skelcore/skeleton/_farthest.c"],
            extra_compile_args=["-O3", "-std=gnu99", "-ffp-contract=off"],
        ),
        Extension(
            "skelcore.metrics._emst",
            sources=["skelcore/metrics/_emst.c"],
            extra_compile_args=["-O3", "-std=gnu99"],
        ),
    ]
)
