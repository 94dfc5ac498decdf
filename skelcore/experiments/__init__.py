"""Experiments built on the engine: the paper's degradation study (``study``)."""
