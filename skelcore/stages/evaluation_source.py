"""What an Evaluation keeps of how it was made, so that :meth:`skelcore.Evaluation.update` can score an
edited curve the same way: the arguments of :func:`skelcore.evaluate` and the context the stages
shared (the normalized cloud, its search structures, every stage's result). The context is not
pickled (it holds locks and trees): a copied Evaluation updates by evaluating again."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .catalogue import CATALOGUE
from .context import EvalContext

__all__ = ["EvaluationSource", "CURVE_STAGES", "REUSED", "READ_BY_REPAIR"]

#: the stages whose result depends on the curve (their context inputs name it): an update runs them again
CURVE_STAGES = tuple(s.name for s in CATALOGUE
                     if {"curve", "samples", "curve boundedness", "curve coverage"} & set(s.inputs)
                     and s.name != "correspondence")  # of a given skeletal set: reads no curve
#: of those, the results an update reads (the samples' values it keeps where a sample did not move)
REUSED = ("curve boundedness", "curve centeredness")
#: kept too: the repair reads the defects and missing parts found (skeleton_repair.findings)
READ_BY_REPAIR = ("curve defects", "curve missing parts")


@dataclass
class EvaluationSource:
    """``args``: the keyword arguments :func:`skelcore.evaluate` was called with (progress, cancel and
    on_stages left out); ``ctx``: the stages' context, None once pickled; ``cache``: what updates
    share (built on first use, e.g. the cloud's slab grid). Of the curve's stages the context keeps only the
    results an update or the repair reads (``REUSED``, ``READ_BY_REPAIR``)."""

    args: dict[str, Any]
    ctx: EvalContext | None = None
    cache: dict[str, Any] = field(default_factory=dict)
    #: an update that left out the curve's diagnostics: the curve's other results, which finishing it
    #: (skelcore.edit.incremental.complete_update) assembles again
    rest: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # the other curve stages' results are the Evaluation's own or are never read again
        if self.ctx is not None:
            for name in set(CURVE_STAGES) - set(REUSED) - set(READ_BY_REPAIR):
                self.ctx.results.pop(name, None)

    def __getstate__(self) -> dict[str, Any]:
        return {"args": self.args, "ctx": None, "cache": {}, "rest": {}}
