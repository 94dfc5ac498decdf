"""Running one skeletonizer on one cloud: the built-in one, an external command (no shell, its own
process group, killed on timeout or cancel), another tool by name (:mod:`skelcore.adapters`, in a
child process run the same way) or precomputed files. Returns what ``evaluate`` takes.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import tempfile
import time
from typing import Any, Callable

import numpy as np

from ..curve import CurveSkeleton
from ..errors import Cancelled, SkelInputError
from .manifest import (MethodSpec, check_command_template, command_argv, expand_template, python_executable,
                       skeletonize_accepts_method)

__all__ = ["skeletonize_accepts_method", "run_builtin", "run_command", "run_adapter", "read_files"]

Progress = Callable[[float, str], None]


def run_builtin(points: np.ndarray, spec: MethodSpec, progress: Progress | None = None,
                cancel: Callable[[], bool] | None = None) -> tuple[np.ndarray | None, CurveSkeleton | None]:
    from ..skeleton import skeletonize
    from ..skeleton.skeleton_params import method_params

    method, params = method_params(spec.method, spec.params)
    return skeletonize(points, params, progress=progress, cancel=cancel, method=method)


def _kill_group(proc: subprocess.Popen) -> None:
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        proc.kill()
    proc.communicate()


def run_command(
    template: str,
    cloud_path: str,
    skeletal_path: str,
    curve_path: str,
    *,
    timeout: float | None = None,
    cancel: Callable[[], bool] | None = None,
    label: str = "command",
    cwd: str | None = None,
) -> tuple[np.ndarray | None, CurveSkeleton | None]:
    """Run the user's skeletonizer: ``shlex.split`` argv, placeholders substituted per token
    (``{python}``: the interpreter running skelcore, :func:`.manifest.command_argv`).

    The program runs in its own session so that a timeout, a cancel or our own termination kills it
    and all its children. Its outputs are read back with the project's loaders, so a file that is
    not a skeleton becomes a one-line error naming it.
    """
    from .. import io

    joined = " ".join(check_command_template(template, label))
    wants_skeletal = "{out_skeletal}" in joined
    wants_curve = "{out_curve}" in joined
    args = command_argv(template, label, {"{in}": cloud_path, "{out_skeletal}": skeletal_path,
                                          "{out_curve}": curve_path})
    for stale in (skeletal_path, curve_path):
        if os.path.exists(stale):
            os.unlink(stale)
    _run_process(args, label, timeout=timeout, cancel=cancel, cwd=cwd)
    skeletal = curve = None
    if wants_skeletal:
        if not os.path.exists(skeletal_path):
            raise SkelInputError(f"{label} did not write the skeletal point set", skeletal_path)
        skeletal = io.load_points(skeletal_path)
    if wants_curve:
        if not os.path.exists(curve_path):
            raise SkelInputError(f"{label} did not write the curve skeleton", curve_path)
        curve = io.load_curve(curve_path)
    return skeletal, curve


def _run_process(args: list[str], label: str, *, timeout: float | None = None,
                 cancel: Callable[[], bool] | None = None, cwd: str | None = None,
                 env: dict[str, str] | None = None, exit_2_is_input_error: bool = False) -> None:
    """Run ``args`` in its own session until it exits; SkelInputError (one line, prefixed ``label``)
    when it cannot start, times out or is cancelled (its whole process group killed), or fails.
    ``exit_2_is_input_error``: status 2 means the program already said what was wrong in one line."""
    try:
        proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                errors="replace", start_new_session=True, cwd=cwd, env=env)
    except OSError as exc:
        raise SkelInputError(f"{label} could not start {args[0]!r}: {exc.strerror or exc}") from None
    start = time.monotonic()
    try:
        while True:
            try:
                out, err = proc.communicate(timeout=0.1)
                break
            except subprocess.TimeoutExpired:
                if cancel is not None and cancel():
                    _kill_group(proc)
                    raise Cancelled("cancelled while the skeleton command ran") from None
                if timeout is not None and time.monotonic() - start > timeout:
                    _kill_group(proc)
                    raise SkelInputError(f"{label} timed out after {timeout:g} s and was killed") from None
    except BaseException:
        if proc.poll() is None:  # SystemExit from SIGTERM, KeyboardInterrupt: take the program down too
            _kill_group(proc)
        raise
    if proc.returncode != 0:
        last = (err or out or "").strip().splitlines()
        if exit_2_is_input_error and proc.returncode == 2 and last:
            raise SkelInputError(f"{label}: {last[-1][:300]}")
        how = f"was killed by signal {-proc.returncode}" if proc.returncode < 0 else f"exited with status {proc.returncode}"
        raise SkelInputError(f"{label} {how}" + (f": {last[-1][:200]}" if last else ""))


def run_adapter(points: np.ndarray, spec: MethodSpec, *, cancel: Callable[[], bool] | None = None,
                label: str | None = None) -> tuple[np.ndarray | None, CurveSkeleton, str, dict[str, Any]]:
    """Run a tool adapter (``spec.kind`` in :data:`skelcore.adapters.KINDS`) on ``points`` in a child
    process (``python -m skelcore.adapters.child``): a crash or a hang past ``spec.timeout`` fails
    this job with one line, and the run goes on. Returns (skeletal, curve, correspondence, info: what
    the adapter reports, such as the voxel size it used)."""
    label = label or f"method {spec.name!r}: {spec.kind}"
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # holds skelcore/
    env = dict(os.environ)  # the child imports this very skelcore, installed or not
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    with tempfile.TemporaryDirectory(prefix="skelcore-adapter-") as work:
        cloud, out, request = (os.path.join(work, n) for n in ("cloud.npy", "out.npz", "request.json"))
        np.save(cloud, np.asarray(points, dtype=np.float64))
        with open(request, "w", encoding="utf-8") as fh:
            json.dump({"kind": spec.kind, "params": spec.params, "cloud": cloud, "out": out, "tool": spec.tool}, fh)
        _run_process([python_executable(), "-m", "skelcore.adapters.child", request], label,
                     timeout=spec.timeout, cancel=cancel, env=env, exit_2_is_input_error=True)
        with np.load(out) as z:
            radius = z["curve_radius"] if "curve_radius" in z.files else None
            curve = CurveSkeleton.from_raw(z["curve_vertices"], z["curve_edges"], radius=radius)
            skeletal = z["skeletal"] if "skeletal" in z.files else None
            correspondence = str(z["correspondence"])
            info = json.loads(str(z["info"])) if "info" in z.files else {}
    return skeletal, curve, correspondence, info


def read_files(spec: MethodSpec, stem: str, condition: str, seed: int
               ) -> tuple[np.ndarray | None, CurveSkeleton | None, np.ndarray | None, dict[str, str]]:
    """Precomputed skeletons of a ``files`` method: (skeletal, curve, skeletal_index, paths), mapped
    into the cloud's frame by the method's ``scale`` / ``offset`` (:mod:`skelcore.skeleton_mapping`)."""
    from .. import io
    from ..skeleton_mapping import map_skeleton

    paths = {k: expand_template(t, stem, condition, seed) for k, t in spec.file_templates().items()}
    skeletal = io.load_points(paths["skeletal"]) if "skeletal" in paths else None
    curve = io.load_curve(paths["curve"]) if "curve" in paths else None
    mapping = spec.mapping()
    if mapping is not None:
        skeletal, curve = map_skeleton(skeletal, curve, mapping["scale"], mapping["offset"])
    index = None
    if "skeletal_index" in paths:
        index = _load_index(paths["skeletal_index"])
    return skeletal, curve, index, paths


def _load_index(path: str) -> np.ndarray:
    """One cloud row per skeletal point: a ``.npy`` or a text file of integers."""
    try:
        arr = np.load(path) if path.endswith(".npy") else np.loadtxt(path, dtype=np.int64, ndmin=1)
    except (OSError, ValueError) as exc:
        raise SkelInputError(f"cannot read the skeletal index: {exc}", path) from None
    arr = np.asarray(arr)
    if arr.ndim != 1 or not np.issubdtype(arr.dtype, np.integer):
        raise SkelInputError("skeletal index must be one integer per line", path)
    return arr.astype(np.int64)
