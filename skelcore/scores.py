"""The overall scores as one flat, typed record, the catalogue of its columns and the one number
formatter every table uses (CLI, summary panel, study, compare jobs, results.csv, leaderboard).

A :class:`Scores` is made from an Evaluation (:meth:`Scores.from_evaluation`, thresholds beta*, c*
from its ``Params`` unless given, docs/metrics.md 2-3) or read back from a stored ``evaluate --json`` document
(:meth:`Scores.from_json_dict`); both give equal records. ``None`` means not computed (no such input,
no correspondence), NaN computed without a valid element (docs/metrics.md 5.5). Each field names where the
document holds it; :data:`SCORE_COLUMNS` says how a score is labelled, rounded, ranked and grouped
(paper, SkelScope's own, reference comparison, ground truth, diagnostics, run facts). Adding a score is one field and one
column here (plus its value in the Evaluation and its JSON document).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any, Callable, Iterable

__all__ = ["Scores", "ScoreColumn", "SCORE_COLUMNS", "COLUMN", "KINDS", "format_score", "column_keys",
           "paired_columns", "paper_table"]

#: the two skeleton representations, in the paper's column order (docs/metrics.md 0)
KINDS = ("skeletal", "curve")
#: the paper's local metrics (docs/metrics.md 2-4), in the order every table, menu and colour choice lists them
LOCAL_METRICS = ("boundedness", "centeredness", "smoothness")


def format_score(value: Any, digits: int = 3, *, missing: str = "-", nan: str = "nan", signed: bool = False) -> str:
    """A score as every table prints it: ``missing`` for None (not computed), ``nan`` for NaN (no
    valid element), "inf" / "-inf", else ``digits`` decimals (a sign always when ``signed``).

    >>> format_score(0.81234), format_score(None), format_score(float("nan")), format_score(0.0123, 4, signed=True)
    ('0.812', '-', 'nan', '+0.0123')
    """
    if value is None:
        return missing
    v = float(value)
    if math.isnan(v):
        return nan
    return f"{v:+.{digits}f}" if signed else f"{v:.{digits}f}"


@dataclass(frozen=True)
class ScoreColumn:
    """How one score of :class:`Scores` is shown and compared.

    ``key`` is the Scores field and the results.csv / leaderboard column; ``better`` "higher",
    "lower" or None (a fact, not ranked); ``digits`` the decimals shown (the leaderboard ranks on
    them); ``group`` "paper", "skelscope", "reference", "ground truth", "diagnostics" or "run"; ``metric`` / ``kind`` place a
    per-representation score in the paper's table (row, column); ``count`` names the field with the
    number of elements it counted; ``detail`` a text shown after it, fields in braces; ``compared``
    makes it a column of ``skelcore compare`` (job records, results.csv, leaderboard, profiles).
    """

    key: str
    label: str
    short: str
    tex: str
    unit: str
    better: str | None
    digits: int
    group: str
    metric: str = ""
    kind: str | None = None
    count: str | None = None
    detail: str = ""
    compared: bool = False

    def format(self, value: Any, **kw: Any) -> str:
        return format_score(value, self.digits, **kw)

    @property
    def arrow(self) -> str:
        """The paper's table arrows: ↓ lower is better, ↑ higher, "" unranked."""
        return {"lower": "↓", "higher": "↑"}.get(self.better or "", "")

    @property
    def tex_arrow(self) -> str:
        """The arrow in LaTeX math (without the $)."""
        return {"lower": r"\downarrow", "higher": r"\uparrow"}.get(self.better or "", "")


def _per_kind(metric: str, tex: tuple[str, str], unit: str, *, group: str = "paper", count: bool = True,
              detail: str = "", short: str = "") -> tuple[ScoreColumn, ...]:
    return tuple(ScoreColumn(f"{metric}_{kind}", f"{metric} ({kind})", f"{short or metric[:7]}. {kind[0]}", t, unit,
                             "higher", 3, group, metric, kind, f"n_{metric}_{kind}" if count else None,
                             detail.replace("KIND", kind), compared=True)
                 for kind, t in zip(KINDS, tex))


_GAP = "gap {coverage_KIND_mean_gap} / {coverage_KIND_max_gap}"

