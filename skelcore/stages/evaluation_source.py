"""What an Evaluation keeps of how it was made, so that :meth:`skelcore.Evaluation.update` can score an
edited curve the same way: the arguments of :func:`skelcore.evaluate` and the context the stages
shared (the normalized cloud, its search structures, every stage's result). The context is not
pickled (it holds locks and trees): a copied Evaluation updates by evaluating again."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .context import EvalContext

__all__ = ["EvaluationSource"]


@dataclass
class EvaluationSource:
    """``args``: the keyword arguments :func:`skelcore.evaluate` was called with (progress, cancel and
    on_stages left out); ``ctx``: the stages' context, None once pickled; ``cache``: what updates
    share (built on first use, e.g. the cloud's slab grid)."""

    args: dict[str, Any]
    ctx: EvalContext | None = None
    cache: dict[str, Any] = field(default_factory=dict)

    def __getstate__(self) -> dict[str, Any]:
        return {"args": self.args, "ctx": None, "cache": {}}
