"""``python -m skelcore.adapters.child REQUEST.json``: run one adapter in a process of its own, so
a tool that crashes (a segfault in its C++) or hangs fails one job, not the run.

The request names the ``kind``, its resolved ``params``, the ``cloud`` (.npy), the ``out`` file
(.npz, written atomically) and the ``tool`` version string the job key was made with; a worker
with another version refuses (its results would be filed under the wrong key). Exit 0: written;
2: an input problem; 1: the tool raised. The last stderr line is the one-line reason.
"""

from __future__ import annotations

import json
import sys

import numpy as np


def main(argv: list[str] | None = None) -> int:
    from ..errors import SkelInputError
    from ..io.atomic import atomic_open
    from . import registry

    args = sys.argv[1:] if argv is None else argv
    with open(args[0], encoding="utf-8") as fh:
        req = json.load(fh)
    try:
        tool = registry.require(req["kind"])
        if req.get("tool") and tool != req["tool"]:
            raise SkelInputError(f"this worker has {tool}, the job key was made with {req['tool']}")
        res = registry.run(req["kind"], np.load(req["cloud"]), req.get("params") or {})
    except SkelInputError as exc:
        print(" ".join(str(exc).split()), file=sys.stderr)
        return 2
    except Exception as exc:  # the tool's own failure: one line
        print(f"{type(exc).__name__}: {' '.join(str(exc).split())}"[:300], file=sys.stderr)
        return 1
    arrays = {"curve_vertices": res.curve.vertices, "curve_edges": res.curve.edges,
              "correspondence": np.array(res.correspondence), "tool": np.array(tool),
              "info": np.array(json.dumps(res.info))}
    if res.curve.radius is not None:
        arrays["curve_radius"] = res.curve.radius
    if res.skeletal is not None:
        arrays["skeletal"] = res.skeletal
    with atomic_open(req["out"], "wb") as fh:
        np.savez(fh, **arrays)
    return 0


if __name__ == "__main__":
    sys.exit(main())
