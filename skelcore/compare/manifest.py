"""The ``compare`` manifest (TOML): which shapes, methods, conditions and seeds to run, checked whole
before any job starts so that a typo costs a one-line error, not an hour of jobs.

Paths are relative to the manifest's folder. Every table accepts only the keys listed in
``_KEYS``; an unknown key, a glob that matches nothing, a command that is not on PATH, a missing
precomputed skeleton or a bad value is a :class:`~skelcore.errors.SkelInputError` naming the
manifest and the offending entry.
"""

from __future__ import annotations

import glob
import math
import os
import re
import shlex
import shutil
import sys
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from ..errors import SkelInputError
from ..params import Params

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["ShapeSpec", "MethodSpec", "ConditionSpec", "Manifest", "load_manifest", "parse_manifest",
           "check_command_template", "command_argv", "python_executable", "expand_template",
           "skeletonize_accepts_method"]

_KEYS = {
    "top": {"evaluation", "shapes", "methods", "conditions", "seeds"},
    "shapes": {"path", "name", "suffix", "viewpoint", "reference", "reference_facts", "tree"},
    "builtin": {"name", "kind", "method", "params", "repair"},
    "command": {"name", "kind", "command", "timeout", "correspondence", "repair"},
    "files": {"name", "kind", "curve", "skeletal", "skeletal_index", "correspondence", "scale", "offset", "repair"},
    "adapter": {"name", "kind", "params", "timeout", "correspondence", "repair"},  # kind = a skelcore.adapters KIND
    "conditions": {"name", "noise", "model", "sparse", "grid", "fps", "base_grid", "seeds"},
}
_PLACEHOLDERS = ("{python}", "{in}", "{out_skeletal}", "{out_curve}")
_PLACEHOLDER_RE = re.compile("|".join(re.escape(p) for p in _PLACEHOLDERS))


@dataclass(frozen=True)
class ShapeSpec:
    """One input cloud, named by its file stem less the entry's ``suffix`` ("_cloud"), or by the
    entry's ``name`` for a single file; ``viewpoints``: the sensor positions of a one-sided scan
    (``viewpoint = [x, y, z]`` or a list of them; docs/metrics.md 6.3); ``reference``: its
    ground-truth curve skeleton (``reference = "truth/{stem}.ply"``, the shape's name for ``{stem}``),
    ``tree``: the shape is declared a tree (its reference may have no cycle); ``reference_facts``: how
    far each reference vertex lies outside the surface the cloud was drawn from (a real suite's
    ``truth/{neuron}_gt_facts.csv``), for the held ground-truth scores (docs/metrics.md 5.3.1)."""

    name: str
    path: str
    viewpoints: tuple[tuple[float, float, float], ...] = ()
    reference: str | None = None
    tree: bool = False
    reference_facts: str | None = None


