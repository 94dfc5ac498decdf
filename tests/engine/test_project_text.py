"""The project's text speaks of the project alone: no tracker numbers, no citation of a specification
outside the repository (docs/metrics.md is the specification), no path to a folder outside the
checkout and no time of day of the work (the patterns below; written so that this file does not
match them, though it is left out anyway). Read from the tracked files (``git ls-files``; every file
on disk without git)."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
THIS = Path(__file__).resolve()

#: the folders of code whose Python files are checked, and the single Python files outside them
CODE_DIRS = ("skelcore", "app", "tests", "benchmarks", "scripts", "examples")
CODE_FILES = ("setup.py", "docs/conf.py", "pyproject.toml", "MANIFEST.in", "Makefile")
#: the pages: every markdown file of docs/ and of the code folders, and these
PAGE_DIRS = ("docs", *CODE_DIRS)
PAGE_FILES = ("README.md", "CHANGELOG.md")

FORBIDDEN = {
    "an issue number": re.compile(r"\b[Ii]ssues? #?[0-9]+"),
    "the word S-P-E-C": re.compile(r"\bS[P]EC\b"),
    "a path outside the checkout": re.compile(r"\.\./sh[a]red"),
    "a time of day": re.compile(r"\b\d{1,2}:\d{2} ?U[T]C"),
    "a merge conflict marker": re.compile(r"^(<{7}|>{7}) "),
}


def _tracked(dirs: tuple[str, ...], files: tuple[str, ...], suffix: str) -> list[Path]:
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--", *dirs, *files], cwd=ROOT, capture_output=True,
                             check=True, timeout=60).stdout.decode("utf-8").split("\0")
        paths = [ROOT / p for p in out if p]
    except (OSError, subprocess.SubprocessError):
        paths = [p for d in dirs for p in (ROOT / d).rglob("*")] + [ROOT / f for f in files]
    also = (".c", ".toml", ".cfg") if suffix == ".py" else ()
    return sorted(p for p in paths if p.suffix in (suffix, *also) and p.is_file() and p.resolve() != THIS)


def _offences(paths: list[Path]) -> list[str]:
    found = []
    for path in paths:
        for n, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
            for what, pattern in FORBIDDEN.items():
                m = pattern.search(line)
                if m:
                    found.append(f"{path.relative_to(ROOT)}:{n}: {what} ({m.group(0)!r})")
    return found


def test_the_checked_files_are_found():
    paths = _tracked(CODE_DIRS, CODE_FILES, ".py")
    assert ROOT / "skelcore" / "evaluation.py" in paths and ROOT / "setup.py" in paths
    assert THIS not in paths


def test_code_names_no_issue_spec_outside_path_or_time_of_day():
    found = _offences(_tracked(CODE_DIRS, CODE_FILES, ".py"))
    assert found == [], "\n".join(found)


def test_pages_name_no_issue_or_spec():
    paths = _tracked(PAGE_DIRS, PAGE_FILES, ".md")
    assert ROOT / "README.md" in paths
    found = _offences(paths)
    assert found == [], "\n".join(found)
