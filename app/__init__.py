"""SkelScope's desktop viewer (PySide6 + pyvistaqt) on top of the skelcore engine.

Installed as the package ``skelscope`` (the folder ``app/`` of the repository). Importing it is cheap: Qt, VTK and matplotlib are imported by the modules that need them.
"""

from __future__ import annotations

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    from .__main__ import main as _main

    return _main(argv)
