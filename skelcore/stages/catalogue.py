"""The stages of an evaluation, declared once: each names its weight (relative cost, for a
progress bar that moves evenly; measured on 4k-point shapes), the column it fills, what it reads from
the context (the stage that makes an input runs before it), when it applies and its function.

The paper's four metrics on the skeletal set and the curve (docs/metrics.md 1-4), the reverse correspondence,
SkelScope's coverage, the reference comparison and the ground-truth metrics (docs/metrics.md), the diagnostics.  Start order (docs/performance.md
8): the boundedness stages first (the longest), then what others wait for, then the rest in catalogue
order; the skeletal set's boundedness waits for the curve's, so that one lane runs both kernels while
the other runs the Python stages (curve defects among them, not after them); topology follows
skeletal centeredness on a large skeletal set, whose neighbours its EMST takes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..correspondence import project_onto_curve, reverse_projection
from ..geometry import Checkpoint
from ..metrics.centeredness import curve_centeredness, skeletal_centeredness
from ..metrics.coverage import coverage, curve_elements
from ..metrics.ground_truth import ground_truth
from ..metrics.reference import compare_with_reference
from ..metrics.smoothness import curve_smoothness_overall, curve_vertex_smoothness, skeletal_smoothness
from ..metrics.topology import topological_similarity
from ..diagnostics.defects import find_curve_defects
from ..diagnostics.missing_parts import missing_parts
from ..diagnostics.outside import find_outside
from ..scan.prepare import find_strays
from .context import EvalContext

__all__ = ["Stage", "CATALOGUE", "select", "start_order", "FIRST", "EARLY", "IN_TURN", "LAST"]

#: start groups (list scheduling: the longest first so that the other thread takes the rest beside it)
FIRST, EARLY, IN_TURN, LAST = range(4)
# from this many skeletal points topology waits for centeredness' neighbours (its EMST's first round);
# on smaller sets the lists save the EMST nothing measurable (hammer: 11.6 -> 11.5 CPU ms), so it
# does not wait
_EMST_LISTS_FROM = 65536


@dataclass(frozen=True)
class Stage:
    """One stage: ``fn(ctx, checkpoint)`` returns its result, stored as ``ctx.results[name]``."""

    name: str
    weight: float
    column: str  # "skeletal" | "curve" | "" (coverage, reference: after both columns)
    inputs: tuple[str, ...]  # context items it reads (context.CONTEXT_ITEMS)
    applies: Callable[[EvalContext], bool]
    fn: Callable[[EvalContext, Checkpoint], object]
    start: int | Callable[[EvalContext], int] = IN_TURN  # start group, or a function of the context
    follows: Callable[[EvalContext], tuple[str, ...]] | None = None  # stages it starts after (not inputs)

    def start_group(self, ctx: EvalContext) -> int:
        return self.start(ctx) if callable(self.start) else self.start

    def after(self, ctx: EvalContext) -> tuple[str, ...]:
        """The stages that make its inputs in this evaluation."""
        return tuple(dict.fromkeys(s for s in map(ctx.made_by, self.inputs) if s is not None))

    def waits(self, ctx: EvalContext) -> tuple[str, ...]:
        """The stages it starts after: those that make its inputs, then those it follows by schedule."""
        return tuple(dict.fromkeys(self.after(ctx) + (self.follows(ctx) if self.follows else ())))


# ---- the stages' functions --------------------------------------------------------------------

def _correspondence(ctx: EvalContext, checkpoint: Checkpoint) -> np.ndarray:
    """Reverse correspondence: each cloud row's nearest skeletal row, or its projection onto the curve."""
    if ctx.from_curve:
        return project_onto_curve(ctx.cloud_n, ctx.curve_n)[0]
    return reverse_projection(ctx.cloud_n, ctx.skeletal_n)


def _topology(ctx: EvalContext, checkpoint: Checkpoint):
    pointwise = ctx.skeletal_points()[ctx.rows()] if ctx.skeletal_mode == "reverse" else ctx.skeletal_points()
    return topological_similarity(ctx.cloud_n, pointwise, params=ctx.params, checkpoint=checkpoint,
                                  cloud_spacings=ctx.cloud_index.offer_spacings)


