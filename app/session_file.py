"""A saved viewer session as one small JSON file (File > Save session, ``skelscope --session F``).

Not :mod:`skelscope.session`, the viewer's controller: this is the file format, without widgets. A session holds
the inputs' paths (relative to the session file when possible, absolute as well) with each file's
size, modification time and SHA-256, so that opening it can tell a file that moved (missing) or
changed from one that did not; the settings and thresholds (every ``skelcore.Params`` field) and the
correspondence mode (docs/metrics.md 5.1) with the skeletal set's index file (a record like the inputs'), the real-scan
options (``remove_outliers``, ``cap_openings``); each skeleton
layer's mapping into the cloud's frame (scale, offset); the curve's edits (``edits``: skelcore's edit
log, replayed on the loaded curve); the scan's viewpoints; the metric, colour
range and display options; the camera with the view's size; and the picked element. Written atomically (``skelcore.io.atomic``); read back with
every field checked, so a bad file is one line (``SkelInputError``) before anything changes.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import dataclass, field
from typing import Any, Iterable

from skelcore.errors import SkelInputError
from skelcore.io.atomic import atomic_open
from skelcore.params import Params

__all__ = ["FORMAT", "VERSION", "ROLES", "FileRecord", "SessionState", "fingerprint", "write_session",
           "read_session", "session_to_json", "session_from_json", "locate", "Located", "file_sha256"]

FORMAT = "skelscope_session"
VERSION = 1
ROLES = ("cloud", "skeletal", "curve")
CORRESPONDENCES = ("auto", "reverse")
#: skelcore.evaluate's real-scan options a session records (the Settings panel's check boxes)
SCAN_OPTIONS = ("remove_outliers", "cap_openings")
_HASH_CHUNK = 1 << 20


@dataclass(frozen=True)
class FileRecord:
    """One input file as saved: where it was (absolute, and relative to the session file's folder when
    on the same drive) and what it was (size in bytes, modification time, SHA-256)."""

    path: str
    relative: str | None
    size: int
    mtime: float
    sha256: str


@dataclass
class SessionState:
    """Everything a session restores; see the module docstring. ``params`` is ``Params.to_dict()``."""

    files: dict[str, FileRecord] = field(default_factory=dict)
    params: dict[str, Any] = field(default_factory=dict)
    correspondence: str = "auto"
    scan_options: dict[str, bool] = field(default_factory=dict)  # remove_outliers, cap_openings (evaluate's)
    skeletal_index: FileRecord | None = None  # the skeletal set's index file (docs/metrics.md 5.1), found like the inputs
    mappings: dict[str, tuple[float, tuple[float, float, float]]] = field(default_factory=dict)  # role -> scale, offset
    viewpoints: list[tuple[float, float, float]] = field(default_factory=list)  # the scan's sensor positions
    metric: str = "boundedness"
    clim: tuple[float, float] | None = None
    edges_as_tubes: bool = False
    style: dict[str, bool] = field(default_factory=dict)
    layers: dict[str, dict[str, Any]] = field(default_factory=dict)  # role -> visible, point_size, opacity
    camera: dict[str, Any] | None = None
    picked: dict[str, Any] | None = None  # layer, location, index
    edits: dict[str, Any] | None = None  # the curve's edit log (skelcore.edit.new_log), None when not edited
    defect_marks: dict[str, str] = field(default_factory=dict)  # Defects dock: mark key -> fixed / accepted / ignored

    def paths(self) -> dict[str, str]:
        return {role: rec.path for role, rec in self.files.items()}


def file_sha256(path: str | os.PathLike) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(_HASH_CHUNK), b""):
            digest.update(chunk)
    return digest.hexdigest()


def fingerprint(path: str | os.PathLike, base_dir: str | os.PathLike) -> FileRecord:
    """The record of an input file as it is now; ``relative`` to ``base_dir`` (the session file's
    folder) when a relative path exists (same drive)."""
    path = os.path.abspath(str(path))
    st = os.stat(path)
    try:
        relative: str | None = os.path.relpath(path, os.path.abspath(str(base_dir)))
    except ValueError:  # another drive (Windows)
        relative = None
    return FileRecord(path, relative, int(st.st_size), float(st.st_mtime), file_sha256(path))


def session_to_json(state: SessionState) -> dict[str, Any]:
    return {
        FORMAT: VERSION,
        "files": {role: _record_json(rec) for role, rec in state.files.items()},
        "params": {k: _json_value(v) for k, v in state.params.items()},
        "correspondence": state.correspondence,
        "scan_options": {k: bool(v) for k, v in state.scan_options.items()},
        "skeletal_index": None if state.skeletal_index is None else _record_json(state.skeletal_index),
        "mappings": {role: {"scale": float(s), "offset": [float(v) for v in o]} for role, (s, o) in state.mappings.items()},
        "viewpoints": [[float(v) for v in p] for p in state.viewpoints],
        "metric": state.metric,
        "clim": None if state.clim is None else [float(state.clim[0]), float(state.clim[1])],
        "edges_as_tubes": bool(state.edges_as_tubes),
        "style": {k: bool(v) for k, v in state.style.items()},
        "layers": {role: dict(opts) for role, opts in state.layers.items()},
        "camera": state.camera,
        "picked": state.picked,
        **({} if state.edits is None else {"edits": state.edits}),
        **({"defect_marks": dict(state.defect_marks)} if state.defect_marks else {}),
    }


def write_session(path: str | os.PathLike, state: SessionState, inputs: Iterable[str] = ()) -> str:
    """Write ``state`` as a session file, atomically and never over a loaded input."""
    with atomic_open(path, "w", inputs=tuple(inputs)) as fh:
        json.dump(session_to_json(state), fh, indent=1, allow_nan=False)
        fh.write("\n")
    return str(path)


def read_session(path: str | os.PathLike) -> SessionState:
    """Read and check a session file; SkelInputError naming the file and the problem otherwise."""
    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
    except FileNotFoundError:
        raise SkelInputError("session file not found", path) from None
    except IsADirectoryError:
        raise SkelInputError("is a folder, not a session file", path) from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise SkelInputError(f"not a SkelScope session file ({exc})", path) from None
    return session_from_json(doc, path)


def session_from_json(doc: Any, path: str | os.PathLike = "session") -> SessionState:
    """A parsed session document, checked field by field (SkelInputError naming ``path``)."""

    def bad(why: str) -> SkelInputError:
        return SkelInputError(f"not a SkelScope session file ({why})", path)

    if not isinstance(doc, dict) or FORMAT not in doc:
        raise bad(f"no {FORMAT!r} key")
    version = doc[FORMAT]
    if not isinstance(version, int) or version < 1:
        raise bad(f"bad version {version!r}")
    if version > VERSION:
        raise SkelInputError(f"session format version {version} is newer than this SkelScope reads ({VERSION})", path)
    state = SessionState()
    files = doc.get("files", {})
    if not isinstance(files, dict) or set(files) - set(ROLES):
        raise bad(f"'files' must map {', '.join(ROLES)} to file records")
    for role, rec in files.items():
        state.files[role] = _record(rec, role, bad)
    params = doc.get("params", {})
    if not isinstance(params, dict):
        raise bad("'params' must be an object")
    known = set(Params().to_dict())
    unknown = sorted(set(params) - known)
    if unknown:
        raise bad(f"unknown parameter(s) {', '.join(unknown)}")
    try:
        Params(**{k: _from_json_value(v) for k, v in params.items()})
    except (TypeError, ValueError) as exc:
        raise bad(f"bad parameters: {exc}") from None
    state.params = {k: _from_json_value(v) for k, v in params.items()}
    state.correspondence = str(doc.get("correspondence", "auto"))
    if state.correspondence not in CORRESPONDENCES:
        raise bad(f"correspondence must be one of {', '.join(CORRESPONDENCES)}")
    options = doc.get("scan_options", {})
    if not isinstance(options, dict) or set(options) - set(SCAN_OPTIONS) or \
            not all(isinstance(v, bool) for v in options.values()):
        raise bad(f"scan_options must map {' / '.join(SCAN_OPTIONS)} to true or false")
    state.scan_options = dict(options)
    index = doc.get("skeletal_index")
    if isinstance(index, str):  # written before the index had a record: its path alone
        state.skeletal_index = FileRecord(index, None, -1, 0.0, "")
    elif index is not None:
        state.skeletal_index = _record(index, "skeletal index", bad)
    mappings = doc.get("mappings", {})
    if not isinstance(mappings, dict) or set(mappings) - {"skeletal", "curve"}:
        raise bad("'mappings' must map skeletal, curve to a scale and an offset")
    for role, m in mappings.items():
        try:
            scale, offset = float(m["scale"]), tuple(float(v) for v in m["offset"])
        except (TypeError, KeyError, ValueError):
            raise bad(f"the {role} mapping needs a scale and an offset x y z") from None
        if len(offset) != 3 or not all(math.isfinite(v) for v in (scale, *offset)) or scale <= 0:
            raise bad(f"the {role} mapping needs a scale > 0 and a finite offset x y z")
        state.mappings[role] = (scale, offset)  # type: ignore[assignment]
    edits = doc.get("edits")
    if edits is not None and not (isinstance(edits, dict) and isinstance(edits.get("operations"), list)):
        raise bad("'edits' must be an edit log (skelcore.edit.new_log, with its operations) or null")
    state.edits = edits
    marks = doc.get("defect_marks", {})
    if not isinstance(marks, dict) or not all(isinstance(k, str) and v in ("fixed", "accepted", "ignored")
                                              for k, v in marks.items()):
        raise bad("'defect_marks' must map defect keys to fixed, accepted or ignored")
    state.defect_marks = dict(marks)
    viewpoints = doc.get("viewpoints", [])
    try:
        state.viewpoints = [tuple(float(v) for v in p) for p in viewpoints]  # type: ignore[misc]
    except (TypeError, ValueError):
        raise bad("viewpoints must be a list of x y z") from None
    if any(len(p) != 3 or not all(math.isfinite(v) for v in p) for p in state.viewpoints):
        raise bad("viewpoints must be a list of x y z")
    from .scene import METRICS
    from .scene.model import STYLE_DEFAULTS

    state.metric = str(doc.get("metric", "boundedness"))
    if state.metric not in METRICS:
        raise bad(f"metric must be one of {', '.join(METRICS)}")
    clim = doc.get("clim")
    if clim is not None:
        try:
            lo, hi = (float(v) for v in clim)
        except (TypeError, ValueError):
            raise bad("clim must be null or [min, max]") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise bad("clim needs finite min < max")
        state.clim = (lo, hi)
    state.edges_as_tubes = bool(doc.get("edges_as_tubes", False))
    style = doc.get("style", {})
    if not isinstance(style, dict) or set(style) - set(STYLE_DEFAULTS):
        raise bad(f"style keys must be among {', '.join(STYLE_DEFAULTS)}")
    state.style = {k: bool(v) for k, v in style.items()}
    layers = doc.get("layers", {})
    if not isinstance(layers, dict) or set(layers) - set(ROLES):
        raise bad(f"'layers' must map {', '.join(ROLES)} to display options")
    for role, opts in layers.items():
        try:
            state.layers[role] = {"visible": bool(opts.get("visible", True)),
                                  "point_size": float(opts["point_size"]), "opacity": float(opts["opacity"])}
        except (AttributeError, KeyError, TypeError, ValueError):
            raise bad(f"the {role} layer needs visible, point_size and opacity") from None
    camera = doc.get("camera")
    if camera is not None:
        from .view.camera import check_camera

        keys = ("position", "focal_point", "view_up", "view_angle", "parallel_projection", "parallel_scale")
        if not isinstance(camera, dict) or any(k not in camera for k in keys):
            raise bad(f"the camera needs {', '.join(keys)}")
        try:
            for key in ("position", "focal_point", "view_up"):
                vec = [float(v) for v in camera[key]]
                if len(vec) != 3 or not all(math.isfinite(v) for v in vec):
                    raise ValueError(key)
                camera[key] = vec
            camera["view_angle"], camera["parallel_scale"] = float(camera["view_angle"]), float(camera["parallel_scale"])
        except (TypeError, ValueError):
            raise bad("bad camera vector or number") from None
        state.camera = check_camera(camera, path)
    picked = doc.get("picked")
    if picked is not None:
        try:
            state.picked = {"layer": str(picked["layer"]), "location": str(picked["location"]),
                            "index": int(picked["index"])}
        except (TypeError, KeyError, ValueError):
            raise bad("the picked element needs layer, location and index") from None
        if state.picked["layer"] not in ROLES or state.picked["index"] < 0:
            raise bad("bad picked element")
    return state


@dataclass(frozen=True)
class Located:
    """Where a session's file is now (None: missing) and what changed about it ("" when nothing)."""

    role: str
    path: str | None
    problem: str = ""


