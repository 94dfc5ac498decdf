"""Pictures and tables of an Evaluation for notebooks, windows and files: ``where``
(notebook? display?), ``picture_arrays`` (what a picture draws), ``scene`` (the pyvista scene, colours of
docs/metrics.md 5.5), ``plotter`` (panels side by side, off-screen PNG), ``barcodes`` (the H0 barcodes),
``summary_table`` (the paper's summary table as text and HTML), ``show`` (``Evaluation.show``,
``show_barcodes``, ``show_ab``). pyvista, matplotlib and IPython are imported only when drawing.
"""

from __future__ import annotations

from .show import show, show_ab, show_barcodes

__all__ = ["show", "show_ab", "show_barcodes"]