#: Every column, in the order of :meth:`Scores.row` (and of results.csv and the leaderboard).
SCORE_COLUMNS: tuple[ScoreColumn, ...] = (
    # the paper's (docs/metrics.md 1-4)
    ScoreColumn("d_B", "d_B", "d_B", r"$d_B$", "normalized units", "lower", 4, "paper", "topology", compared=True),
    ScoreColumn("d_Wp", "d_Wp", "d_Wp", r"$d_{W_p}$", "normalized units", "lower", 4, "paper", "topology",
                compared=True),
    ScoreColumn("eps_star", "eps*", "eps*", r"$\epsilon^*$", "normalized units", None, 5, "paper", "topology"),
    ScoreColumn("n_bars", "K (bars compared)", "K", r"$K$", "bars", None, 0, "paper", "topology"),
    *_per_kind("boundedness", (r"$\mathcal{B}_{P_s}$", r"$\mathcal{B}_{G_s}$"), "fraction", short="bounded"),
    *_per_kind("centeredness", (r"$\mathcal{C}_s(P_s)$", r"$\mathcal{C}_s(G_s)$"), "fraction", short="centred"),
    *_per_kind("smoothness", (r"$S(P_s)$", r"$\mathfrak{S}_{G_s}$"), "mean in [0, 1]", short="smooth"),
    # the ground-truth metrics against the reference (docs/metrics.md 5.3.1): the cloud's units
    # and local radii of the reference; the community's metrics, side by side with the paper's
    ScoreColumn("gt_chamfer_radii", "chamfer (radii)", "CD r", r"CD$_r$", "local radii", "lower", 3, "ground truth",
                compared=True),
    ScoreColumn("gt_chamfer", "chamfer", "CD", "CD", "the cloud's units", "lower", 4, "ground truth", compared=True),
    ScoreColumn("gt_precision", "precision", "P", "$P$", "fraction", "higher", 3, "ground truth", compared=True),
    ScoreColumn("gt_recall", "recall", "R", "$R$", "fraction", "higher", 3, "ground truth", compared=True),
    ScoreColumn("gt_f1", "F1", "F1", "$F_1$", "fraction", "higher", 3, "ground truth", compared=True),
    # on the held reference, where the reference's facts are given (a real suite's traced neuron):
    # only its nodes the cloud can show (docs/metrics.md 5.3.1 "The held reference")
    ScoreColumn("gt_held_precision", "held precision", "held P", "$P_h$", "fraction", "higher", 3, "ground truth",
                compared=True),
    ScoreColumn("gt_held_recall", "held recall", "held R", "$R_h$", "fraction", "higher", 3, "ground truth",
                compared=True),
    ScoreColumn("gt_held_f1", "held F1", "held F1", "$F_{1,h}$", "fraction", "higher", 3, "ground truth",
                compared=True),
    ScoreColumn("gt_junction_precision", "junction precision", "J-P", "$J_P$", "fraction", "higher", 3, "ground truth",
                compared=True),
    ScoreColumn("gt_junction_recall", "junction recall", "J-R", "$J_R$", "fraction", "higher", 3, "ground truth",
                compared=True),
    ScoreColumn("gt_endpoint_precision", "endpoint precision", "E-P", "$E_P$", "fraction", "higher", 3, "ground truth",
                compared=True),
    ScoreColumn("gt_endpoint_recall", "endpoint recall", "E-R", "$E_R$", "fraction", "higher", 3, "ground truth",
                compared=True),
    ScoreColumn("gt_cycle_error", "|cycle count error|", "|dC|", r"$|\Delta C|$", "cycles", "lower", 1,
                "ground truth", compared=True),
    ScoreColumn("gt_length_ratio", "length ratio", "L/L*", "$L/L^*$", "ours / reference", None, 3, "ground truth",
                compared=True),
    ScoreColumn("gt_splits", "splits", "split", "splits", "count", "lower", 1, "ground truth", compared=True),
    ScoreColumn("gt_merges", "merges", "merge", "merges", "count", "lower", 1, "ground truth", compared=True),
    # SkelScope's own (docs/metrics.md 5.2)
    *_per_kind("coverage", (r"cov.\ $P_s$", r"cov.\ $G_s$"), "fraction of the cloud", group="skelscope", count=False,
               detail=_GAP, short="cover"),
    *(ScoreColumn(f"coverage_{kind}_{g}_gap", f"{g} coverage gap ({kind})", f"{g} gap {kind[0]}.",
                  rf"{g} gap ${'P_s' if kind == 'skeletal' else 'G_s'}$", "normalized units", "lower", 4, "skelscope",
                  "coverage", kind) for kind in KINDS for g in ("mean", "max")),
    ScoreColumn("coverage_tau", "coverage tau", "tau", r"$\tau$", "normalized units", None, 4, "skelscope", "coverage"),
    # the comparison with a reference curve (docs/metrics.md 5.3)
    ScoreColumn("reference_chamfer", "chamfer", "chamfer", "chamfer", "normalized units", "lower", 4, "reference"),
    ScoreColumn("reference_hausdorff", "Hausdorff", "Hausdorff", "Hausdorff", "normalized units", "lower", 4,
                "reference"),
    ScoreColumn("reference_precision", "precision", "P", "precision", "fraction", "higher", 3, "reference"),
    ScoreColumn("reference_recall", "recall", "R", "recall", "fraction", "higher", 3, "reference"),
    ScoreColumn("reference_f1", "F1", "F1", "$F_1$", "fraction", "higher", 3, "reference"),
    ScoreColumn("reference_tau", "reference tau", "tau", r"$\tau$", "normalized units", None, 4, "reference"),
    # the diagnostics (docs/diagnostics.md)
    *(ScoreColumn(f"completeness_{kind}", f"completeness ({kind})", f"compl. {kind[0]}", rf"compl.\ ${'P_s' if kind == 'skeletal' else 'G_s'}$",
                  "fraction of the cloud", "higher", 3, "diagnostics", "completeness", kind, compared=True)
      for kind in KINDS),
    ScoreColumn("spurious_branches", "spurious branches", "spurs", "spurs", "count", "lower", 1, "diagnostics",
                compared=True),
    ScoreColumn("spurious_length_share", "spurious length share", "spur len.", "spur len.", "fraction of the length",
                "lower", 3, "diagnostics"),
    ScoreColumn("spurious_cycles", "spurious cycles", "sp. cyc.", "sp. cycles", "count", "lower", 1, "diagnostics",
                compared=True),
    ScoreColumn("missing_cycles", "missing cycles", "miss. cyc.", "miss. cycles", "count", "lower", 1, "diagnostics",
                compared=True),
    ScoreColumn("outside_length_share", "length outside", "outside", "outside", "fraction of the length", "lower", 3,
                "diagnostics", compared=True),
    # facts of the run, lower is better in the leaderboard (1 decimal: means over jobs); "seconds" is the
    # evaluation's wall time in a Scores, the whole job's (skeletonize + evaluate) in compare's tables
    ScoreColumn("n_warnings", "warnings", "warn.", "warnings", "count", "lower", 1, "run", compared=True),
    ScoreColumn("seconds", "time (s)", "s", "time (s)", "s", "lower", 1, "run", compared=True),
)

