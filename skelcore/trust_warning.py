"""The warning record every trust check and diagnostic returns (``skelcore.trust`` re-exports it):
a stable ``code`` and a one-line ``message`` with its numbers (docs/metrics.md 5.4, issue 22).

It lives in this leaf module, outside the diagnostics package, so that ``skelcore.trust`` (whose
frame fit asks :func:`skelcore.diagnostics.missing_parts.missing_parts` for completeness) and the
diagnostics import it without a cycle, whichever is imported first."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["TrustWarning"]


@dataclass(frozen=True)
class TrustWarning:
    code: str
    message: str

    def to_dict(self) -> dict[str, str]:
        return {"code": self.code, "message": self.message}
