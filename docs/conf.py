"""Sphinx configuration of SkelScope's documentation site.

Build: ``make docs`` (warnings are errors). The source is this folder: the user guide (``guide/``),
the API reference (``api/``), the gallery (``../examples/gallery/plot_*.py``, run at build time into
``gallery/``) and the maintainers' notes, the other ``*.md`` here, which are pages as they are (so
their edits show up) and listed under "Developer notes" automatically, a new one included.
"""

from __future__ import annotations

import importlib.util
import os
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))  # skelcore from this tree, also without an install

os.environ.setdefault("MPLBACKEND", "Agg")  # the gallery draws with matplotlib, never a window

import skelcore  # noqa: E402

project = "SkelScope"
author = "the SkelScope developers"
copyright = "2026, the SkelScope developers"
version = release = skelcore.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "gallery/*.ipynb", "gallery/*.py",
                    "gallery/*.zip", "gallery/*.json"]

# MyST: $...$ math, ::: fences, anchors for ## and ### headings (links like notes.md#section)
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
# the notes are maintainers' notebooks, edited by many: a skipped heading level there is style, not a
# broken page (broken links and includes still fail the build)
suppress_warnings = ["myst.header"]

# autodoc with numpydoc-style docstrings (napoleon)
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_preserve_defaults = True  # defaults as written (Params(), not its 80-field repr)
autodoc_default_options = {"members": True}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False
napoleon_use_ivar = True  # "Attributes" as a field list (dataclass fields are not documented twice)

# sphinx-gallery: small generated shapes (skelcore.shapes), matplotlib, a few seconds in all
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples" / "gallery"),
    "gallery_dirs": "gallery",
    "filename_pattern": r"/plot_",
    "image_scrapers": ("matplotlib",),
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "min_reported_time": 10**6,  # no per-example timing lines (they change every build)
    "write_computation_times": False,
    "abort_on_example_error": True,
}

# MathJax from the sphinx-mathjax-offline package (the docs extra), so the formulas render without a
# network; only the parts the pages use are copied (the package holds 24 MB). Without it: the CDN.
try:
    _MATHJAX = Path(importlib.util.find_spec("sphinx-mathjax-offline").origin).parent / "static" / "mathjax"
except (AttributeError, ImportError, ValueError):
    _MATHJAX = None
if _MATHJAX is not None and (_MATHJAX / "tex-chtml.js").is_file():
    mathjax_path = "mathjax/tex-chtml.js"


def _copy_mathjax(app, exc) -> None:
    if exc is None and _MATHJAX is not None and app.builder.format == "html":
        from sphinx.util.fileutil import copy_asset

        out = Path(app.outdir) / "_static" / "mathjax"
        copy_asset(str(_MATHJAX / "tex-chtml.js"), str(out))
        for sub in ("output/chtml/fonts/woff-v2", "ui"):
            copy_asset(str(_MATHJAX / sub), str(out / sub))


html_theme = "furo"
html_title = f"SkelScope {release}"
html_static_path = ["_static"]
html_css_files = ["skelscope.css"]
html_show_sourcelink = False

# The pages of the user guide and the front matter; every other *.md here is a developer note.
_NOT_NOTES = {"index", "changelog", "credits", "notes", "skeletonizers", "compare", "diagnostics", "output_formats"}


def developer_notes() -> list[str]:
    """The maintainers' notes: every top-level ``*.md`` that is not a site page (docnames, sorted)."""
    return sorted(p.stem for p in HERE.glob("*.md") if p.stem not in _NOT_NOTES)


_SECTION = re.compile(r'^% include-section (\S+) "([^"]+)" "([^"]*)"$', re.MULTILINE)
_LINK = re.compile(r"(\]\()(?!https?:|mailto:|#|/)([^)\s]+)(\))")


def section_of(path: Path, start: str, end: str, rel: str) -> str:
    """The text of ``path`` after the line starting ``start`` (the rest of that heading line first)
    up to the line starting ``end`` (or the end); its relative links made relative to the page by
    the prefix ``rel``, so a note's ``[x](compare.md)`` still reaches docs/compare.md."""
    text = path.read_text(encoding="utf-8")
    i = text.find("\n" + start)
    if i < 0:
        raise ValueError(f"{path.name}: no line starts with {start!r}")
    body = text[i + 1 + len(start):]
    if end:
        j = body.find("\n" + end)
        if j < 0:
            raise ValueError(f"{path.name}: no line starts with {end!r} after {start!r}")
        body = body[:j]
    return _LINK.sub(lambda m: m.group(1) + rel + m.group(2) + m.group(3), body)


def _fill_source(app, docname: str, source: list[str]) -> None:
    # the notes' toctree is filled in at read time, so a note added by anyone appears without an edit here
    if docname == "notes":
        source[0] = source[0].replace("@DEVELOPER_NOTES@", "\n".join(developer_notes()))
    # "% include-section FILE START END": a section of a note, read at build time (its later edits show)
    page_dir = (HERE / docname).parent

    def put(m: re.Match) -> str:
        path = (page_dir / m.group(1)).resolve()
        app.env.note_dependency(str(path))
        rel = os.path.relpath(path.parent, page_dir).replace(os.sep, "/") + "/"
        return section_of(path, m.group(2), m.group(3), rel)

    source[0] = _SECTION.sub(put, source[0])


def command_help(command: str) -> str:
    """The ``--help`` text of ``skelcore SUBCOMMAND`` or ``skelscope``, from the parsers themselves
    (so the CLI page never disagrees with the code), 86 columns wide (the page's width)."""
    import argparse

    os.environ["COLUMNS"] = "86"
    words = command.split()
    if words[0] == "skelscope":
        from skelscope.__main__ import build_parser as viewer_parser

        return viewer_parser().format_help()
    from skelcore.cli.main import build_parser

    parser = build_parser()
    if len(words) == 1:
        return parser.format_help()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[words[1]].format_help()


def setup(app) -> dict:
    from docutils import nodes
    from sphinx.util.docutils import SphinxDirective

    class CommandHelp(SphinxDirective):
        """``{command-help} skelcore evaluate``: the command's help text as a literal block."""

        required_arguments = 1
        final_argument_whitespace = True

        def run(self):
            text = command_help(self.arguments[0])
            block = nodes.literal_block(text, text)
            block["language"] = "text"
            return [block]

    app.add_directive("command-help", CommandHelp)
    app.connect("source-read", _fill_source)
    app.connect("build-finished", _copy_mathjax)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
