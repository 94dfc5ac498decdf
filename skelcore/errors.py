"""Exceptions shared by the engine, the CLI and the viewer."""

from __future__ import annotations


class SkelInputError(ValueError):
    """Bad user input: one line naming the file (when there is one) and the problem.

    The CLI prints ``str(err)`` and exits 2; the viewer shows it in a dialog. It must never carry a
    numpy traceback's wording, so loaders catch low-level errors and re-raise this.
    """

    def __init__(self, message: str, path: object | None = None) -> None:
        self.path = None if path is None else str(path)
        text = " ".join(str(message).split())  # always one line
        super().__init__(f"{self.path}: {text}" if self.path else text)


class Cancelled(Exception):
    """Raised from a progress checkpoint when the caller's ``cancel()`` returned True."""
