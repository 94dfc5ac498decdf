"""All of a curve skeleton's defects at once: one KD-tree of the cloud
and one branch decomposition shared by the spurious-branch, cycle, outside, disconnected and
along-the-surface diagnostics, and the branches flagged with what each found (docs/diagnostics.md)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..metrics.curve_sampling import CurveSamples
from ..geometry import Checkpoint, kd_tree, no_checkpoint
from ..params import Params
from .trust_warning import TrustWarning
from .branches import Branches, decompose_branches
from .pieces import CurveComponents, find_components
from .cycles import CycleDefects, find_cycle_defects
from .interior import VoxelShape, cloud_subsample, voxelize_interior
from .outside import OutsideDefects, find_outside
from .spur_cache import SpurMemo
from .spurs import SpurDefects, find_spurious_branches
from .surface import SurfaceRuns, find_along_surface

__all__ = ["CurveDefects", "find_curve_defects"]


@dataclass
class CurveDefects:
    """The branches (flagged ``spurious_branches``, ``spurious_cycles``, ``outside``,
    ``disconnected``, ``along_surface``) and each diagnostic's result; per-element defect flags by code."""

    branches: Branches
    spurs: SpurDefects
    cycles: CycleDefects
    outside: OutsideDefects
    timings: dict
    components: CurveComponents = field(default_factory=CurveComponents)
    surface: SurfaceRuns = field(default_factory=SurfaceRuns)

    def warnings(self) -> list[TrustWarning]:
        return (self.spurs.warnings() + self.cycles.warnings() + self.outside.warnings() + self.components.warnings()
                + self.surface.warnings())

    def vertex_flags(self) -> dict[str, np.ndarray]:
        return {"spurious_branches": self.spurs.vertex_flag, "spurious_cycles": self.cycles.vertex_flag,
                "outside": self.outside.vertex_flag, "disconnected": self.components.vertex_flag,
                "along_surface": self.surface.vertex_flag}

    def sample_flags(self) -> dict[str, np.ndarray | None]:
        return {"spurious_branches": self.spurs.sample_flag, "spurious_cycles": self.cycles.sample_flag,
                "outside": self.outside.sample_outside, "disconnected": self._sample_disconnected(),
                "along_surface": self.surface.sample_flag(self.branches.sample_branch)}

    def _sample_disconnected(self) -> np.ndarray | None:
        sb = self.branches.sample_branch
        return None if sb is None else np.isin(sb, self.components.extra_branches)

    def edge_flags(self) -> dict[str, np.ndarray]:
        """Per curve edge: on a spurious branch, on a spurious cycle's branch, with length outside, on
        a piece beyond one per cloud piece (what report.html draws in each defect's colour)."""
        eb = np.asarray(self.branches.edge_branch, dtype=np.int64)
        return {"spurious_branches": np.isin(eb, self.spurs.spurious),
                "spurious_cycles": np.asarray(self.cycles.branch_spurious, bool)[eb] if len(eb) else np.zeros(0, bool),
                "outside": (np.asarray(self.outside.edge_outside_length) > 0)
                | np.isin(eb, self.outside.far_branches()),
                "disconnected": np.isin(eb, self.components.extra_branches),
                "along_surface": np.isin(eb, self.surface.flagged)}

    def to_dict(self) -> dict:
        return {
            "branches": self.branches.to_dict(),
            "spurious_branches": self.spurs.to_dict(),
            "cycles": self.cycles.to_dict(),
            "outside": self.outside.to_dict(),
            "components": self.components.to_dict(),
            "along_surface": self.surface.to_dict(),
            "warnings": [w.to_dict() for w in self.warnings()],
        }


