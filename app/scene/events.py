"""Scene change events: what the model tells its subscribers (the 3D view, the panels).

Kept apart from the model so a subscriber can name the event type without the ``Scene`` itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

__all__ = ["SceneEvent", "Listener"]


@dataclass(frozen=True)
class SceneEvent:
    """What changed: ``kind`` is 'layer', 'display', 'quantities', 'colouring', 'thresholds',
    'stale' (the results went out of date or back) or 'style' (a figure option; ``layer`` names the
    option)."""

    kind: str
    layer: str | None = None


Listener = Callable[[SceneEvent], None]
