"""Deprecated alias of :mod:`skelcore.diagnostics.trust` (the trust checks moved into the diagnostics,
issue 22); removed in the next release. Import from ``skelcore.diagnostics.trust``."""

import warnings

from .diagnostics.trust import *  # noqa: F401,F403
from .diagnostics.trust import __all__  # noqa: F401

warnings.warn("skelcore.trust is deprecated: import from skelcore.diagnostics.trust", DeprecationWarning, stacklevel=2)