def find_curve_defects(
    cloud: np.ndarray,
    curve: CurveSkeleton,
    *,
    samples: CurveSamples | None = None,
    sample_boundedness: np.ndarray | None = None,
    sample_centeredness: np.ndarray | None = None,
    skeletal: np.ndarray | None = None,
    skeletal_boundedness: np.ndarray | None = None,
    params: Params = Params(),
    checkpoint: Checkpoint = no_checkpoint,
    interior: Callable[[Checkpoint], VoxelShape] | None = None,
    cloud_tree: cKDTree | None = None,
    spur_memo: SpurMemo | None = None,
) -> CurveDefects:
    """Branches, spurious branches, cycles, the parts outside of ``curve`` (and of ``skeletal``) and
    its pieces beyond one per piece of the cloud (:mod:`.pieces`) and its branches along the surface
    (:mod:`.surface`), all normalized (docs/metrics.md 0); ``sample_boundedness`` and
    ``sample_centeredness`` (raw, Eq. 11) are the values of ``samples`` the evaluation computed. The
    local radii come from at most ``diag_max_points`` of the cloud (``spurs.subsampled`` says when).
    ``interior(checkpoint)`` gives the cloud's voxelized interior when it is shared (the evaluation's
    stages make it once); default :func:`.interior.voxelize_interior` with ``params``. ``cloud_tree``: the
    KD-tree of ``cloud_subsample(cloud, params.diag_max_points)`` when kept (an edit's update);
    ``spur_memo``: the spur test's search kept from an earlier curve (:mod:`.spur_cache`)."""
    import time

    t: dict[str, float] = {}
    t0 = time.perf_counter()
    cloud = np.asarray(cloud, dtype=float)
    # the local radii from at most diag_max_points of the cloud (a 1M-point tree costs 1-2 s; the
    # radii grow by about the subsample's spacing, a few % of a radius)
    tree = cloud_tree if cloud_tree is not None else kd_tree(cloud_subsample(cloud, params.diag_max_points),
                                                             lambda f: checkpoint(0.05 * f))
    branches = decompose_branches(curve, cloud=cloud, sample_edge=None if samples is None else samples.edge,
                                  cloud_tree=tree, checkpoint=lambda f: checkpoint(0.05 + 0.05 * f))
    t["branches"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    if interior is None:
        def interior(check: Checkpoint) -> VoxelShape:
            return voxelize_interior(cloud, voxels=params.cycles_voxels, min_spacing_factor=params.cycles_voxel_spacing,
                                     inside_share=params.beta_star, checkpoint=check)
    shape = interior(lambda f: checkpoint(0.1 + 0.1 * f))
    t["interior"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    spurs = find_spurious_branches(cloud, curve, params=params, branches=branches, cloud_tree=tree,
                                   checkpoint=lambda f: checkpoint(0.2 + 0.3 * f), search_memo=spur_memo,
                                   voxel_shape=shape)
    t["spurs"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    cycles = find_cycle_defects(cloud, curve, params=params, branches=branches, cloud_tree=tree, voxel_shape=shape,
                                checkpoint=lambda f: checkpoint(0.5 + 0.4 * f))
    t["cycles"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    outside = find_outside(cloud, curve, samples=samples, sample_boundedness=sample_boundedness, skeletal=skeletal,
                           skeletal_boundedness=skeletal_boundedness, params=params, branches=branches,
                           cloud_tree=tree, voxel_shape=shape, checkpoint=lambda f: checkpoint(0.9 + 0.1 * f))
    t["outside"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    components = find_components(curve, branches, tree, params)
    t["components"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    surface = find_along_surface(curve, branches, samples, sample_centeredness, sample_boundedness, tree,
                                 outside.radius, params)
    t["along_surface"] = time.perf_counter() - t0
    flagged = branches.flagged("spurious_branches", spurs.spurious)
    flagged = flagged.flagged("spurious_cycles", np.flatnonzero(cycles.branch_spurious))
    flagged = flagged.flagged("outside", outside.defective_branches())
    flagged = flagged.flagged("disconnected", components.extra_branches)
    flagged = flagged.flagged("along_surface", surface.flagged)
    return CurveDefects(branches=flagged, spurs=spurs, cycles=cycles, outside=outside, timings=t,
                        components=components, surface=surface)
