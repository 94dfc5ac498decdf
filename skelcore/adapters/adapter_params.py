"""An adapter's parameters: each a name, a type, a default and a one-line description, checked once
when the compare manifest is read, so a typo costs a one-line error.

``resolve(specs, given)`` returns every parameter with its default filled in (what a job key
hashes, so changing a default reruns the jobs it feeds) or raises ``ValueError`` with one line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

__all__ = ["Param", "resolve", "describe"]


@dataclass(frozen=True)
class Param:
    """``kind``: "int", "float" or "bool"; ``minimum``: the smallest allowed value (ints, floats);
    ``positive``: strictly above ``minimum``; ``optional``: None (absent) is allowed (then derived)."""

    name: str
    kind: str
    default: Any
    doc: str
    minimum: float | None = None
    positive: bool = False
    optional: bool = False

    def check(self, value: Any) -> Any:
        if value is None and self.optional:
            return None
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise ValueError(f"{self.name} must be true or false, got {value!r}")
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                (self.kind == "int" and not float(value).is_integer()) or not math.isfinite(value):
            raise ValueError(f"{self.name} must be {'a whole number' if self.kind == 'int' else 'a finite number'}, "
                             f"got {value!r}")
        value = int(value) if self.kind == "int" else float(value)
        if self.minimum is not None and (value <= self.minimum if self.positive else value < self.minimum):
            raise ValueError(f"{self.name} must be {'>' if self.positive else '>='} {self.minimum:g}, got {value!r}")
        return value


def resolve(specs: tuple[Param, ...], given: dict[str, Any]) -> dict[str, Any]:
    """Every parameter of ``specs``, from ``given`` or its default; ValueError (one line) on an
    unknown name or a bad value."""
    if not isinstance(given, dict):
        raise ValueError("params must be a table ([methods.params])")
    names = {p.name for p in specs}
    extra = sorted(set(given) - names)
    if extra:
        raise ValueError(f"unknown parameter{'s' if len(extra) > 1 else ''} {', '.join(map(repr, extra))} "
                         f"(allowed: {', '.join(sorted(names)) or 'none'})")
    return {p.name: p.check(given[p.name]) if p.name in given else p.default for p in specs}


def describe(specs: tuple[Param, ...]) -> str:
    """One line per parameter: ``name = default  # doc`` (docs/skeletonizers.md lists the same)."""
    return "\n".join(f"{p.name} = {p.default!r}  # {p.doc}" for p in specs)
