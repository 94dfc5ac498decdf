"""The 3D view: turns the Qt-free scene into pyvista actors inside a ``QtInteractor``.

Only this package touches VTK, and only on the GUI thread. Modules: :mod:`.scene_view` (the
``SceneView``), :mod:`.interactor` (the Qt widget and its input), :mod:`.frames` (frame
scheduling), :mod:`.paint_hold` (the window's repaints held with the frames), :mod:`.actors` (actor-building helpers), :mod:`.lod` (twins while moving), :mod:`.culling`
and :mod:`.visibility` (the points that can show at rest), :mod:`.colorbar`, :mod:`.camera`, :mod:`.style`.

The names below are imported on first use: reading a camera file (:mod:`.camera`, no Qt) before any
window opens must not import Qt ahead of VTK (``app.__main__.import_view_libraries``).
"""

from __future__ import annotations

from typing import Any

__all__ = ["SceneView", "DropInteractor", "RENDER_DELAY_MS"]

_WHERE = {"SceneView": "scene_view", "DropInteractor": "interactor", "RENDER_DELAY_MS": "frames"}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        import importlib

        return getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
