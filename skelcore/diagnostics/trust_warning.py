"""The warning record every trust check and diagnostic returns (``skelcore.diagnostics.trust``
re-exports it): a stable ``code`` and a one-line ``message`` with its numbers (docs/metrics.md 5.4). 

A leaf module (the standard library only) in a package whose ``__init__`` imports nothing at import
time, so that the foundation's users of the record (the scan checks, the Evaluation) load neither the
diagnostics nor scipy with it, and ``trust`` (whose frame fit asks :mod:`.missing_parts` for
completeness) and the diagnostics import it without a cycle, whichever comes first."""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["TrustWarning", "finite_range"]


_NUMBER = r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"
_MAPPING = re.compile(rf"--skeleton-scale {_NUMBER} --skeleton-offset {_NUMBER} {_NUMBER} {_NUMBER}")
#: where a message's command-line remedy starts (what precedes it is the finding)
_REMEDIES = ("; give --skeletal-index", "; " + "map it with --skeleton-scale", " (or, if it is in other units, ")


def finite_range(values, spec: str = ".2g") -> str | None:
    """"a-b" (or "a" when both agree) of the finite ``values`` in the format ``spec``, None when none
    is finite: a message leaves the clause out rather than print "nan" (docs/diagnostics.md)."""
    finite = [float(v) for v in values if v == v and abs(float(v)) != float("inf")]
    if not finite:
        return None
    lo, hi = format(min(finite), spec), format(max(finite), spec)
    return lo if lo == hi else f"{lo}-{hi}"


@dataclass(frozen=True)
class TrustWarning:
    """``message`` is the text the CLI prints and the JSON stores, with the command line's remedy.
    ``finding`` (what was found) and ``mapping`` (the suggested ``(scale, offset)`` into the cloud's
    frame, or None) are read from it, for a front end that words its own remedy (the viewer names its
    menus and settings); a warning read back from a file gives the same."""

    code: str
    message: str

    def to_dict(self) -> dict[str, str]:
        return {"code": self.code, "message": self.message}

    @property
    def finding(self) -> str:
        cut = [i for i in (self.message.find(r) for r in _REMEDIES) if i >= 0]
        return self.message[: min(cut)] if cut else self.message

    @property
    def mapping(self) -> tuple[float, tuple[float, float, float]] | None:
        m = _MAPPING.search(self.message)
        if m is None:
            return None
        s, x, y, z = (float(v) for v in m.groups())
        return s, (x, y, z)

