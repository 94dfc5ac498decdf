"""Proofreading a curve skeleton: pure edits of a :class:`~skelcore.curve.CurveSkeleton`, each returning
``(new_curve, change)`` (a :class:`Change` record: what went, what came, the id map), and the edit
log that replays them (docs/guide/editing.md). The Evaluation of an edited curve:
:meth:`skelcore.Evaluation.update` (:mod:`skelcore.edit.incremental`)."""

from .branch_ops import delete_branch, prune_branch
from .change import Change, content_hash
from .edge_ops import add_edge, cut_cycle, delete_edge, split_edge
from .edit_log import FORMAT, OPERATIONS, apply, new_log, read_log, replay, write_log
from .vertex_ops import add_vertex, delete_vertex, merge_vertices, move_vertex

__all__ = ["Change", "content_hash", "delete_vertex", "delete_edge", "delete_branch", "prune_branch", "add_vertex",
           "add_edge", "split_edge", "merge_vertices", "move_vertex", "cut_cycle", "FORMAT", "OPERATIONS",
           "new_log", "apply", "replay", "write_log", "read_log"]