def _skeletal_boundedness(ctx: EvalContext, checkpoint: Checkpoint) -> np.ndarray:
    return ctx.boundedness(ctx.skeletal_points(), checkpoint, unseen="skeletal")


def _skeletal_centeredness(ctx: EvalContext, checkpoint: Checkpoint) -> np.ndarray:
    """Per skeletal point, or per cloud row under reverse correspondence (aggregated by the assembly)."""
    if ctx.skeletal_mode == "reverse":
        return skeletal_centeredness(ctx.cloud_n, ctx.skeletal_points()[ctx.rows()], params=ctx.params,
                                     depth=ctx.depth(ctx.skeletal_points(), ctx.rows()), checkpoint=checkpoint)
    corr_cloud = ctx.cloud_n if ctx.index is None else ctx.cloud_n[ctx.index]
    return skeletal_centeredness(corr_cloud, ctx.skeletal_points(), params=ctx.params,
                                 depth=ctx.depth(ctx.skeletal_points()), checkpoint=checkpoint)


def _skeletal_smoothness(ctx: EvalContext, checkpoint: Checkpoint) -> np.ndarray:
    return skeletal_smoothness(ctx.skeletal_points(), params=ctx.params, checkpoint=checkpoint)


def _curve_boundedness(ctx: EvalContext, checkpoint: Checkpoint) -> np.ndarray:
    # the samples' hint tables kept for an update's moved samples (docs/boundedness.md 3.18)
    ctx.ray_hints.clear()
    return ctx.boundedness(ctx.samples.points, checkpoint, keep=ctx.ray_hints)


def _curve_centeredness(ctx: EvalContext, checkpoint: Checkpoint) -> np.ndarray:
    return curve_centeredness(ctx.cloud_n, ctx.samples.points, ctx.samples.directions, params=ctx.params,
                              checkpoint=checkpoint)


def _curve_smoothness(ctx: EvalContext, checkpoint: Checkpoint) -> tuple:
    """(per-vertex smoothness, (overall, count))."""
    s = curve_vertex_smoothness(ctx.curve_n)
    return s, curve_smoothness_overall(ctx.curve_n, s)


def _skeletal_coverage(ctx: EvalContext, checkpoint: Checkpoint):
    tau = ctx.tau(lambda f: checkpoint(0.1 * f))
    return coverage(ctx.cloud_n, ctx.skeletal_n, ctx.params, tau, checkpoint=lambda f: checkpoint(0.1 + 0.9 * f),
                    index=ctx.cloud_index)


def _curve_coverage(ctx: EvalContext, checkpoint: Checkpoint):
    """The curve's coverage elements (:func:`curve_elements`) against the cloud."""
    tau = ctx.tau(lambda f: checkpoint(0.1 * f))
    return coverage(ctx.cloud_n, curve_elements(ctx.curve_n, tau, ctx.params), ctx.params, tau,
                    checkpoint=lambda f: checkpoint(0.1 + 0.9 * f), index=ctx.cloud_index)


def _reference(ctx: EvalContext, checkpoint: Checkpoint):
    return compare_with_reference(ctx.curve_n, ctx.reference_n, ctx.tau(checkpoint))


def _ground_truth(ctx: EvalContext, checkpoint: Checkpoint):
    """The community's metrics against the reference, in the user's units (docs/metrics.md 5.3.1)."""
    return ground_truth(ctx.curve, ctx.reference, ctx.cloud, ctx.params, outside_radii=ctx.reference_outside)


def _curve_defects(ctx: EvalContext, checkpoint: Checkpoint):
    """Branches, spurious branches, cycles, the parts outside, the branches along the surface (docs/diagnostics.md)."""
    return find_curve_defects(ctx.cloud_n, ctx.curve_n, samples=ctx.samples,
                              sample_boundedness=ctx.results["curve boundedness"],
                              sample_centeredness=ctx.results.get("curve centeredness"), params=ctx.params,
                              checkpoint=checkpoint, interior=ctx.interior,
                              cloud_tree=ctx.diag_tree(lambda f: checkpoint(0.05 * f)), spur_memo=ctx.spur_memo)


