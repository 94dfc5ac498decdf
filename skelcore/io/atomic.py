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


def release(path: str | os.PathLike) -> None:
    """Forget a file :func:`protect` remembered (a file ``convert`` wrote and read back to check it)."""
    with contextlib.suppress(OSError):
        _protected.discard(Path(path).resolve())


def check_not_input(path: str | os.PathLike, inputs: Iterable[str | os.PathLike] = ()) -> None:
    target = Path(path).resolve()
    others = {Path(p).resolve() for p in inputs if p is not None}
    if target in _protected or target in others:
        raise SkelInputError("refusing to overwrite an input file", path)


def check_output_file(path: str | os.PathLike, inputs: Iterable[str | os.PathLike] = ()) -> None:
    """Fail early, in one line, when ``path`` cannot be written (before any long computation)."""
    p = Path(path)
    check_not_input(p, inputs)
    folder = p.parent if str(p.parent) else Path(".")
    if p.is_dir():
        raise SkelInputError("is a folder, not a file", p)
    _check_folder(folder, p)


def check_output_dir(path: str | os.PathLike) -> None:
    """Fail early when folder ``path`` is a file, or cannot be created or written in."""
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise SkelInputError("output folder is a file", p)
    ancestor = p
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    _check_folder(ancestor, p)


def _check_folder(folder: Path, target: Path) -> None:
    for up in (folder, *folder.parents):
        if up.exists():
            if not up.is_dir():
                raise SkelInputError(f"cannot write: {up} is a file, not a folder", target)
            break
    if not folder.exists():
        raise SkelInputError("output folder does not exist", folder)
    if not folder.is_dir():
        raise SkelInputError(f"cannot write: {folder} is a file, not a folder", target)
    if not os.access(folder, os.W_OK | os.X_OK):
        raise SkelInputError(f"cannot write: permission denied in {folder}", target)


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike, mode: str = "w", inputs: Iterable[str | os.PathLike] = ()) -> Iterator[IO]:
    """Write to a temporary file in the target's folder, then rename over the target.

    A crash or an exception leaves the old file (if any) untouched and no partial file behind.
    """
    path = Path(path)
    check_not_input(path, inputs)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        _check_folder(folder, path)
    if path.is_dir():
        raise SkelInputError("is a folder, not a file", path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise SkelInputError(f"cannot write here ({exc.strerror or exc})", path) from None
    try:
        kwargs = {} if "b" in mode else {"encoding": "utf-8", "newline": ""}
        with os.fdopen(fd, mode, **kwargs) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except OSError as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise SkelInputError(f"cannot write ({exc.strerror or exc})", path) from None
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
