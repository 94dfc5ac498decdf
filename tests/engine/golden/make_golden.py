"""Golden outputs of ``skelcore.evaluate``: the cases, how one is recorded, and the
writer of ``evaluate_golden.json``.

Recorded so that ``tests/engine/test_evaluate_golden.py`` can show that a change of the code
changes no value, bit for bit: per case the ``--json`` document (minus the timings and
the version), a sha256 of every array of the Evaluation (local values, barcodes, coverage gaps, rows),
the stages that ran (the timing keys), the stage labels in the order shown when the stages run one after
the other (``workers=1``) and the last progress fraction.  Two of the cases are real scans of
resources/scans (the hammer, the apple tree at the paper's 0.02 grid) with skeletons that
``skeletonize`` method "cao" made once, stored in ``scan_skeletons.npz``: the skeletonizer's last bits
follow the platform's scipy and BLAS, and these cases guard the evaluation, not the skeletonizer.

Three local values go through BLAS and LAPACK (the ellipse fits' products, the smoothness' principal
axes), whose kernels OpenBLAS and numpy choose by CPU: their last bits differ from one CPU to another
(up to about 1e-11 measured, forcing other kernels on one machine). Their values are stored as well, in
``evaluate_golden_values.npz``, and the test takes them within ``MACHINE_ATOL`` where the hash differs.

Run ``PYTHONPATH=. python tests/engine/golden/make_golden.py`` to rewrite both files (only when a change
of values is intended, and say why in the commit); with ``--skeletons`` it first remakes the scans'
skeletons; with ``--values`` it writes only the values file.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path
from typing import Any, Callable

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
SAMPLES = ROOT / "resources" / "samples"
SCANS = ROOT / "resources" / "scans"
GOLDEN = HERE / "evaluate_golden.json"
SKELETONS = HERE / "scan_skeletons.npz"
VALUES = HERE / "evaluate_golden_values.npz"
#: the arrays whose last bits follow the CPU's BLAS and LAPACK kernels, stored as values too
MACHINE_DEPENDENT = ("skeletal.smoothness", "curve.sample_centeredness_raw", "curve.vertex_smoothness")
#: how far those values (in [0, 1]) may move with the CPU: 1e-11 seen, a hundredfold margin
MACHINE_ATOL = 1e-9


# ---- inputs ---------------------------------------------------------------------------------------

def _sample(shape: str, kind: str = "") -> dict:
    from skelcore.io import load_curve, load_points

    pre = f"{shape}_{kind}_" if kind else f"{shape}_"
    return {
        "cloud": load_points(SAMPLES / f"{shape}_cloud.ply"),
        "skeletal": load_points(SAMPLES / f"{pre}skeletal.ply"),
        "curve": load_curve(SAMPLES / f"{pre}curve.ply"),
    }


def _scan_cloud(name: str) -> np.ndarray:
    from skelcore.io import load_cloud
    from skelcore.skeleton.degrade import voxel_grid_average

    if name == "hammer":
        return load_cloud(SCANS / "hammer_4096.ply")
    # the paper's "synthetic tree": the apple tree averaged on a 0.02 grid (8936 points)
    return voxel_grid_average(load_cloud(SCANS / "apple_tree_22367.ply"), 0.02)[0]


def write_scan_skeletons() -> None:
    """``scan_skeletons.npz``: each scan's "cao" skeletons, with the fan start the golden outputs were
    first made with ("axis"; the default became the toolbox's Qhull start later)."""
    from skelcore import skeletonize
    from skelcore.skeleton import CaoParams

    out = {}
    for name in ("hammer", "tree"):
        skeletal, curve = skeletonize(_scan_cloud(name), CaoParams(fan_start="axis"), method="cao")
        out[f"{name}_skeletal"] = np.asarray(skeletal)
        out[f"{name}_curve_vertices"] = np.asarray(curve.vertices)
        out[f"{name}_curve_edges"] = np.asarray(curve.edges)
    np.savez_compressed(SKELETONS, **out)


def _scan(name: str) -> dict:
    """A real scan and its stored "cao" skeletons."""
    from skelcore.curve import CurveSkeleton

    with np.load(SKELETONS) as z:
        skeletal = z[f"{name}_skeletal"]
        curve = CurveSkeleton.from_raw(z[f"{name}_curve_vertices"], z[f"{name}_curve_edges"])
    return {"cloud": _scan_cloud(name), "skeletal": skeletal, "curve": curve}


def _rows(n: int, step: int) -> np.ndarray:
    return np.arange(0, n, step, dtype=np.int64)


def _case(make: Callable[[], dict]) -> dict:
    return {"make": make}


def _cases() -> dict[str, dict]:
    from skelcore import Params

    def pointwise(shape, kind="", workers=None, **extra):
        def make():
            s = _sample(shape, kind)
            return dict(cloud=s["cloud"], skeletal=s["skeletal"], curve=s["curve"], workers=workers, **extra)

        return make

    def index_mode():
        s = _sample("yshape")
        rows = _rows(len(s["cloud"]), 7)
        return dict(cloud=s["cloud"], skeletal=s["skeletal"][rows], curve=s["curve"], skeletal_index=rows)

    def reverse_with_set(workers=None):
        def make():
            s = _sample("yshape", "lbc")
            return dict(cloud=s["cloud"], skeletal=s["skeletal"][::10], curve=s["curve"], correspondence="reverse",
                        workers=workers)

        return make

    def reverse_curve_only(workers=None):
        def make():
            s = _sample("torus")
            return dict(cloud=s["cloud"], curve=s["curve"], correspondence="reverse", workers=workers)

        return make

    def none_mode(params=Params()):
        def make():
            s = _sample("cylinder")
            return dict(cloud=s["cloud"], skeletal=s["skeletal"][::10], curve=s["curve"], params=params)

        return make

    def with_reference():
        s, ref = _sample("torus"), _sample("torus", "lbc")
        return dict(cloud=s["cloud"], skeletal=s["skeletal"], curve=s["curve"], reference_curve=ref["curve"])

    def curve_only():
        s = _sample("cylinder", "lbc")
        return dict(cloud=s["cloud"], curve=s["curve"], workers=1)

    def skeletal_only():
        s = _sample("torus", "lbc")
        return dict(cloud=s["cloud"], skeletal=s["skeletal"], workers=1)

    def scan(name, workers=None):
        def make():
            return dict(**_scan(name), workers=workers)

        return make

    no_cov = Params(coverage_max_points=1000)
    return {
        "cylinder": _case(pointwise("cylinder")),
        "cylinder_w1": _case(pointwise("cylinder", workers=1)),
        "cylinder_lbc_w1": _case(pointwise("cylinder", "lbc", workers=1)),
        "cylinder_no_coverage": _case(pointwise("cylinder", params=no_cov)),
        "torus": _case(pointwise("torus")),
        "torus_lbc": _case(pointwise("torus", "lbc")),
        "yshape": _case(pointwise("yshape")),
        "yshape_lbc_w1": _case(pointwise("yshape", "lbc", workers=1)),
        "yshape_index": _case(index_mode),
        "yshape_lbc_reverse": _case(reverse_with_set()),
        "yshape_lbc_reverse_w1": _case(reverse_with_set(workers=1)),
        "torus_reverse_curve_only": _case(reverse_curve_only()),
        "torus_reverse_curve_only_w1": _case(reverse_curve_only(workers=1)),
        "cylinder_none": _case(none_mode()),
        "cylinder_none_no_coverage": _case(none_mode(no_cov)),
        "torus_reference": _case(with_reference),
        "cylinder_lbc_curve_only_w1": _case(curve_only),
        "torus_lbc_skeletal_only_w1": _case(skeletal_only),
        "hammer_cao": _case(scan("hammer")),
        "hammer_cao_w1": _case(scan("hammer", workers=1)),
        "apple_tree_8936_cao": _case(scan("tree")),
    }


CASES = _cases()


# ---- one case's record ----------------------------------------------------------------------------

def array_sha(a: Any) -> str | None:
    """sha256 of an array's dtype, shape and bytes (None for None)."""
    if a is None:
        return None
    a = np.ascontiguousarray(a)
    h = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())
    return h.hexdigest()[:32]


