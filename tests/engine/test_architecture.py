"""The house rules, read from the source with ``ast`` (nothing is imported): no import cycle between
skelcore modules, no GUI or plotting library imported by skelcore at module level, no plyfile (GPL)
imported by skelcore or the viewer, no engine module importing the command line, and package
``__init__`` files that only re-export."""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FORBIDDEN = ("PySide6", "PyQt5", "PyQt6", "shiboken6", "qtpy", "pyvista", "pyvistaqt", "vtk", "vtkmodules", "matplotlib",
             "IPython")
# Reports and figures import their plotting lazily, inside the function that draws.
LAZY_PLOTTING_OK = ("skelcore.experiments", "skelcore.compare", "skelcore.benchmark.validity_report",
                    "skelcore.display")


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


@functools.cache
def _tree(path: Path) -> ast.Module:
    """The parsed file, once per run: every rule walks the same trees (none changes them)."""
    return ast.parse(path.read_text(encoding="utf-8"), filename=str(path))


def _modules(package: str) -> dict[str, Path]:
    return {_module_name(p): p for p in sorted((ROOT / package).rglob("*.py"))}


def _imports(name: str, path: Path, known: set[str]) -> list[tuple[str, int, bool]]:
    """(imported module, line, at module level) for every import statement of the file."""
    tree = _tree(path)
    is_pkg = path.name == "__init__.py"
    base = name.split(".") if is_pkg else name.split(".")[:-1]
    top_level = {id(n) for n in tree.body}
    for n in tree.body:  # imports inside a module-level try/if still run at import time
        if isinstance(n, (ast.Try, ast.If)):
            top_level.update(id(m) for m in ast.walk(n))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                out.append((alias.name, node.lineno, id(node) in top_level))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                stem = base[: len(base) - node.level + 1]
                target = ".".join(stem + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                out.append((sub if sub in known else target, node.lineno, id(node) in top_level))
    return out


# A public method kept on a lower module that hands its work to the module above it, imported inside the
# method (never at module level): the only arrows allowed to point up, and they are no cycle at import time.
LAZY_DELEGATIONS = {
    ("skelcore.evaluation", "skelcore.io.evaluation_files"),  # Evaluation.write_json & co.
    # other libraries' objects: recognised only when one is given instead of an array / path
    ("skelcore.geometry", "skelcore.interop.objects_in"),
    ("skelcore.curve", "skelcore.interop.objects_in"),
    ("skelcore.io.loaders", "skelcore.interop.objects_in"),
    ("skelcore.evaluation", "skelcore.interop.tables"),
    ("skelcore.evaluation", "skelcore.interop.graph_out"),
    ("skelcore.evaluation", "skelcore.interop.open3d_out"),
    # pictures and tables for notebooks: Evaluation.show, show_barcodes, _repr_html_
    ("skelcore.evaluation", "skelcore.display.show"),
    ("skelcore.evaluation", "skelcore.display.summary_table"),
    # the Evaluation of an edited curve: Evaluation.update
    ("skelcore.evaluation", "skelcore.edit.incremental"),
}


def _edges(package: str) -> tuple[dict[str, Path], list[tuple[str, str, int, bool]]]:
    """(importer, imported, line, at module level) for every import between two modules of ``package``,
    the lazy delegations imported inside a function left out."""
    mods = _modules(package)
    known = set(mods)
    edges = []
    for name, path in mods.items():
        for target, line, top in _imports(name, path, known):
            if target in known and target != name and (top or (name, target) not in LAZY_DELEGATIONS):
                edges.append((name, target, line, top))
    return mods, edges


def _graph(package: str) -> tuple[dict[str, Path], dict[str, set[str]]]:
    mods, edges = _edges(package)
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for name, target, _line, _top in edges:
        graph[name].add(target)
    return mods, graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


@pytest.mark.parametrize("package", ["skelcore", "app"])
def test_no_import_cycles(package):
    _mods, graph = _graph(package)
    assert _cycles(graph) == []


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


# The engine's layers, bottom to top, and the lower layers each may import (its own always; an import
# inside a function counts too, the LAZY_DELEGATIONS aside):
#   foundation        errors, version, params, geometry, parallel, curve, correspondence,
#                     colors, shapes, skeleton_mapping, diagnostics.trust_warning (the warning record; the
#                     diagnostics package's __init__ imports nothing at import time) -> nothing else
#   formats           skelcore.io: readers and writers of file formats, atomic writes, JSON numbers
#                                                                                 -> foundation
#   skeletonizer      skelcore.skeleton                                           -> foundation
#   metrics           skelcore.metrics (each result type beside its metric)       -> foundation
#   scan              skelcore.scan (openings, viewpoints, stray points, caps)    -> foundation, metrics
#   diagnostics       skelcore.diagnostics, with the trust checks (diagnostics.trust; TrustWarning itself is
#                     in the foundation)
#                                                                                 -> foundation, formats, metrics
#   record            the Evaluation (skelcore.evaluation), Scores
#                                                             -> foundation, metrics, scan, diagnostics
#   stages            skelcore.stages (the evaluate pipeline) -> foundation, metrics, scan, diagnostics, record
#   objects in        skelcore.interop's recognisers of other libraries' objects -> foundation, formats
#   evaluation files  io.evaluation_files (JSON, CSVs, npz of an Evaluation), io.export (coloured PLY),
#                     io.conversion (skelcore convert), interop's outputs (to_frame, to_networkx, to_open3d)
#                                                             -> foundation, formats, metrics, scan, diagnostics, record
#   adapters          skelcore.adapters: other skeletonizers by name (PyGEL, kimimaro, scikit-image)
#                                                                                 -> foundation, formats
#   display           skelcore.display: pictures and tables of an Evaluation (notebook, window, PNG)
#                                                             -> foundation, formats, metrics, scan, diagnostics, record
#   edits             skelcore.edit: pure edits of a curve skeleton, the edit log
#                                                             -> foundation, formats, metrics, diagnostics
#   edit update       skelcore.edit.incremental (Evaluation.update)
#                                                             -> foundation, formats, metrics, scan, diagnostics,
#                                                                record, stages, edits
#   applications      skelcore.compare, skelcore.experiments, skelcore.benchmark, skelcore.skeleton_repair
#                                                                                 -> every layer above this line
#   entry points      skelcore.cli, skelcore.__main__, the package facade skelcore/__init__ -> every layer
# So: metrics never import the record, the stages or the evaluation files; the record imports no io; the
# format readers and writers import no metric; compare and the CLI sit on top. A pattern "x.*" is the
# package x and everything in it, any other an exact module; a module's layer is its longest pattern.
_BELOW_APPS = ["foundation", "formats", "objects in", "skeletonizer", "adapters", "metrics", "scan", "diagnostics",
               "record", "stages", "evaluation files", "display", "edits", "edit update"]
LAYERS: dict[str, tuple[list[str], list[str]]] = {
    "foundation": ([f"skelcore.{m}" for m in ("errors", "version", "params", "geometry", "parallel", "curve",
                                              "correspondence", "colors", "shapes",
                                              "skeleton_mapping", "diagnostics.trust_warning")],
                   []),
    "formats": (["skelcore.io.*"], ["foundation"]),
    "skeletonizer": (["skelcore.skeleton.*"], ["foundation"]),
    "adapters": (["skelcore.adapters.*"], ["foundation", "formats"]),
    "metrics": (["skelcore.metrics.*"], ["foundation"]),
    "scan": (["skelcore.scan.*"], ["foundation", "metrics"]),
    "diagnostics": (["skelcore.diagnostics.*"], ["foundation", "formats", "metrics"]),
    "record": (["skelcore.evaluation", "skelcore.scores"],
               ["foundation", "metrics", "scan", "diagnostics"]),
    "stages": (["skelcore.stages.*"], ["foundation", "metrics", "scan", "diagnostics", "record"]),
    "objects in": (["skelcore.interop", "skelcore.interop.recognise", "skelcore.interop.objects_in",
                    "skelcore.interop.swc_frames"], ["foundation", "formats"]),
    "evaluation files": (["skelcore.io.evaluation_files", "skelcore.io.export", "skelcore.io.conversion",
                          "skelcore.interop.tables",
                          "skelcore.interop.graph_out", "skelcore.interop.open3d_out"],
                         ["foundation", "formats", "metrics", "scan", "diagnostics", "record"]),
    "display": (["skelcore.display.*"], ["foundation", "formats", "metrics", "scan", "diagnostics", "record"]),
    "edits": (["skelcore.edit.*"], ["foundation", "formats", "metrics", "diagnostics"]),
    "edit update": (["skelcore.edit.incremental"],
                    ["foundation", "formats", "metrics", "scan", "diagnostics", "record", "stages", "edits"]),
    "applications": (["skelcore.compare.*", "skelcore.experiments.*", "skelcore.benchmark.*", "skelcore.skeleton_repair.*"],
                     _BELOW_APPS),
    "entry points": (["skelcore", "skelcore.__main__", "skelcore.cli.*"], [*_BELOW_APPS, "applications"]),
}


def _layer_of(module: str) -> str | None:
    best, best_len = None, -1
    for layer, (patterns, _may) in LAYERS.items():
        for pattern in patterns:
            stem = pattern[:-2] if pattern.endswith(".*") else pattern
            hit = module == stem or (pattern.endswith(".*") and module.startswith(stem + "."))
            if hit and len(stem) > best_len:
                best, best_len = layer, len(stem)
    return best


def _upward_arrows(edges: list[tuple[str, str, int, bool]]) -> list[str]:
    bad = []
    for name, target, line, _top in edges:
        src, dst = _layer_of(name), _layer_of(target)
        if src != dst and dst not in LAYERS[src][1]:
            bad.append(f"{name}:{line} ({src}) imports {target} ({dst})")
    return bad


def test_every_engine_module_has_a_layer():
    mods, _edges_ = _edges("skelcore")
    assert [m for m in mods if _layer_of(m) is None] == []


def test_no_arrow_runs_up_the_layers():
    _mods, edges = _edges("skelcore")
    assert _upward_arrows(edges) == []


def test_the_layer_check_finds_an_upward_arrow():
    """An upward import would be caught: a metric importing the record, the record importing io,
    a format reader importing a metric, an engine module importing compare."""
    edges = [("skelcore.metrics.topology", "skelcore.evaluation", 26, True),
             ("skelcore.evaluation", "skelcore.io.atomic", 19, True),
             ("skelcore.io.loaders", "skelcore.metrics.coverage", 1, False),
             ("skelcore.stages.orchestrate", "skelcore.compare.jobs", 1, False),
             ("skelcore.metrics.coverage", "skelcore.geometry", 1, True),
             ("skelcore.compare.jobs", "skelcore.io.evaluation_files", 1, False)]
    assert [b.split(":")[0] for b in _upward_arrows(edges)] == [
        "skelcore.metrics.topology", "skelcore.evaluation", "skelcore.io.loaders", "skelcore.stages.orchestrate"]
    assert _layer_of("skelcore.evaluation") == "record" and _layer_of("skelcore.stages.catalogue") == "stages"
    assert _layer_of("skelcore.io.evaluation_files") == "evaluation files" and _layer_of("skelcore.io.ply") == "formats"


def test_lazy_delegations_are_imported_inside_functions_only():
    """An arrow of LAZY_DELEGATIONS at module level is kept in the graph (and fails the cycle and layer
    tests); each listed delegation exists."""
    mods = _modules("skelcore")
    found = set()
    for name, target in LAZY_DELEGATIONS:
        for imported, line, top in _imports(name, mods[name], set(mods)):
            if imported == target:
                assert not top, f"{name}:{line} imports {target} at module level"
                found.add((name, target))
    assert found == LAZY_DELEGATIONS


def test_skelcore_never_imports_gui_or_plotting_at_module_level():
    mods = _modules("skelcore")
    bad = []
    for name, path in mods.items():
        for target, line, top in _imports(name, path, set(mods)):
            root = target.split(".")[0]
            if root in FORBIDDEN and (top or not name.startswith(LAZY_PLOTTING_OK)):
                bad.append(f"{path.relative_to(ROOT)}:{line} imports {target}")
    assert bad == []


def test_no_module_of_the_package_imports_plyfile():
    """SkelScope is MIT and plyfile GPL-3.0-or-later: PLY is read and written by skelcore.io.ply, and
    plyfile stays the tests' reference (the ``test`` extra), imported by no engine or viewer module,
    at module level or inside a function."""
    bad = []
    for package in ("skelcore", "app"):
        mods = _modules(package)
        for name, path in mods.items():
            bad += [f"{path.relative_to(ROOT)}:{line} imports {target}"
                    for target, line, _ in _imports(name, path, set(mods)) if target.split(".")[0] == "plyfile"]
    assert bad == []


def test_the_plyfile_rule_finds_an_import(tmp_path):
    module = tmp_path / "reader.py"
    module.write_text("def read(path):\n    from plyfile import PlyData\n    return PlyData.read(path)\n")
    assert [t for t, _, top in _imports("skelcore.io.reader", module, set()) if not top] == ["plyfile"]


def test_no_engine_module_imports_the_cli():
    mods, graph = _graph("skelcore")
    bad = [f"{m} -> {t}" for m, targets in graph.items() if not m.startswith(("skelcore.cli", "skelcore.__main__"))
           for t in targets if t.startswith("skelcore.cli")]
    assert bad == []


@pytest.mark.parametrize("package", ["skelcore", "app"])
def test_package_inits_only_re_export(package):
    """An ``__init__.py`` holds a docstring, imports, ``__all__`` and at most a tiny helper."""
    heavy = []
    for path in sorted((ROOT / package).rglob("__init__.py")):
        tree = _tree(path)
        defs = [n for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef, ast.AsyncFunctionDef))]
        code_lines = sum((n.end_lineno or n.lineno) - n.lineno + 1 for n in defs)
        if code_lines > 15:
            heavy.append(f"{path.relative_to(ROOT)}: {code_lines} lines of definitions")
    assert heavy == []


