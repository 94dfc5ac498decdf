"""The files a command will write, checked before its work (docs/guide/cli.md, "Exit codes"): each in a
format its extension names, none named twice, none an input, each in a folder that can be written;
with ``new``, none that exists yet (``repair``, ``edit``). One-line SkelInputError naming the file."""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Sequence

from ..errors import SkelInputError
from ..io.atomic import check_not_input, check_output_file
from ..io.writers import CURVE_SUFFIXES, POINT_SUFFIXES

__all__ = ["checked_outputs"]

_WRITERS = {"curve": ("curve", CURVE_SUFFIXES), "points": ("point-set", POINT_SUFFIXES)}


def checked_outputs(named: Sequence[tuple[str, str | None, str]], inputs: Iterable[str], *,
                    new: bool = False) -> list[Path]:
    """The paths of ``named`` (``(flag, path or None, kind)``, kind ``curve``, ``points`` or ``any``) that
    are given, each checked; raises on the first that cannot be written as named."""
    inputs = tuple(str(p) for p in inputs if p)
    outs: list[Path] = []
    for flag, name, kind in named:
        if not name:
            continue
        path = Path(name)
        if kind in _WRITERS:
            what, suffixes = _WRITERS[kind]
            if path.suffix.lower() not in suffixes:
                raise SkelInputError(f"no {what} writer for {path.suffix or '(no extension)'} "
                                     f"(writable: {', '.join(suffixes)})", path)
        if any(path.resolve() == o.resolve() for o in outs):
            raise SkelInputError(f"{flag} names a file another output names", path)
        outs.append(path)
    for path in outs:
        check_not_input(path, inputs)
        if new and path.exists() and not path.is_dir():  # a folder: check_output_file says so
            raise SkelInputError("exists: refusing to overwrite it", path)
        check_output_file(path, inputs)
    return outs