@dataclass(frozen=True)
class MethodSpec:
    """A skeletonizer: ``builtin`` (SkelScope's, optional ``method`` and ``params``), ``command``
    (an external program, placeholders ``{python} {in} {out_skeletal} {out_curve}``, ``timeout``
    seconds) or ``files`` (precomputed skeletons; templates with ``{stem}``, optionally
    ``{condition}``, ``{seed}``; ``scale`` and ``offset`` map them into the cloud's frame as
    ``evaluate --skeleton-scale S --skeleton-offset X Y Z`` does), or another tool by name
    (``pygel``, ``kimimaro``, ``skimage``: :mod:`skelcore.adapters`, ``params`` resolved with their
    defaults, ``tool`` its version string, both in the job key)."""

    name: str
    kind: str
    method: str | None = None
    params: dict[str, Any] = field(default_factory=dict)
    command: str | None = None
    timeout: float | None = None
    cwd: str | None = None  # a command runs here: the manifest's folder
    curve: str | None = None
    skeletal: str | None = None
    skeletal_index: str | None = None
    correspondence: str | None = None  # evaluate(correspondence=...): "reverse" for unmatched point sets
    scale: float | None = None  # files: skeleton coordinates * scale + offset (None: not mapped)
    offset: tuple[float, float, float] | None = None
    tool: str | None = None  # an adapter's tool and version, "kimimaro 5.8.5; adapter 1"
    repair: bool = False  # the method's curve repaired (skelcore.repair) before it is scored

    def to_dict(self) -> dict[str, Any]:
        """The definition a job key hashes; ``scale`` / ``offset`` / ``tool`` only when set and
        ``repair`` only when true, so the keys of runs made before they existed still hold."""
        return {f.name: getattr(self, f.name) for f in fields(self)
                if not (f.name in ("scale", "offset", "tool") and getattr(self, f.name) is None)
                and not (f.name == "repair" and not self.repair)}

    def file_templates(self) -> dict[str, str]:
        return {k: v for k, v in (("curve", self.curve), ("skeletal", self.skeletal),
                                  ("skeletal_index", self.skeletal_index)) if v}

    def mapping(self) -> dict[str, Any] | None:
        """A ``files`` method's ``{"scale", "offset"}`` when it maps its skeletons, else None."""
        from ..skeleton_mapping import is_identity

        scale, offset = self.scale or 1.0, self.offset or (0.0, 0.0, 0.0)
        return None if is_identity(scale, offset) else {"scale": scale, "offset": list(offset)}

    def per_condition(self) -> bool:
        """A ``files`` method whose templates name ``{condition}`` has skeletons of degraded clouds."""
        return any("{condition}" in t for t in self.file_templates().values())


@dataclass(frozen=True)
class ConditionSpec:
    """A degradation of the input, applied in this order: ``base_grid`` (voxel-grid average),
    then one of ``grid`` / ``sparse`` (random) / ``fps`` (farthest point), then ``noise``."""

    name: str
    noise: float | None = None
    model: str = "reference"
    sparse: int | None = None
    grid: float | None = None
    fps: int | None = None
    base_grid: float | None = None
    seeds: tuple[int, ...] | None = None  # this condition's own seeds (TOML: ``seeds`` after its table)

    def to_dict(self) -> dict[str, Any]:
        """What the result depends on (the seeds are a job's, not the condition's)."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name != "seeds"}

    @property
    def degrades(self) -> bool:
        return any(v is not None for v in (self.noise, self.sparse, self.grid, self.fps, self.base_grid))

    def label(self, n_points: int) -> str:
        """As in the paper's table: "4096 pts", "5% noise"."""
        if self.noise:
            return f"{self.noise * 100:g}% noise"
        return f"{n_points} pts"


@dataclass(frozen=True)
class Manifest:
    """A checked compare manifest (TOML): its shapes, methods, conditions, seeds and the evaluation
    :class:`~skelcore.Params`; paths are resolved against the manifest's folder (docs/compare.md)."""

    path: str
    params: Params
    shapes: tuple[ShapeSpec, ...]
    methods: tuple[MethodSpec, ...]
    conditions: tuple[ConditionSpec, ...]
    seeds: tuple[int, ...]


