"""Atomic, never-overwrite-an-input file writing shared by every writer."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import IO, Iterable, Iterator

from ..errors import SkelInputError

_protected: set[Path] = set()


def protect(path: str | os.PathLike) -> None:
    """Remember a file the user loaded: writers refuse to replace it."""
    with contextlib.suppress(OSError):
        _protected.add(Path(path).resolve())


def check_not_input(path: str | os.PathLike, inputs: Iterable[str | os.PathLike] = ()) -> None:
    target = Path(path).resolve()
    others = {Path(p).resolve() for p in inputs if p is not None}
    if target in _protected or target in others:
        raise SkelInputError("refusing to overwrite an input file", path)


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike, mode: str = "w", inputs: Iterable[str | os.PathLike] = ()) -> Iterator[IO]:
    """Write to a temporary file in the target's folder, then rename over the target.

    A crash or an exception leaves the old file (if any) untouched and no partial file behind.
    """
    path = Path(path)
    check_not_input(path, inputs)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise SkelInputError("output folder does not exist", folder)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    try:
        kwargs = {} if "b" in mode else {"encoding": "utf-8", "newline": ""}
        with os.fdopen(fd, mode, **kwargs) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
