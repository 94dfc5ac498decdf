"""Which role a loaded file plays (cloud, skeletal point set, curve skeleton): Qt-free rules.

Issue 3's rules for files dropped or named together: a file with edges is a curve skeleton; a point
set with the cloud's point count is a skeletal point set (SPEC 0's pointwise correspondence); the first
point set is the cloud. When that is ambiguous the ``ask`` callback decides (the window shows a dialog).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Callable, Sequence

ROLES = ("cloud", "skeletal", "curve")

Ask = Callable[[str, list[str]], "str | None"]
"""``ask(question, options) -> chosen option`` or None to skip the file."""


@dataclass(frozen=True)
class Assignment:
    role: str  # "cloud", "skeletal" or "curve"
    loaded: Any  # skelcore.io.Loaded


def _count(loaded: Any) -> int:
    return int(len(loaded.points))


def assign_roles(items: Sequence[Any], cloud_count: int | None, ask: Ask) -> list[Assignment]:
    """Roles for ``items`` (``skelcore.io.Loaded``), given the currently loaded cloud's size.

    Ambiguous cases asked about: several same-size point sets and no cloud yet (which one is the
    cloud?), and a point set whose size differs from an already loaded cloud (replace the cloud?).
    """
    out: list[Assignment] = [Assignment("curve", it) for it in items if it.kind == "curve"]
    points = [it for it in items if it.kind != "curve"]
    count = cloud_count
    if count is None and points:
        first = points[0]
        same = [p for p in points if _count(p) == _count(first)]
        if len(same) > 1:
            names = [os.path.basename(p.path) for p in same]
            choice = ask("Several point sets have the same number of points. Which one is the cloud?", names)
            cloud = same[names.index(choice)] if choice in names else first
        else:
            cloud = first
        out.append(Assignment("cloud", cloud))
        points = [p for p in points if p is not cloud]
        count = _count(cloud)
    skeletal_taken = False
    for p in points:
        name = os.path.basename(p.path)
        if _count(p) == count and not skeletal_taken:
            out.append(Assignment("skeletal", p))
            skeletal_taken = True
            continue
        if _count(p) == count:
            question = f"{name} has the cloud's {count} points, like another file dropped with it. Load it as:"
        else:
            question = (
                f"{name} has {_count(p)} points but the cloud has {count}, so it cannot be a skeletal point "
                "set (pointwise correspondence). Load it as:"
            )
        options = ["the cloud (replaces the current one)", "the skeletal point set"]
        choice = ask(question, options)
        if choice == options[0]:
            out.append(Assignment("cloud", p))
            count = _count(p)
        elif choice == options[1]:
            out.append(Assignment("skeletal", p))
            skeletal_taken = True
    order = {"cloud": 0, "skeletal": 1, "curve": 2}
    return sorted(out, key=lambda a: order[a.role])
