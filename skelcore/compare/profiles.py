"""Application profiles (paper section V-B): which scores matter for grasping, navigation,
agricultural manipulation and surface reconstruction, as thresholds with weights.

The thresholds are our reading of the paper's discussion, not its numbers (only d* = 0.02 is the
paper's). They live in ``skelcore/compare/data/profiles.toml`` (copied to
``resources/profiles.toml`` for users to edit; ``--profiles F`` loads another file). A verdict is
computed from a job's stored scores, so editing a profile never recomputes a job.
"""

from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass
from importlib import resources
from typing import Any

from ..errors import SkelInputError
from ..scores import column_keys
from ..diagnostics.trust import DEFECT_CODES

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["Criterion", "Profile", "Verdict", "load_profiles", "default_profiles_text"]

_METRICS = set(column_keys(compared=True))


@dataclass(frozen=True)
class Criterion:
    metrics: tuple[str, ...]  # the first one a job has is used
    bound: float
    upper: bool  # True: value <= bound passes ("max"); False: value >= bound ("min")
    weight: float = 1.0

    def check(self, scores: dict[str, float]) -> tuple[bool, str]:
        for m in self.metrics:
            v = scores.get(m, math.nan)
            if v is not None and not math.isnan(float(v)):
                v = float(v)
                ok = v <= self.bound if self.upper else v >= self.bound
                op = ("<=" if ok else ">") if self.upper else (">=" if ok else "<")
                return ok, f"{m} {v:.3g} {op} {self.bound:g}"
        return False, f"{'/'.join(self.metrics)} missing"


@dataclass(frozen=True)
class Verdict:
    status: str  # "pass", "fail" or "n/a"
    score: float  # weighted fraction of criteria met (NaN when n/a)
    reason: str


@dataclass(frozen=True)
class Profile:
    name: str
    title: str
    why: str
    criteria: tuple[Criterion, ...]
    when: str | None = None  # "noise", "sparse" or None (every condition)
    fail_on: tuple[str, ...] = ()  # defect codes that fail the profile whatever the scores

    def applies(self, condition: dict[str, Any]) -> bool:
        if self.when == "noise":
            return bool(condition.get("noise"))
        if self.when == "sparse":
            return any(condition.get(k) is not None for k in ("sparse", "grid", "fps"))
        return True

    def verdict(self, scores: dict[str, float], condition: dict[str, Any], ok: bool = True,
                defects: tuple[str, ...] | list[str] = ()) -> Verdict:
        """Pass when every criterion is met and the job has none of the defects in ``fail_on``."""
        if not self.applies(condition):
            return Verdict("n/a", math.nan, f"only for {self.when} conditions")
        if not ok:
            return Verdict("fail", 0.0, "job failed")
        fatal = [d for d in defects if d in self.fail_on]
        if fatal:
            return Verdict("fail", 0.0, "defect: " + ", ".join(fatal))
        results = [c.check(scores) for c in self.criteria]
        total = sum(c.weight for c in self.criteria) or 1.0
        score = sum(c.weight for c, (met, _) in zip(self.criteria, results) if met) / total
        failed = [why for met, why in results if not met]
        if failed:
            return Verdict("fail", score, "; ".join(failed))
        return Verdict("pass", score, "; ".join(why for _, why in results))


def default_profiles_text() -> str:
    return resources.files("skelcore.compare").joinpath("data/profiles.toml").read_text(encoding="utf-8")


def load_profiles(path: str | os.PathLike | None = None) -> tuple[Profile, ...]:
    """The shipped profiles, or those of ``path``; one-line SkelInputError on a bad file."""
    label = "skelcore/compare/data/profiles.toml" if path is None else os.fspath(path)
    try:
        text = default_profiles_text() if path is None else open(path, encoding="utf-8").read()
        doc = tomllib.loads(text)
    except FileNotFoundError:
        raise SkelInputError("profiles file not found", label) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SkelInputError(f"cannot read the profiles: {exc}", label) from None
    except tomllib.TOMLDecodeError as exc:
        raise SkelInputError(f"not valid TOML: {exc}", label) from None
    return _parse(doc, label)


def _parse(doc: dict[str, Any], label: str) -> tuple[Profile, ...]:
    def fail(msg: str) -> None:
        raise SkelInputError(msg, label)

    if set(doc) - {"profiles"}:
        fail(f"unknown top-level keys {sorted(set(doc) - {'profiles'})} (expected [[profiles]])")
    entries = doc.get("profiles")
    if not isinstance(entries, list) or not entries:
        fail("no [[profiles]] entries")
    out: list[Profile] = []
    for i, e in enumerate(entries):
        name = e.get("name")
        if not isinstance(name, str) or not name.isidentifier():
            fail(f"profiles[{i}]: name must be a word (letters, digits, _), got {name!r}")
        where = f"profile {name!r}"
        extra = set(e) - {"name", "title", "why", "when", "require", "fail_on"}
        if extra:
            fail(f"{where}: unknown keys {sorted(extra)}")
        fail_on = e.get("fail_on", [])
        if not isinstance(fail_on, list) or any(c not in DEFECT_CODES for c in fail_on):
            fail(f"{where}: fail_on must list defect codes among {', '.join(sorted(DEFECT_CODES))}; got {fail_on!r}")
        if e.get("when") not in (None, "noise", "sparse"):
            fail(f"{where}: when must be 'noise' or 'sparse'")
        reqs = e.get("require")
        if not isinstance(reqs, list) or not reqs:
            fail(f"{where}: needs [[profiles.require]] criteria")
        crits = []
        for r in reqs:
            extra = set(r) - {"metric", "min", "max", "weight"}
            if extra:
                fail(f"{where}: unknown criterion keys {sorted(extra)}")
            metrics = r.get("metric")
            metrics = (metrics,) if isinstance(metrics, str) else tuple(metrics or ())
            bad = [m for m in metrics if m not in _METRICS]
            if not metrics or bad:
                fail(f"{where}: metric must be one or more of {', '.join(sorted(_METRICS))}; got {bad or metrics}")
            if ("min" in r) == ("max" in r):
                fail(f"{where}: each criterion needs exactly one of min and max")
            bound = r.get("max", r.get("min"))
            weight = r.get("weight", 1.0)
            if not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in (bound, weight)) or weight < 0:
                fail(f"{where}: min/max and weight must be numbers (weight >= 0)")
            crits.append(Criterion(metrics, float(bound), "max" in r, float(weight)))
        if any(p.name == name for p in out):
            fail(f"{where}: defined twice")
        out.append(Profile(name, str(e.get("title", name)), str(e.get("why", "")), tuple(crits), e.get("when"),
                           tuple(fail_on)))
    return tuple(out)