def _skeletal_outside(ctx: EvalContext, checkpoint: Checkpoint):
    """The given skeletal set's points outside the shape, clustered (docs/diagnostics.md "Outside")."""
    return find_outside(ctx.cloud_n, None, skeletal=ctx.skeletal_n,
                        skeletal_boundedness=ctx.results["skeletal boundedness"], params=ctx.params,
                        voxel_shape=ctx.interior(lambda f: checkpoint(0.5 * f)),
                        checkpoint=lambda f: checkpoint(0.5 + 0.5 * f))


def _stray_points(ctx: EvalContext, checkpoint: Checkpoint):
    """The cloud's stray points and, in pointwise correspondence, the skeletal set's isolated points
    (docs/metrics.md 6.4): a stage beside the others, not a serial tail after them (docs/performance.md 6.6)."""
    return find_strays(ctx.cloud, ctx.skeletal, ctx.params, pointwise=ctx.mode == "pointwise", checkpoint=checkpoint)


def _missing(kind: str) -> Callable[[EvalContext, Checkpoint], object]:
    """Missing parts and completeness of one column (docs/diagnostics.md), from its coverage when computed."""
    def run(ctx: EvalContext, checkpoint: Checkpoint):
        skeleton = ctx.skeletal_n if kind == "skeletal" else ctx.curve_n
        cov = ctx.results.get(f"{kind} coverage")
        what = "skeletal point set" if kind == "skeletal" else "curve skeleton"
        return missing_parts(ctx.cloud_n, skeleton, ctx.params, cov=cov, tau=None if cov is None else cov.tau,
                             what=what, to_user=ctx.norm.invert, inside=ctx.solid_test(), chords=ctx.chords,
                             checkpoint=checkpoint)

    return run


# ---- when they apply ----------------------------------------------------------------------------

def _reverse(ctx: EvalContext) -> bool:
    return ctx.mode == "reverse"


def _skeletal(ctx: EvalContext) -> bool:
    return ctx.has_skeletal_column


def _skeletal_corresponded(ctx: EvalContext) -> bool:
    return ctx.has_skeletal_column and ctx.skeletal_mode != "none"


def _curve(ctx: EvalContext) -> bool:
    return ctx.curve is not None


def _skeletal_set_coverage(ctx: EvalContext) -> bool:
    """Coverage of the given skeletal set only (not of the curve's projections)."""
    return ctx.skeletal is not None and ctx.with_coverage


def _curve_coverage_applies(ctx: EvalContext) -> bool:
    return ctx.curve is not None and ctx.with_coverage


def _skeletal_set(ctx: EvalContext) -> bool:
    return ctx.skeletal is not None


def _reference_given(ctx: EvalContext) -> bool:
    return ctx.reference_n is not None


def _ground_truth_given(ctx: EvalContext) -> bool:
    return ctx.reference is not None and ctx.curve is not None and ctx.reference.n_edges > 0


def _strays_not_yet_found(ctx: EvalContext) -> bool:
    """``remove_outliers`` found them while building the context."""
    return ctx.scan is None or not ctx.scan.outliers_removed


def _after_the_curves(ctx: EvalContext) -> int:
    return FIRST if ctx.curve is None else EARLY


def _the_curves_kernel_first(ctx: EvalContext) -> tuple[str, ...]:
    # one lane runs the curve's kernel (a quarter of the skeletal one on the hammer), then the skeletal
    # set's, each on the cores the other lane's Python stages leave free (parallel.Cores) and on both
    # once those are done; started side by side they held both lanes while the Python stages waited,
    # and the curve's started last left curve defects (which reads it) alone at the end
    return ("curve boundedness",) if ctx.curve is not None else ()


def _the_shared_neighbours_first(ctx: EvalContext) -> tuple[str, ...]:
    # a large skeletal set's EMST takes its first round from the k nearest positions that centeredness
    # publishes (metrics/position_knn.py): about 1.2 CPU s less at 1M points (docs/performance.md 6.1)
    if ctx.from_curve or ctx.skeletal_mode != "pointwise" or ctx.skeletal_n is None:
        return ()
    return ("skeletal centeredness",) if len(ctx.skeletal_n) >= _EMST_LISTS_FROM else ()


