"""Build step for the three compiled modules: the rays boundedness kernel (docs/boundedness.md, section 3),
the coverage kernel (docs/metrics.md, section 5.2) and the topology stage's EMST (docs/performance.md,
section 8).

Everything else is declared in pyproject.toml.  The kernels are plain C against the CPython API (no numpy
headers), so building needs only a C compiler and the Python headers.
"""

from setuptools import Extension, setup

setup(
    ext_modules=[
        Extension(
            "skelcore.metrics._raycast",
            sources=["skelcore/metrics/_raycast.c"],
            extra_compile_args=["-O3", "-std=c99"],
        ),
        Extension(
            "skelcore.metrics._balls",
            sources=["skelcore/metrics/_balls.c"],
            extra_compile_args=["-O3", "-std=c99"],
        ),
        Extension(
            "skelcore.metrics._emst",
            sources=["skelcore/metrics/_emst.c"],
            extra_compile_args=["-O3", "-std=gnu99"],
        ),
    ]
)
