"""The paper's degradation study: skeletonize a cloud, a noisy and a sparse copy, score each, and
write the results table (paper, Table "Quantitative results": rows normal / 5% noise / sparse;
columns d_B/d_Wp, boundedness, centeredness, smoothness, each "skeletal/curve").

Each variant is scored against its own (degraded) cloud, as the paper's toolbox does. The built-in
skeletonizer is :func:`skelcore.skeleton.skeletonize`; ``skeleton_cmd`` plugs in any other
program instead. A study is ``skelcore compare`` with one shape and one method: each row is a
compare job (:func:`skelcore.compare.jobs.execute`), run here in this process. The
``study`` subcommand lives in :mod:`skelcore.cli.study`.
"""

from __future__ import annotations

import csv
import io as _io
import os
import tempfile
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..params import Params
from ..scores import COLUMN, ScoreColumn, column_keys, format_score, paired_columns

__all__ = ["StudyRow", "StudyResult", "run_study"]

Progress = Callable[[float, str], None]

#: the paper's table's scores (d_B, d_Wp, then each metric skeletal, curve)
_PAPER = column_keys(group="paper", compared=True)


@dataclass
class StudyRow:
    """One variant: its cloud, skeleton, evaluation and the files written for it."""

    name: str  # "normal", "noise" or "sparse"
    label: str  # as in the paper's table: "4096 pts", "5% noise", "1024 pts"
    cloud: np.ndarray
    skeletal: np.ndarray | None
    curve: CurveSkeleton | None
    evaluation: Any  # skelcore.evaluation.Evaluation
    files: dict[str, str] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)

    def scores(self) -> dict[str, float | None]:
        """The paper's overall scores (None where the skeleton lacks that representation)."""
        s = self.evaluation.scores()
        return {k: s.get(k) for k in _PAPER}



def _pair(s: dict[str, float | None], a: str, b: str) -> str:
    """A "skeletal/curve" (or "d_B/d_Wp") cell of the paper's table."""
    return f"{format_score(s[a], COLUMN[a].digits)}/{format_score(s[b], COLUMN[b].digits)}"


@dataclass
class StudyResult:
    """The study's rows plus what produced them; table writers in three formats."""

    name: str
    rows: list[StudyRow]
    params: Params
    settings: dict[str, Any]

    HEADER = ("shape", "d_B/d_Wp", *(metric for metric, _s, _c in paired_columns("paper")))

    def table(self) -> list[tuple[str, ...]]:
        """Header and one row per variant, cells "skeletal/curve" as in the paper (d_B 4 digits)."""
        out = [self.HEADER]
        for row in self.rows:
            s = row.scores()
            out.append((f"{self.name} ({row.label})", _pair(s, "d_B", "d_Wp"),
                        *(_pair(s, sk.key, cv.key) for _m, sk, cv in paired_columns("paper"))))
        return out

    def to_markdown(self) -> str:
        rows = self.table()
        widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
        lines = ["| " + " | ".join(c.ljust(w) for c, w in zip(rows[0], widths)) + " |",
                 "|" + "|".join("-" * (w + 2) for w in widths) + "|"]
        lines += ["| " + " | ".join(c.ljust(w) for c, w in zip(r, widths)) + " |" for r in rows[1:]]
        return "\n".join(lines) + "\n"

    def to_csv(self) -> str:
        """Machine-readable: one column per score, full precision, empty where not computed."""
        buf = _io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        keys = _PAPER
        w.writerow(["variant", "label", "n_points", *keys])
        for row in self.rows:
            s = row.scores()
            w.writerow([row.name, row.label, len(row.cloud), *("" if s[k] is None else repr(float(s[k])) for k in keys)])
        return buf.getvalue()

    def to_latex(self) -> str:
        """A ``tabular`` in the paper's layout (booktabs-free, like the paper's table)."""

        def esc(text: str) -> str:
            for a, b in (("\\", r"\textbackslash{}"), ("&", r"\&"), ("%", r"\%"), ("_", r"\_"), ("#", r"\#")):
                text = text.replace(a, b)
            return text

        def pair(a: ScoreColumn, b: ScoreColumn) -> str:  # "$A/B\uparrow$" from "$A$" and "$B$"
            return f"${a.tex.strip('$')}/{b.tex.strip('$')}{a.tex_arrow}$"

        cells = [pair(COLUMN["d_B"], COLUMN["d_Wp"]), *(pair(sk, cv) for _m, sk, cv in paired_columns("paper"))]
        head = r"\textbf{Shapes} & " + " & ".join(cells) + r" \\ \hline\hline"
        lines = [r"\begin{tabular}{l" + "l" * len(cells) + "}", r"\hline", head]
        lines += [" & ".join(esc(c) for c in r) + r" \\" for r in self.table()[1:]]
        lines += [r"\hline", r"\end{tabular}"]
        return "\n".join(lines) + "\n"

    def write_tables(self, out_dir: str | os.PathLike, inputs: tuple[str, ...] = ()) -> dict[str, str]:
        """``study.md``, ``study.csv``, ``study.tex`` in ``out_dir``; returns their paths."""
        from ..io.atomic import atomic_open

        paths = {}
        for ext, text in (("md", self.to_markdown()), ("csv", self.to_csv()), ("tex", self.to_latex())):
            path = os.path.join(out_dir, f"study.{ext}")
            with atomic_open(path, "w", inputs=inputs) as fh:
                fh.write(text)
            paths[ext] = path
        return paths


