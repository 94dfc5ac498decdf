"""Deprecated alias of :mod:`skelcore.evaluation` (the Evaluation record moved there); removed in the
next release. Import ``skelcore.Evaluation`` or from ``skelcore.evaluation``."""

import warnings

from .evaluation import *  # noqa: F401,F403
from .evaluation import __all__  # noqa: F401

warnings.warn("skelcore.results is deprecated: import from skelcore.evaluation", DeprecationWarning, stacklevel=2)