def load_manifest(path: str | os.PathLike) -> Manifest:
    """Read and validate a manifest file (one-line :class:`SkelInputError` on any problem)."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            doc = tomllib.load(fh)
    except FileNotFoundError:
        raise SkelInputError("manifest not found", path) from None
    except OSError as exc:
        raise SkelInputError(f"cannot read manifest: {exc.strerror or exc}", path) from None
    except tomllib.TOMLDecodeError as exc:
        raise SkelInputError(f"not valid TOML: {exc}", path) from None
    return parse_manifest(doc, path)


def parse_manifest(doc: dict[str, Any], path: str) -> Manifest:
    """Validate a parsed manifest; ``path`` names it in errors and anchors relative paths."""
    base = Path(path).resolve().parent

    def fail(message: str) -> None:
        raise SkelInputError(message, path)

    def unknown(where: str, table: dict, allowed: set[str]) -> None:
        extra = sorted(set(table) - allowed)
        if extra:
            fail(f"{where}: unknown key{'s' if len(extra) > 1 else ''} {', '.join(map(repr, extra))} "
                 f"(allowed: {', '.join(sorted(allowed))})")

    unknown("top level", doc, _KEYS["top"])
    params = _evaluation(doc.get("evaluation", {}), fail)
    shapes = _shapes(doc.get("shapes"), base, fail, unknown, params)
    methods = _methods(doc.get("methods"), base, shapes, fail, unknown)
    conditions = _conditions(doc.get("conditions", [{"name": "normal"}]), fail, unknown)
    seeds = _seeds(doc.get("seeds", [0]), "seeds", fail)
    for m in methods:
        if m.kind == "files" and m.per_condition():
            for c in conditions:
                for s in shapes:
                    _files_exist(m, s, c.name, c.seeds or seeds, base, fail)
    return Manifest(path, params, shapes, methods, conditions, tuple(seeds))


def _evaluation(table: Any, fail) -> Params:
    if not isinstance(table, dict):
        fail("[evaluation] must be a table")
    known = {f.name for f in fields(Params)}
    extra = sorted(set(table) - known)
    if extra:
        fail(f"[evaluation]: unknown key{'s' if len(extra) > 1 else ''} {', '.join(map(repr, extra))} "
             "(any skelcore.Params field)")
    try:
        return Params().replace(**table)
    except (TypeError, ValueError) as exc:
        fail(f"[evaluation]: {exc}")
    raise AssertionError  # pragma: no cover


def _list_of_tables(value: Any, name: str, fail) -> list[dict]:
    if value is None:
        fail(f"no [[{name}]] entries")
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value) or not value:
        fail(f"{name}: expected one or more [[{name}]] tables")
    return value


def _name(entry: dict, where: str, fail) -> str:
    name = entry.get("name")
    if not isinstance(name, str) or not name.strip():
        fail(f"{where}: needs a name")
    if any(ch in name for ch in "/\\,\n"):
        fail(f"{where}: name {name!r} may not contain '/', '\\\\' or ','")
    return name


def _shapes(value: Any, base: Path, fail, unknown, params: Params = Params()) -> tuple[ShapeSpec, ...]:
    out: dict[str, ShapeSpec] = {}
    for i, entry in enumerate(_list_of_tables(value, "shapes", fail)):
        where = f"shapes[{i}]"
        unknown(where, entry, _KEYS["shapes"])
        pattern = entry.get("path")
        if not isinstance(pattern, str) or not pattern:
            fail(f"{where}: needs a path (a file or a glob)")
        full = pattern if os.path.isabs(pattern) else str(base / pattern)
        if glob.has_magic(pattern):
            matches = sorted(p for p in glob.glob(full) if os.path.isfile(p))
            if not matches:
                fail(f"{where}: path {pattern!r} matches no file")
            if "name" in entry:
                fail(f"{where}: name is only allowed for a single file, not a glob")
        else:
            if not os.path.isfile(full):
                fail(f"{where}: shape file {pattern!r} not found")
            matches = [full]
        suffix = entry.get("suffix", "")
        if not isinstance(suffix, str):
            fail(f"{where}: suffix must be a string (cut from the end of each file stem)")
        viewpoints = _viewpoints(entry.get("viewpoint"), where, fail)
        reference, tree = entry.get("reference"), entry.get("tree", False)
        if reference is not None and (not isinstance(reference, str) or not reference):
            fail(f"{where}: reference must be a file path or a template with {{stem}}, e.g. \"truth/{{stem}}.ply\"")
        if not isinstance(tree, bool):
            fail(f"{where}: tree must be true or false")
        facts = entry.get("reference_facts")
        if facts is not None and (not isinstance(facts, str) or not facts):
            fail(f"{where}: reference_facts must be a file path or a template with {{stem}}, "
                 "e.g. \"truth/{{stem}}_gt_facts.csv\"")
        if facts is not None and reference is None:
            fail(f"{where}: reference_facts describes the reference's vertices: give reference too")
        for m in matches:
            stem = Path(m).stem
            if suffix and stem.endswith(suffix) and stem != suffix:
                stem = stem[: -len(suffix)]
            name = entry.get("name") if "name" in entry else stem
            if not isinstance(name, str) or not name:
                fail(f"{where}: name must be a non-empty string")
            if name in out and out[name].path != m:
                fail(f"{where}: two shapes are named {name!r} ({out[name].path} and {m})")
            ref = ref_facts = None
            if reference is not None:
                from .references import expand_reference, facts_problem, reference_problem

                ref = expand_reference(reference, name, base)
                problem = reference_problem(ref, m, tree=tree, params=params,
                                            shown=reference.replace("{stem}", name))
                if problem:
                    fail(f"{where} ({name!r}): {problem}")
                if facts is not None:
                    ref_facts = expand_reference(facts, name, base)
                    problem = facts_problem(ref_facts, ref, shown=facts.replace("{stem}", name))
                    if problem:
                        fail(f"{where} ({name!r}): {problem}")
            out[name] = ShapeSpec(name, m, viewpoints, ref, tree, ref_facts)
    return tuple(out.values())


def _viewpoints(value: Any, where: str, fail) -> tuple[tuple[float, float, float], ...]:
    """``viewpoint = [x, y, z]`` or ``[[x, y, z], ...]`` (the cloud's units); absent: ()."""
    if value is None:
        return ()
    rows = [value] if isinstance(value, list) and value and not isinstance(value[0], list) else value
    ok = isinstance(rows, list) and rows and all(
        isinstance(r, list) and len(r) == 3 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                    and math.isfinite(x) for x in r) for r in rows)
    if not ok:
        fail(f"{where}: viewpoint must be [x, y, z] or a list of them, finite numbers")
    return tuple(tuple(float(x) for x in r) for r in rows)