#: column by key
COLUMN: dict[str, ScoreColumn] = {c.key: c for c in SCORE_COLUMNS}


def column_keys(*, group: str | Iterable[str] | None = None, compared: bool | None = None) -> tuple[str, ...]:
    """Keys of the columns of ``group`` (one or several) and/or with ``compared``, in catalogue order."""
    groups = None if group is None else ({group} if isinstance(group, str) else set(group))
    return tuple(c.key for c in SCORE_COLUMNS
                 if (groups is None or c.group in groups) and (compared is None or c.compared == compared))


def paired_columns(group: str = "paper") -> list[tuple[str, ScoreColumn, ScoreColumn]]:
    """(metric, skeletal column, curve column) of ``group``'s scores named ``{metric}_{kind}``: the rows
    of the paper's table (boundedness, centeredness, smoothness) or of SkelScope's (coverage)."""
    rows = []
    for c in SCORE_COLUMNS:
        if c.group == group and c.kind == KINDS[0] and c.key == f"{c.metric}_{c.kind}":
            rows.append((c.metric, c, COLUMN[f"{c.metric}_{KINDS[1]}"]))
    return rows


# ---- the record ---------------------------------------------------------------------------------

def _at(*path: str, default: Any = None, read: str = "float", needs: str | None = None) -> Any:
    """A field read from ``path`` of the ``evaluate --json`` document; ``needs`` the input (skeletal or
    curve) without which a null there means not computed rather than NaN."""
    return field(default=default, metadata={"path": path, "read": read, "needs": needs})