def machine_dependent(ev: Any) -> dict[str, np.ndarray]:
    """The :data:`MACHINE_DEPENDENT` arrays of an Evaluation that has them."""
    parts = {"skeletal": ev.skeletal, "curve": ev.curve}
    out = {}
    for key in MACHINE_DEPENDENT:
        part, name = key.split(".")
        if parts[part] is not None:
            out[key] = np.asarray(getattr(parts[part], name), dtype=float)
    return out


def record(kwargs: dict, values: dict | None = None) -> dict:
    """Evaluate one case and return what is compared: document, array hashes, stages, progress;
    ``values`` receives its :func:`machine_dependent` arrays."""
    from skelcore import evaluate

    labels: list[str] = []
    last = [None]

    def progress(fraction: float, stage: str) -> None:
        if not labels or labels[-1] != stage:
            labels.append(stage)
        last[0] = fraction

    ev = evaluate(**kwargs, progress=progress)
    if values is not None:
        values.update(machine_dependent(ev))
    doc = ev.to_json_dict()
    doc.pop("timings_s")
    if isinstance(doc.get("scan"), dict):  # the scan checks' own timings
        doc["scan"].pop("timings_s", None)
    doc.pop("skelcore_version")
    doc.pop("schema_version")
    arrays: dict[str, str | None] = {
        "cloud": array_sha(ev.cloud),
        "normalization": array_sha(np.append(ev.normalization.center, ev.normalization.scale)),
    }
    s = ev.skeletal
    for name in ("points", "boundedness", "centeredness_raw", "smoothness", "rows", "centeredness_rows_raw", "index"):
        arrays[f"skeletal.{name}"] = None if s is None else array_sha(getattr(s, name))
    c = ev.curve
    for name in ("samples", "sample_edge", "sample_t", "sample_boundedness", "sample_centeredness_raw",
                 "vertex_degree", "vertex_smoothness"):
        arrays[f"curve.{name}"] = None if c is None else array_sha(getattr(c, name))
    arrays["curve.vertices"] = None if c is None else array_sha(c.curve.vertices)
    arrays["curve.edges"] = None if c is None else array_sha(c.curve.edges)
    t = ev.topology
    arrays["topology.cloud_barcode"] = None if t is None else array_sha(t.cloud_barcode)
    arrays["topology.skeletal_barcode"] = None if t is None else array_sha(t.skeletal_barcode)
    for name, cov in (("skeletal", ev.coverage_skeletal), ("curve", ev.coverage_curve)):
        arrays[f"coverage_{name}.gap"] = None if cov is None else array_sha(cov.gap)
        arrays[f"coverage_{name}.covered"] = None if cov is None else array_sha(cov.covered)
    scalars = {
        "skeletal": None if s is None else {"source": s.source, "centeredness_available": s.centeredness_available},
        "curve": None if c is None else {"smoothness_overall": repr(c.smoothness_overall),
                                         "smoothness_count": c.smoothness_count},
        "topology": None if t is None else [repr(t.bottleneck), repr(t.wasserstein), repr(t.eps_star), t.n_bars],
        "coverage": {name: None if cov is None else [repr(cov.fraction), repr(cov.mean_gap), repr(cov.max_gap),
                                                    repr(cov.tau), repr(cov.slack), cov.n_elements]
                     for name, cov in (("skeletal", ev.coverage_skeletal), ("curve", ev.coverage_curve))},
        "reference": None if ev.reference is None else {k: repr(v) for k, v in ev.reference.to_dict().items()},
    }
    one_lane = kwargs.get("workers") == 1
    return {
        "doc": doc,
        "arrays": arrays,
        "scalars": scalars,
        "stages": sorted(k for k in ev.timings if k != "total"),
        # one after the other the order is fixed; side by side only the set of labels is
        "progress_labels": labels if one_lane else sorted(set(labels)),
        "progress_last": last[0],
    }