# ---------------------------------------------------------------------------------------------
# the study = compare jobs of one shape and one method


def _conditions(
    cloud: np.ndarray,
    *,
    noise: float | None,
    noise_model: str,
    sparse: int | None,
    grid: float | None,
    base_grid: float | None,
) -> list[Any]:
    """The study's rows as compare conditions (normal, noise, sparse)."""
    from ..skeleton.degrade import voxel_grid_average
    from ..compare.manifest import ConditionSpec

    if sparse is not None and grid is not None:
        raise SkelInputError("give either a sparse point count or a grid cell, not both")
    n_normal = len(cloud) if base_grid is None else len(voxel_grid_average(cloud, base_grid)[0])
    out = [ConditionSpec("normal", base_grid=base_grid)]
    if noise:
        if noise_model not in ("reference", "isotropic"):
            raise ValueError(f"noise model must be 'reference' or 'isotropic', got {noise_model!r}")
        out.append(ConditionSpec("noise", noise=float(noise), model=noise_model, base_grid=base_grid))
    if grid is not None:
        out.append(ConditionSpec("sparse", grid=float(grid)))
    else:
        n = sparse if sparse is not None else max(10, n_normal // 4)
        if n < n_normal:
            out.append(ConditionSpec("sparse", sparse=int(n), base_grid=base_grid))
    return out


def run_study(
    cloud: np.ndarray,
    *,
    noise: float | None = 0.05,
    noise_model: str = "reference",
    sparse: int | None = None,
    grid: float | None = None,
    base_grid: float | None = None,
    seed: int = 0,
    out_dir: str | os.PathLike | None = None,
    skeleton_cmd: str | None = None,
    params: Params = Params(),
    skeletonize_params: Any = None,
    method: str | None = None,
    name: str = "cloud",
    inputs: tuple[str, ...] = (),
    progress: Progress | None = None,
    cancel: Callable[[], bool] | None = None,
) -> StudyResult:
    """Skeletonize and score the cloud, a noisy copy and a sparse copy (the paper's study).

    Parameters
    ----------
    cloud : (N, 3) points in the user's units.
    noise : noise ratio for the "noise" row (paper: 0.05); 0 or None leaves the row out.
    noise_model : ``"reference"`` (sigma = ratio x each coordinate, the paper's toolbox) or
        ``"isotropic"``; see :func:`skelcore.skeleton.degrade.add_noise`.
    sparse : points kept (random, seeded) for the "sparse" row; default N // 4 (4096 -> 1024 as in
        the paper). Exclusive with ``grid``.
    grid : voxel-grid cell for the "sparse" row instead (the paper's tree and cave), applied to the
        input cloud.
    base_grid : voxel-grid cell applied to the input to make the "normal" row (the paper's tree:
        22367 points, cell 0.02 -> 8936; then ``grid=0.05`` -> 1730 for the sparse row).
    seed : seeds the noise and the random downsampling.
    out_dir : when given, every variant's cloud, skeletal points, curve (PLY) and evaluation (JSON)
        and the tables ``study.md/.csv/.tex`` are written there.
    skeleton_cmd : instead of the built-in skeletonizer, a command line with ``{in}`` (the variant's
        cloud, written as PLY) and ``{out_skeletal}`` and/or ``{out_curve}`` placeholders (and
        ``{python}``, the interpreter running skelcore); run without a shell.
    params : evaluation parameters (docs/metrics.md); ``skeletonize_params`` : :class:`CaoParams` or
        :class:`SkeletonizeParams`; ``method`` : the built-in skeletonizer, "cao" (default) or
        "skelscope" (see :func:`skelcore.skeleton.skeletonize`).
    name : the shape's name in the table's first column.
    inputs : paths no output may overwrite (the user's files).
    progress, cancel : as :func:`skelcore.evaluate`.

    Examples
    --------
    >>> result = run_study(cloud, noise=0.05, sparse=1024, seed=0)    # doctest: +SKIP
    >>> print(result.to_markdown())                                   # doctest: +SKIP
    """
    import dataclasses

    from .. import io
    from ..skeleton.degrade import _cloud
    from ..skeleton import SkeletonizeParams
    from ..compare.jobs import Job, execute
    from ..compare.manifest import MethodSpec, ShapeSpec

    cloud = _cloud(cloud)
    if method is None:
        method = "skelscope" if isinstance(skeletonize_params, SkeletonizeParams) else "cao"
    sk_values = dataclasses.asdict(skeletonize_params) if skeletonize_params is not None else {}
    conditions = _conditions(cloud, noise=noise, noise_model=noise_model, sparse=sparse, grid=grid,
                             base_grid=base_grid)
    if skeleton_cmd is not None:
        method_spec = MethodSpec(name="--skeleton-cmd", kind="command", command=skeleton_cmd)
    else:
        method_spec = MethodSpec(name="builtin", kind="builtin", method=method, params=sk_values)
    shape = ShapeSpec(name, inputs[0] if inputs else "")
    if out_dir is not None:
        out_dir = os.fspath(out_dir)
        os.makedirs(out_dir, exist_ok=True)
    work = tempfile.TemporaryDirectory(prefix="skelcore-study-") if skeleton_cmd and out_dir is None else None
    folder = out_dir if out_dir is not None else (work.name if work is not None else None)

    n_rows = len(conditions)
    rows: list[StudyRow] = []
    try:
        for k, cond in enumerate(conditions):
            vname = cond.name

            def row_progress(f: float, stage: str, k: int = k, vname: str = vname) -> None:
                progress((k + f) / n_rows, f"{vname}: {stage}")  # type: ignore[misc]

            job = Job(shape, method_spec, cond, seed, params)
            out = execute(job, folder, prefix=f"{vname}_", write_cloud=out_dir is not None, inputs=inputs,
                          progress=None if progress is None else row_progress, cancel=cancel, cloud=cloud)
            pts, skeletal, curve, ev = out.points, out.skeletal, out.curve, out.evaluation
            files = dict(out.files)
            timings = {"skeletonize": out.timings["degrade"] + out.timings["skeletonize"],
                       "evaluate": out.timings["evaluate"]}
            if out_dir is not None:
                if skeletal is not None and not skeleton_cmd:
                    files["skeletal"] = os.path.join(out_dir, f"{vname}_skeletal.ply")
                    io.write_points_ply(files["skeletal"], skeletal, inputs=inputs)
                if curve is not None and not skeleton_cmd:
                    files["curve"] = os.path.join(out_dir, f"{vname}_curve.ply")
                    io.write_curve_ply(files["curve"], curve.vertices, curve.edges, inputs=inputs)
                files["json"] = os.path.join(out_dir, f"{vname}_evaluation.json")
                ev.inputs.update({k2: v for k2, v in files.items() if k2 in ("cloud", "skeletal", "curve")})
                ev.write_json(files["json"], inputs=inputs)
            rows.append(StudyRow(vname, cond.label(len(pts)), pts, skeletal, curve, ev, files, timings))
    finally:
        if work is not None:
            work.cleanup()

    settings = {"noise": noise, "noise_model": noise_model, "sparse": sparse, "grid": grid,
                "base_grid": base_grid, "seed": seed, "skeleton_cmd": skeleton_cmd,
                "method": None if skeleton_cmd else (method or "cao")}
    result = StudyResult(name=name, rows=rows, params=params, settings=settings)
    if out_dir is not None:
        result.write_tables(out_dir, inputs=inputs)
    if progress is not None:
        progress(1.0, "done")
    return result