def _pk(metric: str, kind: str) -> Any:
    return _at(metric, kind, needs=kind)


def _n(metric: str, kind: str) -> Any:
    return _at("counts", metric, kind, default=0, read="int")


@dataclass(frozen=True, eq=False)
class Scores:
    """The overall scores of one evaluation; None = not computed, NaN = no valid element.

    Equality treats NaN as equal to NaN (a record read back equals the one written).
    """

    # docs/metrics.md 1: topological similarity of the skeletal point set
    d_B: float | None = _at("topology", "bottleneck")
    d_Wp: float | None = _at("topology", "wasserstein")
    eps_star: float | None = _at("topology", "eps_star")
    n_bars: int | None = _at("topology", "n_bars", read="int")
    # docs/metrics.md 2-4: fraction bounded, fraction centred, mean smoothness; with the elements counted
    boundedness_skeletal: float | None = _pk("boundedness", "skeletal")
    boundedness_curve: float | None = _pk("boundedness", "curve")
    centeredness_skeletal: float | None = _pk("centeredness", "skeletal")
    centeredness_curve: float | None = _pk("centeredness", "curve")
    smoothness_skeletal: float | None = _pk("smoothness", "skeletal")
    smoothness_curve: float | None = _pk("smoothness", "curve")
    n_boundedness_skeletal: int = _n("boundedness", "skeletal")
    n_boundedness_curve: int = _n("boundedness", "curve")
    n_centeredness_skeletal: int = _n("centeredness", "skeletal")
    n_centeredness_curve: int = _n("centeredness", "curve")
    n_smoothness_skeletal: int = _n("smoothness", "skeletal")
    n_smoothness_curve: int = _n("smoothness", "curve")
    # docs/metrics.md 5.2: coverage (SkelScope's own)
    coverage_skeletal: float | None = _at("coverage", "skeletal", "fraction")
    coverage_curve: float | None = _at("coverage", "curve", "fraction")
    coverage_skeletal_mean_gap: float | None = _at("coverage", "skeletal", "mean_gap")
    coverage_skeletal_max_gap: float | None = _at("coverage", "skeletal", "max_gap")
    coverage_curve_mean_gap: float | None = _at("coverage", "curve", "mean_gap")
    coverage_curve_max_gap: float | None = _at("coverage", "curve", "max_gap")
    coverage_slack: float | None = _at("coverage", "slack")
    coverage_tau: float | None = _at("coverage", "tau")
    # docs/metrics.md 5.3: the comparison with a reference curve; graph counts are (ours, reference)
    reference_chamfer: float | None = _at("reference", "chamfer")
    reference_hausdorff: float | None = _at("reference", "hausdorff")
    reference_precision: float | None = _at("reference", "precision")
    reference_recall: float | None = _at("reference", "recall")
    reference_f1: float | None = _at("reference", "f1")
    reference_tau: float | None = _at("reference", "tau")
    reference_junctions: tuple[int, int] | None = _at("reference", "junctions", read="pair")
    reference_endpoints: tuple[int, int] | None = _at("reference", "endpoints", read="pair")
    reference_components: tuple[int, int] | None = _at("reference", "components", read="pair")
    reference_cycles: tuple[int, int] | None = _at("reference", "cycles", read="pair")
    # the ground-truth metrics (docs/metrics.md 5.3.1); counts as (ours, reference[, matched])
    gt_chamfer_radii: float | None = _at("ground_truth", "chamfer_radii")
    gt_chamfer: float | None = _at("ground_truth", "chamfer")
    gt_precision: float | None = _at("ground_truth", "precision")
    gt_recall: float | None = _at("ground_truth", "recall")
    gt_f1: float | None = _at("ground_truth", "f1")
    # None without the reference's facts (the block's held_nodes null), NaN computed without a sample
    gt_held_precision: float | None = _at("ground_truth", "held_precision", read="held")
    gt_held_recall: float | None = _at("ground_truth", "held_recall", read="held")
    gt_held_f1: float | None = _at("ground_truth", "held_f1", read="held")
    gt_junction_precision: float | None = _at("ground_truth", "junction_precision")
    gt_junction_recall: float | None = _at("ground_truth", "junction_recall")
    gt_endpoint_precision: float | None = _at("ground_truth", "endpoint_precision")
    gt_endpoint_recall: float | None = _at("ground_truth", "endpoint_recall")
    gt_cycle_error: int | None = _at("ground_truth", "cycle_error", read="abs")
    gt_length_ratio: float | None = _at("ground_truth", "length_ratio")
    gt_splits: int | None = _at("ground_truth", "splits", read="int")
    gt_merges: int | None = _at("ground_truth", "merges", read="int")
    gt_junctions: tuple[int, ...] | None = _at("ground_truth", "junctions", read="tuple")
    gt_endpoints: tuple[int, ...] | None = _at("ground_truth", "endpoints", read="tuple")
    gt_cycles: tuple[int, ...] | None = _at("ground_truth", "cycles", read="tuple")
    gt_radius_source: str | None = _at("ground_truth", "radius_source", read="str")
    # the diagnostics (docs/diagnostics.md): share of the cloud explained, defects found
    completeness_skeletal: float | None = _at("diagnostics", "completeness", "skeletal", needs="skeletal")
    completeness_curve: float | None = _at("diagnostics", "completeness", "curve", needs="curve")
    spurious_branches: int | None = _at("diagnostics", "spurious_branches", "spurious", read="int")
    spurious_length_share: float | None = _at("diagnostics", "spurious_branches", "length_share", needs="curve")
    spurious_cycles: int | None = _at("diagnostics", "cycles", "spurious", read="int")
    missing_cycles: int | None = _at("diagnostics", "cycles", "missing", read="int")
    outside_length_share: float | None = _at("diagnostics", "outside", "length_share", needs="curve")
    # the run: trust warnings, evaluation wall time (s, to the microsecond), thresholds counted with
    n_warnings: int | None = _at("warnings", read="len")
    seconds: float | None = _at("timings_s", "total")
    beta_star: float | None = _at("params", "beta_star")
    c_star: float | None = _at("params", "c_star")

    # ---- construction -------------------------------------------------------------------------
    @classmethod
    def from_evaluation(cls, ev: Any, beta_star: float | None = None, c_star: float | None = None) -> "Scores":
        """The scores of a :class:`skelcore.evaluation.Evaluation`, counted with beta*, c* (default:
        its ``params``' thresholds, docs/metrics.md 2-3), as its ``summary`` gives them."""
        b_star = ev.params.beta_star if beta_star is None else float(beta_star)
        c_star_ = ev.params.c_star if c_star is None else float(c_star)
        doc = dict(ev.summary(b_star, c_star_))
        total = (ev.timings or {}).get("total")
        doc.update(reference=None if ev.reference is None else ev.reference.to_dict(),
                   ground_truth=None if ev.ground_truth is None else ev.ground_truth.to_dict(),
                   diagnostics=None if ev.diagnostics is None else ev.diagnostics.to_dict(),
                   warnings=list(ev.warnings), params={"beta_star": b_star, "c_star": c_star_},
                   timings_s={} if total is None else {"total": round(float(total), 6)})
        return cls._read(doc, lambda _field: None)

    @classmethod
    def from_json_dict(cls, doc: dict[str, Any]) -> "Scores":
        """The scores of an ``evaluate --json`` document (or of a ``summary()`` dict), as a compare
        job stored them. JSON has no NaN: a null score of an input the document lists (and that
        ``not_computed`` does not name) is NaN; without ``inputs`` a null stays None."""
        inputs = doc.get("inputs")
        skipped = set(doc.get("not_computed") or {})

        def null(meta: dict[str, Any]) -> float | None:
            kind, metric = meta["needs"], meta["path"][0]
            if kind is None:  # inside a block the document has: computed, NaN
                return math.nan
            if not isinstance(inputs, dict) or inputs.get(kind) is None:
                return None
            return None if {metric, f"{kind} {metric}"} & skipped else math.nan

        return cls._read(doc, null)

    @classmethod
    def _read(cls, doc: dict[str, Any], null: Callable[[dict[str, Any]], float | None]) -> "Scores":
        """Every field from its path; a missing block or key gives the field's default."""
        values: dict[str, Any] = {}
        for f in fields(cls):
            meta, path = f.metadata, f.metadata["path"]
            node: Any = doc
            for step in path[:-1]:
                node = node.get(step) if isinstance(node, dict) else None
            if not isinstance(node, dict) or (path[-1] not in node and meta["read"] != "len"):
                continue
            value = node.get(path[-1])
            if meta["read"] == "len":
                values[f.name] = len(value or [])
            elif value is None and meta["read"] == "held":  # computed (NaN) only when the facts were given
                values[f.name] = math.nan if node.get("held_nodes") is not None else None
            elif value is None:
                values[f.name] = null(meta) if meta["read"] == "float" else None
            elif meta["read"] == "int":
                values[f.name] = int(value)
            elif meta["read"] == "pair":
                values[f.name] = (int(value[0]), int(value[1]))
            elif meta["read"] == "tuple":
                values[f.name] = tuple(int(x) for x in value)
            elif meta["read"] == "abs":
                values[f.name] = abs(int(value))
            elif meta["read"] == "str":
                values[f.name] = str(value)
            else:
                values[f.name] = _number(value)
        return cls(**values)

    # ---- reading ------------------------------------------------------------------------------
    def get(self, key: str) -> Any:
        return getattr(self, key)

    def row(self) -> tuple[Any, ...]:
        """The values of :data:`SCORE_COLUMNS`, in their order."""
        return tuple(getattr(self, c.key) for c in SCORE_COLUMNS)

    def flat(self, keys: Iterable[str] | None = None) -> dict[str, float]:
        """{column: float} with None as NaN (the form compare's job records and results.csv hold)."""
        keys = [c.key for c in SCORE_COLUMNS] if keys is None else keys
        return {k: math.nan if getattr(self, k) is None else float(getattr(self, k)) for k in keys}

    def text(self, key: str, **kw: Any) -> str:
        """One score formatted with its column's digits (``format_score``'s options)."""
        return COLUMN[key].format(getattr(self, key), **kw)

    def cell(self, key: str, *, missing: str = "-", sep: str = " ", count: str = "n={}") -> str:
        """A table cell: the score, then the count it was made of or its column's detail in brackets."""
        col = COLUMN[key]
        value = getattr(self, key)
        if value is None:
            return missing
        text = col.format(value)
        if col.count:
            return f"{text}{sep}({count.format(getattr(self, col.count))})"
        if col.detail:
            detail = col.detail.format_map(_Formatted(self))
            return f"{text}{sep}({detail})"
        return text

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Scores):
            return NotImplemented
        return all(_same(a, b) for a, b in zip(_values(self), _values(other)))

    def __hash__(self) -> int:
        return hash(tuple("nan" if isinstance(v, float) and math.isnan(v) else v for v in _values(self)))


