"""One job = (shape, method, condition, seed): degrade, skeletonize, evaluate with every metric.

A job's key hashes what its result depends on: the bytes of its input files (cloud, precomputed
skeletons), the method's definition, the condition, the seed and the evaluation parameters, so a
rerun finds finished jobs and an edited input recomputes exactly the jobs it feeds.
``execute`` is the one code path (``skelcore study`` calls it too); ``run_job`` wraps it for a
worker: it never raises, a failure is a record with a one-line error.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..curve import CurveSkeleton
from ..errors import Cancelled, SkelInputError
from ..params import Params
from ..scores import Scores, column_keys
from .conditions import degrade
from .manifest import ConditionSpec, Manifest, MethodSpec, ShapeSpec, expand_template

__all__ = ["Job", "JobOutput", "make_jobs", "execute", "run_job", "scores_from_doc", "SCORE_COLUMNS",
           "HELD_COLUMNS", "file_digest"]

Progress = Callable[[float, str], None]

#: the scores a job's record holds (:mod:`skelcore.scores`' compared columns; "seconds" is the job's own)
SCORE_COLUMNS = tuple(k for k in column_keys(compared=True) if k != "seconds")
#: the scores on the held reference (docs/metrics.md 5.3.1): in a record only where the shape's
#: reference has facts (``reference_facts``)
HELD_COLUMNS = ("gt_held_precision", "gt_held_recall", "gt_held_f1")


@dataclass(frozen=True)
class Job:
    shape: ShapeSpec
    method: MethodSpec
    condition: ConditionSpec
    seed: int
    params: Params
    key: str = ""

    @property
    def label(self) -> str:
        return f"{self.shape.name} / {self.method.name} / {self.condition.name} / seed {self.seed}"


@dataclass
class JobOutput:
    """What ``execute`` produced, in memory."""

    points: np.ndarray
    skeletal: np.ndarray | None
    curve: CurveSkeleton | None
    evaluation: Any  # skelcore.evaluation.Evaluation
    timings: dict[str, float] = field(default_factory=dict)
    files: dict[str, str] = field(default_factory=dict)
    reference: CurveSkeleton | None = None  # the shape's ground-truth curve
    adapter: dict[str, Any] = field(default_factory=dict)  # an adapter's report (its voxel size, say)


_digests: dict[tuple[str, float, int], str] = {}


def file_digest(path: str) -> str:
    """SHA-256 of a file's bytes (cached per path, mtime and size within one process)."""
    st = os.stat(path)
    k = (os.path.abspath(path), st.st_mtime, st.st_size)
    if k not in _digests:
        h = hashlib.sha256()
        with open(path, "rb") as fh:
            for chunk in iter(lambda: fh.read(1 << 20), b""):
                h.update(chunk)
        _digests[k] = h.hexdigest()
    return _digests[k]


