"""The other tools a compare manifest can name by ``kind``: which package each
needs, its parameters, what its skeletal set is, and its version for the job key.

The tools are optional (``pip install 'skelscope[skeletonizers]'``). :func:`require` imports one
and returns ``"PyGEL3D 0.8.2; adapter 1"``: the manifest check calls it before any job runs (a
missing tool is one line naming the extra), the job key holds the string (a tool upgrade or an
adapter change reruns exactly that tool's jobs) and the child process checks it again.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import SkelInputError
from .adapter_params import Param, resolve
from .adapter_result import AdapterResult

__all__ = ["Adapter", "ADAPTERS", "KINDS", "EXTRA", "ADAPTER_REVISION", "adapter", "params_of",
           "resolve_params", "require", "run"]

#: how to install every tool at once
EXTRA = "pip install 'skelscope[skeletonizers]'"
#: the adapters' own code: raise it when a change alters their outputs, so their jobs rerun
ADAPTER_REVISION = 1


@dataclass(frozen=True)
class Adapter:
    kind: str  # the manifest's ``kind``
    tool: str  # the distribution pip installs (its version is recorded)
    module: str  # the tool's import name
    impl: str  # our module: PARAMS and skeletonize(points, params)
    summary: str


ADAPTERS: dict[str, Adapter] = {a.kind: a for a in (
    Adapter("pygel", "PyGEL3D", "pygel3d.graph", "skelcore.adapters.pygel_ls",
            "PyGEL3D's local-separator skeleton of the cloud's kNN graph (pointwise map)"),
    Adapter("kimimaro", "kimimaro", "kimimaro", "skelcore.adapters.kimimaro_teasar",
            "kimimaro's TEASAR skeleton of the voxelized, filled cloud"),
    Adapter("skimage", "scikit-image", "skimage.morphology", "skelcore.adapters.skimage_thinning",
            "scikit-image's 3-D thinning of the voxelized, filled cloud, as a 26-neighbour graph"),
)}
KINDS = tuple(ADAPTERS)


def adapter(kind: str) -> Adapter:
    if kind not in ADAPTERS:
        raise SkelInputError(f"unknown skeletonizer kind {kind!r} (adapters: {', '.join(KINDS)})")
    return ADAPTERS[kind]


def params_of(kind: str) -> tuple[Param, ...]:
    """The adapter's parameters (its module imports the tool only when it runs)."""
    return importlib.import_module(adapter(kind).impl).PARAMS


def resolve_params(kind: str, given: dict[str, Any]) -> dict[str, Any]:
    """Every parameter with its default filled in; ValueError (one line) on a bad one."""
    return resolve(params_of(kind), given)


def require(kind: str) -> str:
    """Import the tool; its version string, or a one-line SkelInputError naming the extra."""
    from importlib.metadata import PackageNotFoundError, version

    a = adapter(kind)
    try:
        importlib.import_module(a.module)
    except Exception as exc:  # ImportError, or a wheel whose compiled library does not load (OSError)
        why = " ".join(str(exc).split())[:160] or type(exc).__name__
        raise SkelInputError(f"kind {kind!r} needs {a.tool}, which cannot be imported ({why}): {EXTRA}") from None
    try:
        v = version(a.tool)
    except PackageNotFoundError:
        v = getattr(importlib.import_module(a.module.split(".")[0]), "__version__", "unknown")
    return f"{a.tool} {v}; adapter {ADAPTER_REVISION}"


def run(kind: str, points: np.ndarray, params: dict[str, Any] | None = None) -> AdapterResult:
    """Run the tool in this process on ``points`` (N x 3, the cloud's frame) and return its skeleton
    in that frame. (``skelcore compare`` runs it in a child process instead: :mod:`.child`.)"""
    require(kind)
    try:
        resolved = resolve_params(kind, params or {})
    except ValueError as exc:
        raise SkelInputError(f"{kind}: {exc}") from None
    return importlib.import_module(adapter(kind).impl).skeletonize(np.asarray(points, dtype=float), resolved)