def paper_table(scores: Scores | None, *, missing: str = "-", sep: str = " ", count: str = "n={}",
                every_row: bool = True) -> list[tuple[str, str, str]]:
    """The paper's results table (docs/metrics.md 5.5): (row, skeletal points cell, curve skeleton cell) for
    d_B / d_Wp, each per-representation score with its count, then SkelScope's rows marked "*"
    (without ``every_row``, only those with a value)."""
    s = scores if scores is not None else Scores()
    topo = missing if s.d_B is None else f"{s.text('d_B')} / {s.text('d_Wp')}"
    rows = [("d_B / d_Wp", topo, missing)]
    for group, mark in (("paper", ""), ("skelscope", "*")):
        for metric, sk, cv in paired_columns(group):
            if every_row or mark == "" or s.get(sk.key) is not None or s.get(cv.key) is not None:
                rows.append((metric + mark, *(s.cell(c.key, missing=missing, sep=sep, count=count) for c in (sk, cv))))
    return rows


class _Formatted(dict):
    """``str.format_map`` source: each field formatted with its column's digits."""

    def __init__(self, scores: Scores) -> None:
        super().__init__()
        self.scores = scores

    def __missing__(self, key: str) -> str:
        return self.scores.text(key)


def _number(v: Any) -> float:
    """A score as JSON holds it: a number, or "inf" / "-inf" (NaN for any other text)."""
    if isinstance(v, str):
        return {"inf": math.inf, "-inf": -math.inf}.get(v, math.nan)
    return float(v)


def _values(s: Scores) -> tuple[Any, ...]:
    return tuple(getattr(s, f.name) for f in fields(s))


def _same(a: Any, b: Any) -> bool:
    nan = lambda v: isinstance(v, float) and math.isnan(v)  # noqa: E731
    return (nan(a) and nan(b)) or (not nan(a) and not nan(b) and a == b)
