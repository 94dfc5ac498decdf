"""A fill's outside test at its first look (docs/repair.md "The repair's cost"): the edited curve's
branches and their length outside the shape, the same functions on the same inputs as the whole
update's ``curve defects`` stage (:func:`skelcore.diagnostics.defects.find_curve_defects`:
:func:`~skelcore.diagnostics.branches.decompose_branches`, then
:func:`~skelcore.diagnostics.outside.find_outside`), so the same outside tally and length share,
without the spur and cycle tests, the dear part of an update at 100k points. A fill that adds an
outside branch is refused by the rule whatever the rest ("Fills that pass"), so it is refused here."""

from __future__ import annotations

import numpy as np

from ..diagnostics.branches import decompose_branches
from ..diagnostics.outside import OutsideDefects, find_outside
from ..evaluation import Evaluation

__all__ = ["outside_of", "outside_named"]


def outside_of(pre: Evaluation) -> OutsideDefects | None:
    """The outside test of ``pre`` (an ``update(..., diagnostics=False)``) as its whole update's
    ``curve defects`` stage runs it; None when ``pre`` keeps no context or no curve boundedness."""
    ctx = getattr(pre.source, "ctx", None)
    if ctx is None or ctx.curve_n is None or ctx.samples is None or "curve boundedness" not in ctx.results:
        return None
    tree = ctx.diag_tree()
    branches = decompose_branches(ctx.curve_n, cloud=ctx.cloud_n, sample_edge=ctx.samples.edge, cloud_tree=tree)
    return find_outside(ctx.cloud_n, ctx.curve_n, samples=ctx.samples,
                        sample_boundedness=ctx.results["curve boundedness"], params=ctx.params,
                        branches=branches, cloud_tree=tree, voxel_shape=ctx.interior())


def outside_named(out: OutsideDefects, new_edges: np.ndarray) -> str:
    """The outside branches of ``out`` that hold one of the edge ids ``new_edges`` (the fill's own; all of
    them when none does), each with its reach and, when the length test ran (``length_test``: voxels fine
    enough), its length outside, in local radii (docs/diagnostics.md "Outside")."""
    bad = out.defective_branches()
    eb = np.asarray(out.branches.edge_branch, np.int64) if out.branches is not None else np.zeros(0, np.int64)
    own = np.intersect1d(bad, eb[np.asarray(new_edges, np.int64)]) if len(eb) else np.zeros(0, np.int64)
    which, whose = (own, "the fill's") if len(own) else (bad, "the curve's")
    reach = out.reach if len(out.reach) else np.zeros(len(out.branch_outside_length))

    def one(b: int) -> str:
        length = f"{out.branch_radii[b]:.2g} local radii of length outside, " if out.length_test else ""
        return f"branch {b} ({length}reaching {reach[b]:.2g} local radii out)"

    named = ", ".join(one(int(b)) for b in which)
    return f"{whose} outside {'branch' if len(which) == 1 else 'branches'}: {named}"