def test_module_docstrings_are_short():
    """What and why in about 15 lines; measurement history belongs in docs/."""
    long = []
    for name, path in _modules("skelcore").items():
        doc = ast.get_docstring(_tree(path))
        if doc is None and path.stat().st_size > 200:
            long.append(f"{name}: no module docstring")
        elif doc is not None and len(doc.splitlines()) > 18:
            long.append(f"{name}: {len(doc.splitlines())} lines")
    assert long == []


def test_no_two_engine_modules_share_a_name():
    """A module's file name says what it holds, once: the CLI's subcommand modules aside (``cli/evaluate``
    is the ``evaluate`` subcommand), no two engine modules are called alike."""
    seen: dict[str, list[str]] = {}
    for name, path in _modules("skelcore").items():
        if path.name == "__init__.py" or name.startswith("skelcore.cli."):
            continue
        seen.setdefault(path.stem, []).append(name)
    assert {stem: names for stem, names in seen.items() if len(names) > 1} == {}


def test_engine_top_level_is_small():
    """At most 12 modules at skelcore's top level (``__init__`` and ``__main__`` aside): the rest live in
    the subsystem folders that name them (docs/layout.md)."""
    top = [p.stem for p in (ROOT / "skelcore").glob("*.py") if p.stem not in ("__init__", "__main__")]
    assert len(top) <= 12, sorted(top)


