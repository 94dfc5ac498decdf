"""The results store: one folder per run, one atomic JSON record per job (``jobs/KEY.json``) and its
local values for the report (``jobs/KEY.npz``), so a killed run loses only the jobs in flight and
a rerun skips every key already there.

The ``.npz`` is written before the ``.json``, and a job counts as finished only once its JSON
exists and parses; leftovers of an interrupted write (``.*.tmp``) are ignored and swept.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from ..errors import SkelInputError
from ..io.atomic import atomic_open
from ..io.json_numbers import json_float, json_safe
from ..io.schemas import SCHEMA_VERSION

__all__ = ["Store", "json_float"]  # json_float: from skelcore.io.json_numbers, re-exported


class Store:
    def __init__(self, out_dir: str | os.PathLike, inputs: tuple[str, ...] = ()) -> None:
        self.root = Path(out_dir)
        self.jobs_dir = self.root / "jobs"
        self.inputs = inputs
        try:
            self.jobs_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise SkelInputError(f"cannot create the output folder: {exc.strerror or exc}", out_dir) from None
        if not os.access(self.jobs_dir, os.W_OK):
            raise SkelInputError("output folder is not writable", out_dir)
        for stale in self.jobs_dir.glob(".*.tmp"):
            stale.unlink(missing_ok=True)

    def json_path(self, key: str) -> Path:
        return self.jobs_dir / f"{key}.json"

    def npz_path(self, key: str) -> Path:
        return self.jobs_dir / f"{key}.npz"

    def has(self, key: str) -> bool:
        return self.get(key) is not None

    def get(self, key: str) -> dict[str, Any] | None:
        try:
            with open(self.json_path(key), encoding="utf-8") as fh:
                return json.load(fh)
        except (OSError, ValueError):
            return None

    def put(self, record: dict[str, Any]) -> None:
        """Write a job's record (and its arrays, popped from ``record["arrays"]``) atomically."""
        # the format's version first (skelcore/io/schemas/compare_job.schema.json)
        rec = {"schema_version": SCHEMA_VERSION, **{k: v for k, v in record.items() if k != "schema_version"}}
        arrays = rec.pop("arrays", None)
        key = rec["key"]
        if arrays:
            with atomic_open(self.npz_path(key), "wb", inputs=self.inputs) as fh:
                np.savez_compressed(fh, **arrays)
            rec["arrays"] = self.npz_path(key).name
        with atomic_open(self.json_path(key), "w", inputs=self.inputs) as fh:
            json.dump(json_safe(rec), fh, indent=1)
            fh.write("\n")

    def arrays(self, key: str) -> dict[str, np.ndarray]:
        path = self.npz_path(key)
        if not path.exists():
            return {}
        with np.load(path) as z:
            return {k: z[k] for k in z.files}

    def records(self, keys: list[str] | None = None) -> Iterator[dict[str, Any]]:
        """Stored records, in the order of ``keys`` when given (missing ones skipped)."""
        if keys is None:
            keys = sorted(p.stem for p in self.jobs_dir.glob("*.json"))
        for key in keys:
            rec = self.get(key)
            if rec is not None:
                yield rec

