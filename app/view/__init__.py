"""The 3D view: turns the Qt-free scene into pyvista actors inside a ``QtInteractor``.

Only this package touches VTK, and only on the GUI thread. Modules: :mod:`.scene_view` (the
``SceneView``), :mod:`.interactor` (the Qt widget and its input), :mod:`.frames` (frame
scheduling), :mod:`.actors` (actor-building helpers), :mod:`.colorbar`, :mod:`.camera`, :mod:`.style`.
"""

from .frames import RENDER_DELAY_MS
from .interactor import DropInteractor
from .scene_view import SceneView

__all__ = ["SceneView", "DropInteractor", "RENDER_DELAY_MS"]