def _job_key(job: Job) -> str:
    from ..skeleton.skeleton_params import method_params

    method = job.method.to_dict()
    method.pop("cwd")  # a moved dataset keeps its results (the inputs are hashed by content)
    if job.method.kind == "builtin":
        method["method"], resolved = method_params(job.method.method, job.method.params)
        method["params"] = resolved.__dict__
    if job.method.kind == "files":
        method = {"kind": "files", "name": job.method.name, "inputs": {
            k: file_digest(expand_template(t, job.shape.name, job.condition.name, job.seed))
            for k, t in sorted(job.method.file_templates().items())}}
        if job.method.mapping() is not None:  # absent when unmapped: older runs keep their keys
            method["mapping"] = job.method.mapping()
    doc = {"cloud": file_digest(job.shape.path), "shape": job.shape.name, "method": method,
           "condition": job.condition.to_dict(), "seed": job.seed, "params": job.params.to_dict()}
    if job.shape.viewpoints:  # only then: the keys of runs without viewpoints stay as they were
        doc["viewpoints"] = [list(v) for v in job.shape.viewpoints]
    if job.shape.reference:  # likewise: the reference's bytes
        doc["reference"] = file_digest(job.shape.reference)
    if job.shape.reference_facts:  # and its facts' (the held scores)
        doc["reference_facts"] = file_digest(job.shape.reference_facts)
    text = json.dumps(doc, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def make_jobs(manifest: Manifest) -> list[Job]:
    """Every (shape, method, condition, seed) of the manifest, keyed. A ``files`` method whose
    templates do not name ``{condition}`` holds skeletons of the clean clouds: it only gets the
    conditions that do not degrade."""
    jobs = []
    for shape in manifest.shapes:
        for method in manifest.methods:
            for cond in manifest.conditions:
                if method.kind == "files" and not method.per_condition() and cond.degrades:
                    continue
                for seed in cond.seeds or manifest.seeds:
                    job = Job(shape, method, cond, seed, manifest.params)
                    jobs.append(Job(shape, method, cond, seed, manifest.params, _job_key(job)))
    return jobs


def execute(job: Job, workdir: str | None = None, *, prefix: str = "", write_cloud: bool = False,
            inputs: tuple[str, ...] = (), progress: Progress | None = None,
            cancel: Callable[[], bool] | None = None, cloud: np.ndarray | None = None) -> JobOutput:
    """Degrade, skeletonize (or run the command, or read the files) and evaluate one job.

    ``workdir`` receives ``{prefix}cloud.ply`` (always for a command, else if ``write_cloud``) and a
    command's ``{prefix}skeletal.ply`` / ``{prefix}curve.ply``. ``cloud`` skips reading the shape.
    """
    from .. import io
    from ..stages import evaluate
    from ..adapters import KINDS as ADAPTER_KINDS
    from .methods import read_files, run_adapter, run_builtin, run_command

    def part(lo: float, hi: float) -> Progress | None:
        if progress is None:
            return None
        return lambda f, stage: progress(lo + (hi - lo) * f, stage)

    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    base = io.load_cloud(job.shape.path) if cloud is None else cloud
    pts = degrade(base, job.condition, job.seed)
    timings["degrade"] = time.perf_counter() - t0
    files: dict[str, str] = {}
    m = job.method
    if workdir is not None and (write_cloud or m.kind == "command"):
        files["cloud"] = os.path.join(workdir, f"{prefix}cloud.ply")
        io.write_points_ply(files["cloud"], pts, inputs=inputs)
    t0 = time.perf_counter()
    index = None
    adapter_info: dict[str, Any] = {}
    correspondence = m.correspondence  # an adapter says what its skeletal set is unless the manifest does
    if m.kind == "builtin":
        skeletal, curve = run_builtin(pts, m, progress=part(0.0, 0.5), cancel=cancel)
    elif m.kind == "command":
        if workdir is None:
            raise ValueError("a command method needs a workdir")
        if progress is not None:
            progress(0.0, "skeleton command")
        out_s = os.path.join(workdir, f"{prefix}skeletal.ply")
        out_c = os.path.join(workdir, f"{prefix}curve.ply")
        label = "--skeleton-cmd" if m.name == "--skeleton-cmd" else f"method {m.name!r}: command"
        skeletal, curve = run_command(m.command or "", files["cloud"], out_s, out_c, timeout=m.timeout,
                                      cancel=cancel, label=label, cwd=m.cwd)
        files.update({k: p for k, p, v in (("skeletal", out_s, skeletal), ("curve", out_c, curve)) if v is not None})
    elif m.kind in ADAPTER_KINDS:
        if progress is not None:
            progress(0.0, m.kind)
        skeletal, curve, own, adapter_info = run_adapter(pts, m, cancel=cancel)
        correspondence = correspondence or own
    else:
        skeletal, curve, index, paths = read_files(m, job.shape.name, job.condition.name, job.seed)
        files.update(paths)
    timings["skeletonize"] = time.perf_counter() - t0
    if m.repair and curve is not None and curve.n_edges:
        from ..skeleton_repair import repair

        t0 = time.perf_counter()
        curve = repair(pts, curve, cancel=cancel).curve  # the method's curve repaired (docs/repair.md)
        timings["repair"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    kwargs: dict[str, Any] = {}
    if index is not None:
        kwargs["skeletal_index"] = index
    if correspondence is not None:
        kwargs["correspondence"] = correspondence
    viewpoints = job.shape.viewpoints or _pcd_viewpoints(job.shape.path)
    if viewpoints:
        kwargs["viewpoints"] = np.asarray(viewpoints, dtype=float)
    inputs_doc = {"cloud": files.get("cloud")}
    reference = None
    if job.shape.reference:
        from .references import load_reference, load_reference_outside

        reference = load_reference(job.shape.reference)
        if curve is not None:  # the ground-truth metrics compare curves (docs/metrics.md 5.3.1)
            kwargs["reference_curve"] = reference
            inputs_doc["reference_curve"] = job.shape.reference
            if job.shape.reference_facts:  # and the held scores, on the nodes the cloud can show
                kwargs["reference_outside"] = load_reference_outside(job.shape.reference_facts, reference)
                inputs_doc["reference_facts"] = job.shape.reference_facts
    ev = evaluate(pts, skeletal, curve, job.params, progress=part(0.5, 1.0), cancel=cancel,
                  inputs=inputs_doc, **kwargs)
    timings["evaluate"] = time.perf_counter() - t0
    return JobOutput(pts, skeletal, curve, ev, timings, files, reference, adapter_info)


# ---- the worker's entry point -------------------------------------------------------------------

def _pcd_viewpoints(path: str) -> tuple:
    """A PCD shape's VIEWPOINT when it is not PCL's default (docs/metrics.md 6.3), else ()."""
    from ..io import pcd_viewpoint

    v = pcd_viewpoint(path)
    return () if v is None else (tuple(float(x) for x in v),)


def scores_from_doc(doc: dict[str, Any] | None) -> dict[str, float]:
    """Flat scores of an ``evaluate --json`` document; NaN where not computed (all NaN without one).
    The held ground-truth scores (:data:`HELD_COLUMNS`) only when computed, from the shape's
    ``reference_facts``: absent otherwise, not NaN (docs/compare.md "Ground truth")."""
    if not doc:
        return {k: math.nan for k in SCORE_COLUMNS if k not in HELD_COLUMNS}
    scores = Scores.from_json_dict(doc)
    return scores.flat([k for k in SCORE_COLUMNS if k not in HELD_COLUMNS or scores.get(k) is not None])


def _arrays(ev: Any, reference: CurveSkeleton | None = None) -> dict[str, np.ndarray]:
    """The local values the report draws (:func:`skelcore.display.picture_arrays.drawing_arrays`: float32
    coordinates, NaN kept), the shape's reference curve (drawn under the skeleton), and the whole
    evaluation at full precision for the viewer (:mod:`skelcore.io.evaluation_files`)."""
    from ..display.picture_arrays import drawing_arrays
    from ..io.evaluation_files import evaluation_arrays

    out = drawing_arrays(ev)
    if reference is not None:
        out.update(reference_vertices=np.asarray(reference.vertices, np.float32),
                   reference_edges=np.asarray(reference.edges, np.int32))
    out.update(evaluation_arrays(ev))
    return out


def one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    if isinstance(exc, SkelInputError):
        return text
    return f"{type(exc).__name__}: {text}"[:300] if text else type(exc).__name__


def run_job(job: Job) -> dict[str, Any]:
    """Execute a job in a scratch folder and return its record (never raises on a job's failure):
    ``status`` "ok" or "failed", ``error``, scores, the evaluation document and the arrays."""
    rec: dict[str, Any] = {"key": job.key, "shape": job.shape.name, "method": job.method.name,
                           "condition": job.condition.name, "seed": job.seed, "status": "failed",
                           "error": "", "pid": os.getpid(), "started": time.time()}
    t0 = time.perf_counter()
    try:
        with tempfile.TemporaryDirectory(prefix="skelcore-job-") as work:
            out = execute(job, work if job.method.kind == "command" else None)
        doc = out.evaluation.to_json_dict()
        doc["inputs"]["cloud"]["path"] = job.shape.path
        rec.update(status="ok", evaluation=doc, timings=out.timings, n_points=int(len(out.points)),
                   label=job.condition.label(len(out.points)), arrays=_arrays(out.evaluation, out.reference))
        if out.adapter:
            rec["adapter"] = out.adapter
    except (SkelInputError, Cancelled) as exc:
        rec["error"] = one_line(exc)
    except MemoryError:
        rec["error"] = "MemoryError: out of memory"
    except Exception as exc:  # a bug or a library failure on odd input: recorded, never fatal
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" (at {os.path.basename(tb[-1].filename)}:{tb[-1].lineno})" if tb else ""
        rec["error"] = one_line(exc) + where
    rec["seconds"] = time.perf_counter() - t0
    rec["finished"] = time.time()
    rec["scores"] = scores_from_doc(rec.get("evaluation"))
    return rec
