"""Deprecated alias of :mod:`skelcore.diagnostics.trust_warning` (the warning record moved into the
diagnostics, issue 22); removed in the next release. Import from ``skelcore.diagnostics.trust_warning``."""

import warnings

from .diagnostics.trust_warning import *  # noqa: F401,F403
from .diagnostics.trust_warning import __all__  # noqa: F401

warnings.warn("skelcore.trust_warning is deprecated: import from skelcore.diagnostics.trust_warning",
              DeprecationWarning, stacklevel=2)
