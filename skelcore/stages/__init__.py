"""The evaluation as a declared list of stages sharing one context: ``context`` (inputs,
decisions, results), ``catalogue`` (the stages), ``progress`` (one progress bar and cancel),
``assemble`` (the Evaluation and the trust checks), ``orchestrate`` (:func:`evaluate`)."""

from .catalogue import CATALOGUE, Stage
from .context import CORRESPONDENCE_CHOICES, EvalContext
from .orchestrate import evaluate

__all__ = ["evaluate", "CORRESPONDENCE_CHOICES", "CATALOGUE", "Stage", "EvalContext"]
