"""The viewer's Qt-free model: layers owning named scalar quantities, and change callbacks.

Following Polyscope's structures/quantities and napari's layer model. Nothing in this package
imports Qt or VTK. Modules: :mod:`.layers` (layers, quantities, metric names), :mod:`.events`
(change events), :mod:`.model` (the ``Scene``), :mod:`.element_text` (a picked element as text).
"""

from .element_text import format_element_info
from .events import Listener, SceneEvent
from .layers import CURVE_LOCATION, LAYER_ORDER, METRICS, Layer, ScalarQuantity
from .model import Scene

__all__ = [
    "METRICS", "LAYER_ORDER", "CURVE_LOCATION", "ScalarQuantity", "Layer", "Scene", "SceneEvent", "Listener",
    "format_element_info",
]
