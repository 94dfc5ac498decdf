"""The view's single colour bar: which metric the coloured actor shows, NaN annotated magenta.

pyvista's ``add_scalar_bar`` costs several ms and a new bar re-renders its text, so the bar is made
only when the coloured actor or the metric changes and is otherwise updated in place.
"""

from __future__ import annotations

from typing import Any

from ..scene import Scene

__all__ = ["ColourBar"]


class ColourBar:
    """The one scalar bar of ``plotter``, describing the actor last passed to :meth:`update`."""

    def __init__(self, plotter: Any) -> None:
        self.plotter = plotter
        self.actor: Any = None  # the actor the colour bar describes

    def update(self, actor: Any, scene: Scene) -> None:
        """Describe ``actor`` (None: no bar) coloured by ``scene.metric``; the NaN swatch is shown
        while any shown value is invalid."""
        bars = self.plotter.scalar_bars
        if actor is None or actor is not self.actor or scene.metric not in bars:
            for title in list(bars.keys()):
                self.plotter.remove_scalar_bar(title, render=False)
            self.actor = actor
            if actor is None:
                return
            self.plotter.add_scalar_bar(
                title=scene.metric, mapper=actor.mapper, n_labels=5, fmt="%.2f", color="black",
                vertical=True, position_x=0.87, position_y=0.25, width=0.06, height=0.5, title_font_size=14,
                label_font_size=12, render=False,
            )
        bar = bars[scene.metric]
        bar.SetLookupTable(actor.mapper.lookup_table)
        bar.SetDrawNanAnnotation(scene.n_invalid_shown() > 0)
