"""Headless Chromium for the tests that look at generated HTML (compare's report, the documentation
site): the Debian package run as root without a sandbox, a fresh profile per call."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run"]


def chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    assert exe, "headless Chromium is needed (Debian package 'chromium', installed by `make setup`)"
    return exe


def browser(tmp: Path, *args: str) -> subprocess.CompletedProcess:
    """Chromium with ``args`` (``--dump-dom``, ``--screenshot=...``, a URL) and a new profile in ``tmp``."""
    profile = tmp / f"chromium-profile-{len(list(tmp.glob('chromium-profile-*')))}"
    return subprocess.run([chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args],
                          capture_output=True, text=True, timeout=120)