def input_hashes(kwargs: dict) -> dict[str, str | None]:
    """The inputs' hashes: a changed skeletonizer shows here, not as a changed evaluation."""
    out = {}
    for key in ("cloud", "skeletal", "skeletal_index"):
        out[key] = array_sha(kwargs.get(key))
    for key in ("curve", "reference_curve"):
        c = kwargs.get(key)
        out[key] = None if c is None else array_sha(np.append(c.vertices.ravel(), c.edges.ravel()))
    return out


def main() -> None:
    sys.path.insert(0, str(ROOT))
    if "--skeletons" in sys.argv[1:]:
        write_scan_skeletons()
    out: dict[str, Any] = {}
    values: dict[str, np.ndarray] = {}
    for name, case in CASES.items():
        kwargs = case["make"]()
        found: dict[str, np.ndarray] = {}
        out[name] = {"inputs": input_hashes(kwargs), **record(kwargs, found)}
        values.update({f"{name}/{key}": a for key, a in found.items()})
        print(name, out[name]["stages"])
    with open(VALUES.with_suffix(".tmp.npz"), "wb") as fh:
        np.savez_compressed(fh, **values)
    VALUES.with_suffix(".tmp.npz").replace(VALUES)
    print(f"wrote {VALUES} ({VALUES.stat().st_size:,} bytes)")
    if "--values" not in sys.argv[1:]:
        GOLDEN.write_text(json.dumps(out, indent=1, sort_keys=True) + "\n")
        print(f"wrote {GOLDEN} ({GOLDEN.stat().st_size:,} bytes)")


if __name__ == "__main__":
    main()