def locate(role: str, record: FileRecord, session_path: str | os.PathLike) -> Located:
    """Find a saved file: beside the session first (its relative path: a folder moved whole), then at
    its absolute path. A found file whose size differs, or whose content hash differs when only the
    modification time does, is reported as changed (and still loaded); a missing one as missing."""
    base = os.path.dirname(os.path.abspath(str(session_path)))
    candidates = ([os.path.normpath(os.path.join(base, record.relative))] if record.relative else []) + [record.path]
    name = os.path.basename(record.path)
    found = next((p for p in candidates if os.path.isfile(p)), None)
    if found is None:
        where = " or ".join(dict.fromkeys(candidates))
        return Located(role, None, f"{name}: missing (the {role}; looked for {where})")
    st = os.stat(found)
    if record.size < 0:  # an old session's index: its path only, nothing to compare
        return Located(role, found)
    if st.st_size != record.size:
        return Located(role, found, f"{name}: changed since the session was saved (the {role}; "
                                    f"{record.size} bytes then, {st.st_size} now)")
    if st.st_mtime != record.mtime and file_sha256(found) != record.sha256:
        return Located(role, found, f"{name}: changed since the session was saved (the {role}; same size, "
                                    "other content)")
    return Located(role, found)


def _record_json(rec: FileRecord) -> dict[str, Any]:
    return {"path": rec.path, "relative": rec.relative, "size": rec.size, "mtime": rec.mtime, "sha256": rec.sha256}


def _record(rec: Any, what: str, bad: Any) -> FileRecord:
    try:
        relative = rec.get("relative")
        return FileRecord(str(rec["path"]), None if relative is None else str(relative), int(rec["size"]),
                          float(rec["mtime"]), str(rec["sha256"]))
    except (AttributeError, KeyError, TypeError, ValueError):
        raise bad(f"the {what} file record needs path, size, mtime and sha256") from None


def _json_value(v: Any) -> Any:
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)  # "inf", "nan": JSON has no such numbers
    return v


def _from_json_value(v: Any) -> Any:
    if isinstance(v, str) and v in ("inf", "-inf", "nan"):
        return float(v)
    return v