CATALOGUE: tuple[Stage, ...] = (
    Stage("correspondence", weight=0.3, column="skeletal", inputs=("cloud", "skeletal set", "curve"), applies=_reverse,
          fn=_correspondence, start=EARLY),
    Stage("topology", weight=1.0, column="skeletal", inputs=("cloud", "skeletal points", "rows"),
          applies=_skeletal_corresponded, fn=_topology, follows=_the_shared_neighbours_first),
    Stage("skeletal boundedness", weight=4.0, column="skeletal", inputs=("cloud", "skeletal points"), applies=_skeletal,
          fn=_skeletal_boundedness, start=_after_the_curves, follows=_the_curves_kernel_first),
    Stage("skeletal centeredness", weight=0.5, column="skeletal",
          inputs=("cloud", "skeletal points", "rows", "index", "unseen"),
          applies=_skeletal_corresponded, fn=_skeletal_centeredness),
    Stage("skeletal smoothness", weight=0.5, column="skeletal", inputs=("skeletal points",), applies=_skeletal,
          fn=_skeletal_smoothness),
    Stage("curve boundedness", weight=1.0, column="curve", inputs=("cloud", "samples"), applies=_curve,
          fn=_curve_boundedness, start=FIRST),
    Stage("curve centeredness", weight=1.0, column="curve", inputs=("cloud", "samples"), applies=_curve,
          fn=_curve_centeredness),
    Stage("curve smoothness", weight=0.1, column="curve", inputs=("curve",), applies=_curve, fn=_curve_smoothness),
    Stage("skeletal coverage", weight=0.3, column="", inputs=("cloud", "skeletal set", "tau"),
          applies=_skeletal_set_coverage, fn=_skeletal_coverage),
    Stage("curve coverage", weight=0.3, column="", inputs=("cloud", "curve", "tau"), applies=_curve_coverage_applies,
          fn=_curve_coverage),
    Stage("reference", weight=0.1, column="", inputs=("curve", "reference", "tau"), applies=_reference_given,
          fn=_reference),
    Stage("ground truth", weight=0.3, column="", inputs=("cloud", "curve", "reference"), applies=_ground_truth_given,
          fn=_ground_truth),
    Stage("stray points", weight=0.1, column="", inputs=("cloud", "skeletal set"), applies=_strays_not_yet_found,
          fn=_stray_points),
    Stage("curve defects", weight=0.5, column="",
          inputs=("cloud", "curve", "samples", "curve boundedness", "curve centeredness"),
          applies=_curve, fn=_curve_defects, start=LAST),
    Stage("skeletal outside", weight=0.1, column="", inputs=("cloud", "skeletal set", "skeletal boundedness"),
          applies=_skeletal_set, fn=_skeletal_outside, start=LAST),
    Stage("skeletal missing parts", weight=0.2, column="", inputs=("cloud", "skeletal set", "skeletal coverage"),
          applies=_skeletal_set, fn=_missing("skeletal"), start=LAST),
    Stage("curve missing parts", weight=0.2, column="", inputs=("cloud", "curve", "curve coverage"), applies=_curve,
          fn=_missing("curve"), start=LAST),
)


def select(ctx: EvalContext) -> list[Stage]:
    """The stages that apply, in catalogue order; the curve's column first when the skeletal column is
    made from it (this order sums the progress)."""
    columns = ("curve", "skeletal", "") if ctx.from_curve else ("skeletal", "curve", "")
    return sorted((s for s in CATALOGUE if s.applies(ctx)), key=lambda s: columns.index(s.column))


def start_order(stages: list[Stage], ctx: EvalContext) -> list[Stage]:
    """The order they are started in (:func:`skelcore.parallel.run_graph` takes the first ready one;
    with one worker, the order they run in)."""
    return sorted(stages, key=lambda s: s.start_group(ctx))
