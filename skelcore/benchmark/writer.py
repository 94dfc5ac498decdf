"""A benchmark folder's files, all written atomically (:mod:`skelcore.io.atomic`):

- ``clouds/{case}.ply``: the cloud (binary PLY, double x y z);
- ``truth/{case}_reference.ply``: its exact curve skeleton (PLY with an ``edge`` element and a
  per-vertex ``radius``), the file :mod:`.reference_ply` reads;
- ``truth/{neuron}_gt_facts.csv`` (the real suites only): the traced skeleton's per-node facts
  (:mod:`.neurons`; docs/benchmark.md, the real suite);
- ``cases/{case}.json``: the case's record (its spec, seeds, counts), written last: a case whose
  record is there and matches its spec is finished (resume);
- ``suite.json``: every case's record; ``compare.toml``: a manifest for ``skelcore compare`` running
  the built-in skeletonizers on every case, with ``reference = "truth/{stem}_reference.ply"``;
- ``.skelscope-run``: the marker saying the folder is a benchmark (kind "bench", suite, seed,
  generator; written by :func:`skelcore.compare.run_marker.claim_run_folder`).
Same inputs, same bytes (the marker aside, which records when the folder was made): no dates, no
absolute paths, keys in a fixed order.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ..io import write_curve_ply, write_points_ply
from ..io.atomic import atomic_open

__all__ = ["cloud_path", "reference_path", "record_path", "facts_path", "write_case_files", "write_json",
           "write_manifest", "read_json"]

def cloud_path(folder: Path, case: str) -> Path:
    return folder / "clouds" / f"{case}.ply"


def reference_path(folder: Path, case: str) -> Path:
    return folder / "truth" / f"{case}_reference.ply"


def record_path(folder: Path, case: str) -> Path:
    return folder / "cases" / f"{case}.json"


def facts_path(folder: Path, neuron: str) -> Path:
    return folder / "truth" / f"{neuron}_gt_facts.csv"


def write_case_files(folder: Path, case: str, cloud: np.ndarray, vertices: np.ndarray, edges: np.ndarray,
                     radius: np.ndarray) -> None:
    """The cloud and its reference curve (with radius), each atomically."""
    for sub in ("clouds", "truth", "cases"):
        (folder / sub).mkdir(exist_ok=True)
    write_points_ply(cloud_path(folder, case), cloud)
    write_curve_ply(reference_path(folder, case), vertices, edges, scalars={"radius": np.asarray(radius, float)})


def write_json(path: Path, doc: Any) -> None:
    with atomic_open(path, "w") as fh:
        json.dump(doc, fh, indent=1, allow_nan=False)
        fh.write("\n")


def read_json(path: Path) -> Any | None:
    """The document, or None when the file is missing or not JSON (then the case is remade)."""
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except (OSError, ValueError):
        return None


def _toml_string(text: str) -> str:
    return json.dumps(text)  # a JSON string of printable ASCII is a TOML basic string


def write_manifest(folder: Path, records: list[dict[str, Any]], suite: str, seed: int,
                   notes: list[str] | None = None) -> None:
    """``compare.toml``: the built-in skeletonizers (cao, skelscope) on every case, each case with its
    reference curve (and its facts file, ``reference_facts``, when its record names one: a real suite's
    case), ``tree = true`` when its record says so and, for a one-sided scan, its viewpoints
    (the sensors the scan was made from); ``notes``: comment lines replacing the generated shapes' note."""
    lines = [
        f"# skelcore compare manifest of the benchmark in this folder (suite {suite!r}, seed {seed}),",
        "# written by `skelcore bench make`:  skelcore compare compare.toml --out runs/compare",
        *(notes if notes is not None else [
            "# Each shape is one case of suite.json: its cloud and its exact curve skeleton (reference, a PLY",
            "# with a per-vertex radius). Cases of the plate are marked ill-posed there: a thin plate has no",
            "# well-defined curve skeleton (its reference is only the rim's centre circle)."]),
        "",
    ]
    for name, method in (("cao", "cao"), ("skelscope", "skelscope")):
        lines += ["[[methods]]", f"name = {_toml_string(name)}", 'kind = "builtin"', f"method = {_toml_string(method)}", ""]
    for rec in records:
        lines += ["[[shapes]]", f"name = {_toml_string(rec['name'])}", f"path = {_toml_string(rec['files']['cloud'])}",
                  'reference = "truth/{stem}_reference.ply"']
        facts = (rec.get("files") or {}).get("facts")
        if facts:  # a real suite's traced reference: compare adds the held scores (docs/metrics.md 5.3.1)
            lines.append(f"reference_facts = {_toml_string(facts)}")
        if rec.get("tree"):
            lines.append("tree = true")
        eyes = (rec.get("scan") or {}).get("viewpoints")
        if eyes:  # a one-sided scan: compare scores it from its sensors (docs/metrics.md 6.3)
            lines.append("viewpoint = [" + ", ".join("[" + ", ".join(repr(float(x)) for x in e) + "]" for e in eyes) + "]")
        lines.append("")
    with atomic_open(folder / "compare.toml", "w") as fh:
        fh.write("\n".join(lines))
