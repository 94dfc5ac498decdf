"""A matplotlib figure laid out once by ``tight_layout`` and then left with no layout engine.

``Figure.tight_layout`` leaves a placeholder engine on the figure, and ``savefig`` draws a figure
that has any engine one extra time before the real draw (matplotlib's ``print_figure``). The layout is
already fixed, so that extra draw only costs time: without the engine the PNG is the same, byte for
byte, drawn once (docs/performance.md 6.12).
"""

from __future__ import annotations

from typing import Any

__all__ = ["tight_layout_once"]


def tight_layout_once(fig: Any) -> Any:
    """``fig.tight_layout()``, then no layout engine (the figure is returned)."""
    fig.tight_layout()
    fig.set_layout_engine(None)  # None, not "none": "none" would leave the placeholder again
    return fig
