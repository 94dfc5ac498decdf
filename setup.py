"""Build step for the one compiled module, the rays boundedness kernel (docs/boundedness.md, section 3).

Everything else is declared in pyproject.toml.  The kernel is plain C against the CPython API (no numpy
headers), so building needs only a C compiler and the Python headers.
"""

from setuptools import Extension, setup

setup(
    ext_modules=[
        Extension(
            "skelcore.metrics._raycast",
            sources=["skelcore/metrics/_raycast.c"],
            extra_compile_args=["-O3", "-std=c99"],
        )
    ]
)