def skeletonize_accepts_method() -> bool:
    """True when :func:`skelcore.skeleton.skeletonize` takes ``method=`` (several skeletonizers)."""
    import inspect

    from ..skeleton import skeletonize

    return "method" in inspect.signature(skeletonize).parameters


def python_executable() -> str:
    """What ``{python}`` stands for: the interpreter running skelcore (``sys.executable``), so a
    script importing skelcore runs whether or not a venv is activated."""
    if not sys.executable:
        raise SkelInputError("{python}: cannot tell which Python interpreter runs skelcore (sys.executable is empty)")
    return sys.executable


def command_argv(template: str, label: str, values: dict[str, str] | None = None) -> list[str]:
    """The argv to run: the template split into words (``shlex``, no shell), then ``{python}`` and
    the given ``values`` (``{in}``, ``{out_skeletal}``, ``{out_curve}``) substituted in each word
    in one pass, so a substituted path is never expanded again."""
    argv = check_command_template(template, label)
    table = dict(values or {})
    if any("{python}" in word for word in argv):
        table["{python}"] = python_executable()
    return [_PLACEHOLDER_RE.sub(lambda m: table.get(m.group(0), m.group(0)), word) for word in argv]


def check_command_template(template: str, label: str) -> list[str]:
    """The argv of a skeletonizer command line; SkelInputError (prefixed ``label``) when unusable."""
    try:
        argv = shlex.split(template)
    except ValueError as exc:
        raise SkelInputError(f"{label} cannot be split into words: {exc}") from None
    if not argv:
        raise SkelInputError(f"{label} is empty")
    joined = " ".join(argv)
    if "{in}" not in joined:
        raise SkelInputError(f"{label} needs an {{in}} placeholder for the cloud file")
    if "{out_skeletal}" not in joined and "{out_curve}" not in joined:
        raise SkelInputError(f"{label} needs {{out_skeletal}} and/or {{out_curve}} placeholders")
    return argv