# Each module named on the command line imported first, in a child forked from one interpreter that has
# loaded the third-party libraries but no skelcore module: the same import order as a fresh interpreter
# per module (a cycle fails the same way), without paying numpy's and scipy's import once per module.
_IMPORTS_FIRST = """
import importlib, os, sys, traceback
names = sys.argv[1:]
for name in names:
    try:
        importlib.import_module(name)
    except BaseException:
        pass  # reported by its own child below
for key in [k for k in sys.modules if k == "skelcore" or k.startswith("skelcore.")]:
    del sys.modules[key]
for name in names:
    sys.stdout.flush()
    pid = os.fork()
    if pid == 0:
        try:
            importlib.import_module(name)
        except BaseException:
            traceback.print_exc()
            os._exit(1)
        print(name, "ok", flush=True)
        os._exit(0)
    _, status = os.waitpid(pid, 0)
    if status:
        print(name, "failed", flush=True)
"""


def test_the_warning_record_loads_no_diagnostic_and_every_diagnostics_module_imports_first():
    """skelcore.diagnostics.trust_warning is the foundation's: importing it (a fresh interpreter) loads
    none of the diagnostics nor scipy; each diagnostics module, and each user of the record, imports
    first without a cycle; the package's names resolve (``missing_parts`` the function)."""
    import os
    import subprocess
    import sys

    code = ("import sys\nimport skelcore.diagnostics.trust_warning as t\n"
            "print(sorted(m for m in sys.modules if m.startswith(('skelcore.diagnostics.', 'scipy'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "['skelcore.diagnostics.trust_warning']"
    mods = [m for m in _modules("skelcore") if m.startswith("skelcore.diagnostics.")]
    mods += ["skelcore.scan.scan_report", "skelcore.evaluation", "skelcore.stages.scan_checks"]
    out = subprocess.run([sys.executable, "-c", _IMPORTS_FIRST, *mods], capture_output=True, text=True,
                         env={**os.environ, "OPENBLAS_NUM_THREADS": "1"}, check=True).stdout
    assert out.splitlines() == [f"{m} ok" for m in mods]
    code = ("import skelcore.stages, skelcore.diagnostics.missing_parts\n"
            "from skelcore.diagnostics import missing_parts, find_curve_defects, JUNCTION\n"
            "import skelcore.diagnostics as d\n"
            "print(callable(missing_parts), missing_parts is d.missing_parts, callable(find_curve_defects), JUNCTION)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["True", "True", "True", "-1"]


def test_the_viewer_is_imported_by_its_installed_name():
    """The folder app/ installs as ``skelscope``: a test, script or benchmark importing ``app`` would load a
    second copy of the viewer's modules beside the installed ones (a monkeypatch would miss the window's)."""
    import re

    pattern = re.compile(r"^\s*(import app\b|from app\b)", re.M)
    hits = [str(p.relative_to(ROOT)) for folder in ("app", "tests", "scripts", "benchmarks", "docs", "examples")
            for p in (ROOT / folder).rglob("*.py") if pattern.search(p.read_text(encoding="utf-8"))]
    assert hits == []


def _third_party_imports(folder: str) -> dict[str, bool]:
    """The third-party top-level modules imported under ``folder``: name -> imported at module level
    somewhere (False: only inside functions)."""
    import sys

    found: dict[str, bool] = {}
    own = {"skelcore", "skelscope", "app"}
    for path in (ROOT / folder).rglob("*.py"):
        tree = _tree(path)
        top_level = {id(n) for n in tree.body}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                if top in own or top in sys.stdlib_module_names or top == "__future__":
                    continue
                found[top] = found.get(top, False) or id(node) in top_level
    return found


def _requirement_names(requirements: list[str]) -> set[str]:
    import re

    return {re.split(r"[\s<>=!;\[~]", r, maxsplit=1)[0].lower().replace("_", "-") for r in requirements}


def test_dependencies_are_what_the_package_imports():
    """A required dependency is one the package imports, every library the engine imports at module
    level is required, and every library imported only when used belongs to an extra."""
    import importlib.metadata as md

    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    required = _requirement_names(project["dependencies"])
    extras = {name: _requirement_names(reqs) for name, reqs in project["optional-dependencies"].items()}
    dists = md.packages_distributions()

    def dist_of(module: str) -> set[str]:
        return {d.lower().replace("_", "-") for d in dists.get(module, [module])}

    engine, viewer = _third_party_imports("skelcore"), _third_party_imports("app")
    imported = set().union(*(dist_of(m) for m in {**engine, **viewer}))
    assert required - imported - {"tomli"} == set()  # tomli: tomllib's stand-in before Python 3.11
    at_module_level = {m for m, top in engine.items() if top}
    assert [m for m in at_module_level if not dist_of(m) & required] == []
    optional = set().union(*extras.values()) | required
    assert [m for m in {**engine, **viewer} if not dist_of(m) & optional] == []
    assert [m for m, top in viewer.items() if top and not dist_of(m) & (extras["app"] | required)] == []