def _methods(value: Any, base: Path, shapes, fail, unknown) -> tuple[MethodSpec, ...]:
    out: list[MethodSpec] = []
    for i, entry in enumerate(_list_of_tables(value, "methods", fail)):
        where = f"methods[{i}]"
        name = _name(entry, where, fail)
        where = f"method {name!r}"
        kind = entry.get("kind")
        if kind not in ("builtin", "command", "files") + _adapter_kinds():
            fail(f"{where}: kind must be 'builtin', 'command', 'files' or a tool ({', '.join(_adapter_kinds())}), "
                 f"got {kind!r}")
        unknown(where, entry, _KEYS[kind if kind in _KEYS else "adapter"])
        if any(m.name == name for m in out):
            fail(f"{where}: two methods have this name")
        if kind == "builtin":
            spec = _builtin(entry, where, fail)
        elif kind == "command":
            spec = _command(entry, name, where, base, fail)
        elif kind in _adapter_kinds():
            spec = _adapter(entry, name, where, fail)
        else:
            spec = _files(entry, name, where, base, shapes, fail)
        if "correspondence" in entry:
            spec = _with_correspondence(spec, entry["correspondence"], where, fail)
        if "repair" in entry:
            if not isinstance(entry["repair"], bool):
                fail(f"{where}: repair must be true or false")
            import dataclasses

            spec = dataclasses.replace(spec, repair=entry["repair"])
        out.append(spec)
    return tuple(out)


def _with_correspondence(spec: MethodSpec, value: Any, where: str, fail) -> MethodSpec:
    import dataclasses
    import inspect

    from ..stages import evaluate

    if "correspondence" not in inspect.signature(evaluate).parameters:
        fail(f"{where}: this skelcore's evaluate() has no correspondence option")
    from ..stages import CORRESPONDENCE_CHOICES

    allowed = CORRESPONDENCE_CHOICES  # what evaluate() takes: a wrong value fails here, not in a job
    if value not in allowed:
        fail(f"{where}: correspondence must be one of {', '.join(allowed)}, got {value!r}")
    return dataclasses.replace(spec, correspondence=value)


def _builtin(entry: dict, where: str, fail) -> MethodSpec:
    from ..skeleton.skeleton_params import method_params

    params = entry.get("params", {})
    if not isinstance(params, dict):
        fail(f"{where}: params must be a table ([methods.params])")
    method = entry.get("method")
    if method is not None:
        if not isinstance(method, str):
            fail(f"{where}: method must be a string")
        if not skeletonize_accepts_method():
            fail(f"{where}: this skelcore's skeletonize() has no method= option (method = {method!r})")
    try:
        method_params(method, params)
    except (TypeError, ValueError) as exc:
        fail(f"{where}: {exc}")
    return MethodSpec(name=entry["name"], kind="builtin", method=method, params=dict(params))


def _adapter_kinds() -> tuple[str, ...]:
    from ..adapters import KINDS

    return KINDS


def _timeout(entry: dict, where: str, fail) -> float | None:
    timeout = entry.get("timeout")
    if timeout is not None and (isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or timeout <= 0):
        fail(f"{where}: timeout must be a number of seconds > 0")
    return None if timeout is None else float(timeout)


def _adapter(entry: dict, name: str, where: str, fail) -> MethodSpec:
    """Another tool by name: its parameters checked and completed, then the tool imported (a missing
    one is one line naming the ``[skeletonizers]`` extra, before any job runs)."""
    from ..adapters import require, resolve_params

    kind = entry["kind"]
    try:
        params = resolve_params(kind, entry.get("params", {}))
    except ValueError as exc:
        fail(f"{where}: {exc}")
    timeout = _timeout(entry, where, fail)
    try:
        tool = require(kind)
    except SkelInputError as exc:
        fail(f"{where}: {exc}")
    return MethodSpec(name=name, kind=kind, params=params, timeout=timeout, tool=tool)


def _command(entry: dict, name: str, where: str, base: Path, fail) -> MethodSpec:
    template = entry.get("command")
    if not isinstance(template, str):
        fail(f"{where}: needs command = \"prog {{in}} {{out_skeletal}} {{out_curve}}\"")
    try:
        argv = command_argv(template, f"{where}: command")
    except SkelInputError as exc:
        fail(str(exc))
    prog = argv[0]  # with {python} already the interpreter's absolute path
    if os.sep in prog:
        full = prog if os.path.isabs(prog) else str(base / prog)
        if not (os.path.isfile(full) and os.access(full, os.X_OK)):
            fail(f"{where}: program {prog!r} not found or not executable")
    elif shutil.which(prog) is None:
        fail(f"{where}: program {prog!r} is not on PATH")
    return MethodSpec(name=name, kind="command", command=template, timeout=_timeout(entry, where, fail),
                      cwd=str(base))


def _files(entry: dict, name: str, where: str, base: Path, shapes, fail) -> MethodSpec:
    templates = {}
    for key in ("curve", "skeletal", "skeletal_index"):
        t = entry.get(key)
        if t is None:
            continue
        if not isinstance(t, str) or "{stem}" not in t:
            fail(f"{where}: {key} must be a path template with {{stem}}, e.g. \"skeletons/{{stem}}_{key}.ply\"")
        templates[key] = t if os.path.isabs(t) else str(base / t)
    if "curve" not in templates and "skeletal" not in templates:
        fail(f"{where}: needs curve and/or skeletal path templates")
    if "skeletal_index" in templates and "skeletal" not in templates:
        fail(f"{where}: skeletal_index needs skeletal")
    mapping: dict[str, Any] = {}
    if "scale" in entry or "offset" in entry:
        from ..skeleton_mapping import check_mapping

        try:
            scale, offset = check_mapping(entry.get("scale", 1.0), entry.get("offset", [0.0, 0.0, 0.0]))
        except ValueError as exc:
            fail(f"{where}: {exc}")
        mapping = {"scale": scale, "offset": offset}
    spec = MethodSpec(name=name, kind="files", **templates, **mapping)
    if not spec.per_condition():
        for s in shapes:
            _files_exist(spec, s, None, [0], base, fail)
    return spec


def _files_exist(spec: MethodSpec, shape: ShapeSpec, condition: str | None, seeds, base: Path, fail) -> None:
    for key, template in spec.file_templates().items():
        for seed in seeds:
            p = expand_template(template, shape.name, condition, seed)
            if not os.path.isfile(p):
                fail(f"method {spec.name!r}: {key} file for shape {shape.name!r} not found: {p}")
            if "{seed}" not in template:
                break


def expand_template(template: str, stem: str, condition: str | None, seed: int) -> str:
    return template.replace("{stem}", stem).replace("{condition}", condition or "").replace("{seed}", str(seed))


def _seeds(seeds: Any, where: str, fail) -> tuple[int, ...]:
    if not isinstance(seeds, list) or not seeds or not all(isinstance(s, int) and not isinstance(s, bool) for s in seeds):
        fail(f"{where}: expected a non-empty list of integers, e.g. seeds = [0, 1]")
    if len(set(seeds)) != len(seeds):
        fail(f"{where}: a seed is listed twice")
    return tuple(seeds)


def _conditions(value: Any, fail, unknown) -> tuple[ConditionSpec, ...]:
    out: list[ConditionSpec] = []
    for i, entry in enumerate(_list_of_tables(value, "conditions", fail)):
        name = _name(entry, f"conditions[{i}]", fail)
        where = f"condition {name!r}"
        unknown(where, entry, _KEYS["conditions"])
        if any(c.name == name for c in out):
            fail(f"{where}: two conditions have this name")
        kw: dict[str, Any] = {"name": name}
        for key in ("noise", "grid", "base_grid"):
            if key in entry:
                v = entry[key]
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not (v > 0 if key != "noise" else v >= 0):
                    fail(f"{where}: {key} must be a number {'>= 0' if key == 'noise' else '> 0'}")
                kw[key] = float(v)
        for key in ("sparse", "fps"):
            if key in entry:
                v = entry[key]
                if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                    fail(f"{where}: {key} must be a positive whole number of points")
                kw[key] = v
        if sum(k in entry for k in ("sparse", "grid", "fps")) > 1:
            fail(f"{where}: give only one of sparse, grid and fps")
        if "model" in entry:
            if entry["model"] not in ("reference", "isotropic"):
                fail(f"{where}: model must be 'reference' or 'isotropic'")
            if "noise" not in entry:
                fail(f"{where}: model without noise")
            kw["model"] = entry["model"]
        if "seeds" in entry:
            kw["seeds"] = _seeds(entry["seeds"], f"{where}: seeds", fail)
        out.append(ConditionSpec(**kw))
    return tuple(out)
