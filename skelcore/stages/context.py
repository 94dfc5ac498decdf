"""What the stages of an evaluation share: the checked and normalized inputs, the curve's
samples, which correspondence the skeletal column has, what cannot be computed and why, tau, and each
stage's result as soon as it is done.  :func:`build_context` checks the inputs (one-line
:class:`SkelInputError`) and makes the decisions once, so the stages only read them.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..curve import CurveSkeleton
from ..metrics.curve_sampling import CurveSamples, sample_curve
from ..diagnostics.chord_cache import ChordCache
from ..diagnostics.spur_cache import SpurMemo
from ..errors import SkelInputError
from ..geometry import Checkpoint, Normalization, as_points, check_extent, check_magnitude, no_checkpoint
from ..metrics.boundedness import boundedness, rays_radius
from ..metrics.cloud_index import CloudIndex
from ..metrics.coverage import coverage_tau
from ..params import Params
from ..scan.capping import cap_openings
from ..scan.density import density_fill
from ..scan.openings import Opening, find_openings
from ..scan.prepare import without_strays
from ..scan.scan_report import ScanReport
from ..scan.viewpoint import check_viewpoints, depth_axes, seen_boundedness

__all__ = ["EvalContext", "build_context", "CORRESPONDENCE_CHOICES", "CONTEXT_ITEMS"]

#: ``correspondence=`` choices of :func:`skelcore.evaluate`
CORRESPONDENCE_CHOICES = ("auto", "reverse")

#: What a stage may read from the context (its ``inputs``): "skeletal set" is the one given, "skeletal
#: points" the one the skeletal column scores (the curve's projections, made by the correspondence stage,
#: when no set is given), "rows" the reverse correspondence (made by that stage too), "unseen" what the
#: skeletal boundedness stage found behind the skeletal points with viewpoints (docs/metrics.md 6.3).
CONTEXT_ITEMS = ("cloud", "skeletal set", "skeletal points", "rows", "index", "curve", "samples", "reference", "tau",
                 "unseen", "curve boundedness", "curve centeredness", "skeletal boundedness", "skeletal coverage",
                 "curve coverage")
#: items that are other stages' results (the diagnostics read them), made by the stage of that name
#: when it runs in this evaluation (the coverage stages only below coverage_max_points)
STAGE_RESULTS = ("curve boundedness", "curve centeredness", "skeletal boundedness", "skeletal coverage", "curve coverage")


@dataclass
class EvalContext:
    """Inputs in the user's units and normalized (``_n``, docs/metrics.md 0), the decisions made from them, and
    ``results``: each stage's result by stage name (written by the orchestrator as a stage ends)."""

    params: Params
    cloud: np.ndarray
    norm: Normalization
    cloud_n: np.ndarray
    #: the skeletal column's correspondence (``Evaluation.correspondence``): "pointwise" | "index" |
    #: "reverse" | "none", None without a skeletal column
    mode: str | None
    skeletal: np.ndarray | None = None
    skeletal_n: np.ndarray | None = None
    index: np.ndarray | None = None
    curve: CurveSkeleton | None = None
    curve_n: CurveSkeleton | None = None
    samples: CurveSamples | None = None
    reference_n: CurveSkeleton | None = None
    #: the reference in the user's units, with its radius (given, else its file's; NaN = unknown)
    reference: CurveSkeleton | None = None
    #: per reference vertex, how far it lies outside the cloud's surface in its radii (the held scores)
    reference_outside: np.ndarray | None = None
    #: SkelScope's coverage is exact and grows about as N^1.4 on tubes: only up to coverage_max_points
    with_coverage: bool = True
    not_computed: dict[str, str] = field(default_factory=dict)
    results: dict[str, Any] = field(default_factory=dict)
    #: real scans (docs/metrics.md 6): the sensors' positions, normalized; the cloud boundedness casts
    #: against (the normalized cloud, plus the caps of --cap-openings); the openings when looked for
    #: (user units, rows of ``cloud``); what the scan report will say (None: no scan option given)
    viewpoints_n: np.ndarray | None = None
    capped_cloud_n: np.ndarray | None = None
    #: the params boundedness runs with: ``params``, or with density-aware filling the rays' radius
    #: factor that keeps h = rays_radius_factor x the scanned cloud's own median spacing
    bounded_params: Params | None = None
    openings: list[Opening] | None = None
    scan: ScanReport | None = None
    unseen: dict[str, np.ndarray] = field(default_factory=dict)
    #: the normalized cloud's search structures the stages share (coverage's trees, the spacings)
    cloud_index: CloudIndex | None = field(default=None, repr=False)
    _interior: list = field(default_factory=list, repr=False)
    _interior_lock: threading.Lock = field(default_factory=threading.Lock, repr=False)
    _diag_tree: list = field(default_factory=list, repr=False)
    _diag_tree_lock: threading.Lock = field(default_factory=threading.Lock, repr=False)
    _cloud_box: dict = field(default_factory=dict, repr=False)
    #: the spur test's search of this curve, and of the curve an update started from (its next update
    #: asks again only what the edit can change: skelcore.diagnostics.spur_cache)
    spur_memo: SpurMemo = field(default_factory=SpurMemo, repr=False)
    #: the far rays' hint tables the curve samples' boundedness left (skelcore.metrics.ray_hints; one
    #: entry or none): an update's moved samples start their rays from them (docs/boundedness.md 3.18)
    ray_hints: list = field(default_factory=list, repr=False)
    #: the openings' boundary test of the cloud and each rim's opening, shared along the updates
    #: (skelcore.scan.openings.find_openings)
    openings_memo: dict = field(default_factory=dict, repr=False)
    #: the half chords of the cloud's samples that beside a branch measured, shared along the updates
    #: (skelcore.diagnostics.chord_cache; docs/diagnostics.md "Beside a branch")
    chords: ChordCache = field(default_factory=ChordCache, repr=False)

    def __post_init__(self) -> None:
        if self.cloud_index is None:
            self.cloud_index = CloudIndex(self.cloud_n)

    @property
    def from_curve(self) -> bool:
        """The skeletal column is scored on the cloud's projections onto the curve (reverse, no set)."""
        return self.skeletal is None and self.mode == "reverse"

    @property
    def has_skeletal_column(self) -> bool:
        return self.skeletal is not None or self.from_curve

    @property
    def skeletal_mode(self) -> str | None:
        """The correspondence the skeletal stages see: the curve's projections are pointwise."""
        return "pointwise" if self.from_curve else self.mode

    def made_by(self, item: str) -> str | None:
        """The stage that makes a context item, None when it is there from the start."""
        if item not in CONTEXT_ITEMS:
            raise KeyError(f"unknown context item {item!r}")
        if item == "skeletal points" and self.from_curve:
            return "correspondence"
        if item == "rows" and self.skeletal_mode == "reverse":
            return "correspondence"
        if item in ("curve boundedness", "curve centeredness"):
            return item if self.curve is not None else None
        if item == "skeletal boundedness":
            return item if self.has_skeletal_column else None
        if item == "skeletal coverage":
            return item if self.skeletal is not None and self.with_coverage else None
        if item == "curve coverage":
            return item if self.curve is not None and self.with_coverage else None
        if item == "unseen" and self.viewpoints_n is not None:
            return "skeletal boundedness"
        return None

    def skeletal_points(self) -> np.ndarray:
        """The normalized skeletal set the skeletal stages score."""
        return self.results["correspondence"] if self.from_curve else self.skeletal_n

    def rows(self) -> np.ndarray:
        """Reverse correspondence: the skeletal row of every cloud row."""
        return self.results["correspondence"]

    @property
    def bounded_cloud_n(self) -> np.ndarray:
        """The cloud boundedness runs on: the normalized cloud, with the caps of ``--cap-openings`` and the
        points ``boundedness_density_aware`` fills into its sparse parts."""
        return self.cloud_n if self.capped_cloud_n is None else self.capped_cloud_n

    def boundedness(self, points_n: np.ndarray, checkpoint: Checkpoint = no_checkpoint,
                    unseen: str | None = None, keep: list | None = None) -> np.ndarray:
        """Boundedness of normalized points as the stages score it: the paper's (docs/metrics.md 2), or with
        viewpoints the share of the seen directions that are covered (docs/metrics.md 6.3); then, given a
        name in ``unseen``, also keeps there (``self.unseen``) how much of each point's unseen directions
        the cloud leaves uncovered. ``keep``: the far rays' hint tables of lone queries are appended to it
        (without viewpoints; :func:`boundedness`)."""
        if self.viewpoints_n is None:
            return boundedness(self.bounded_cloud_n, points_n, params=self.bounded_params or self.params,
                               checkpoint=checkpoint, keep=keep)
        if unseen is None:
            return seen_boundedness(self.bounded_cloud_n, points_n, self.viewpoints_n,
                                    params=self.bounded_params or self.params, checkpoint=checkpoint)
        beta, self.unseen[unseen] = seen_boundedness(self.bounded_cloud_n, points_n, self.viewpoints_n,
                                                     params=self.bounded_params or self.params, return_missing=True,
                                                     checkpoint=checkpoint)
        return beta

    def depth(self, points_n: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray | None:
        """Skeletal centeredness' depth per skeletal point with viewpoints (docs/metrics.md 6.3), else
        None; ``rows`` picks the skeletal rows of a reverse correspondence."""
        if self.viewpoints_n is None:
            return None
        d = depth_axes(points_n, self.viewpoints_n, self.unseen["skeletal"])
        return d if rows is None else d[rows]

    def interior(self, checkpoint: Checkpoint = no_checkpoint):
        """The normalized cloud's voxelized interior (docs/diagnostics.md "Cycles"), made once by the first
        diagnostic that asks (curve defects, skeletal outside: the same grid, the same parameters)."""
        from ..diagnostics.interior import median_spacing, voxelize_interior

        with self._interior_lock:
            if not self._interior:
                p = self.params
                if self.with_coverage:  # coverage's tau reads the same exact spacings: one search for both
                    median_spacing(self.cloud_n, spacings=self.cloud_index.spacings(checkpoint))
                self._interior.append(voxelize_interior(self.cloud_n, voxels=p.cycles_voxels,
                                                        min_spacing_factor=p.cycles_voxel_spacing,
                                                        inside_share=p.beta_star, checkpoint=checkpoint))
            return self._interior[0]

    def solid_test(self) -> Callable[[np.ndarray], np.ndarray] | None:
        """Whether normalized points lie in the cloud's voxelized solid (:meth:`interior`), the test the
        missing parts use to tell air from the shape; None for a scan seen from some sides, which
        encloses no interior (docs/diagnostics.md "Missing parts")."""
        if self.viewpoints_n is not None:
            return None

        def inside(points: np.ndarray) -> np.ndarray:
            shape = self.interior()
            ijk = shape.index_of(points)
            return shape.solid()[ijk[:, 0], ijk[:, 1], ijk[:, 2]]

        return inside

    def diag_tree(self, checkpoint: Checkpoint = no_checkpoint):
        """The KD-tree of at most ``diag_max_points`` of the normalized cloud that the diagnostics' local
        radii come from (:func:`skelcore.diagnostics.interior.cloud_subsample`), made once: an edit's
        update shares it with the evaluation it updates."""
        from ..diagnostics.interior import cloud_subsample
        from ..geometry import kd_tree

        with self._diag_tree_lock:
            if not self._diag_tree:
                self._diag_tree.append(kd_tree(cloud_subsample(self.cloud_n, self.params.diag_max_points),
                                               checkpoint))
            return self._diag_tree[0]

    def cloud_box(self, quantile: float) -> tuple[np.ndarray, np.ndarray]:
        """The cloud's box from the ``quantile`` to the 1 - ``quantile`` quantile of each coordinate
        (user units, :func:`skelcore.diagnostics.trust.robust_box`) the trust checks read, made once: an
        edit's update shares it (at 1M points the quantiles take 70 ms)."""
        from ..diagnostics.trust import robust_box

        key = float(quantile)
        if key not in self._cloud_box:
            self._cloud_box[key] = robust_box(self.cloud, key)
        return self._cloud_box[key]

    def tau(self, checkpoint: Checkpoint) -> float:
        """Coverage's tau (``coverage_tau``: the factor x the cloud's median spacing) from the shared
        nearest-other distances, made by the first stage that asks (docs/metrics.md 5.2)."""
        return coverage_tau(self.cloud_n, self.params, checkpoint, self.cloud_index)


def build_context(
    cloud: np.ndarray,
    skeletal: np.ndarray | None,
    curve: CurveSkeleton | tuple | None,
    params: Params,
    *,
    skeletal_index: np.ndarray | None,
    correspondence: str,
    reference_curve: CurveSkeleton | tuple | None,
    reference_radius: np.ndarray | None = None,
    reference_outside: np.ndarray | None = None,
    viewpoints=None,
    remove_outliers: bool = False,
    cap_openings: bool = False,
    checkpoint: Checkpoint = no_checkpoint,
) -> EvalContext:
    """Check the inputs of :func:`skelcore.evaluate`, take out stray points (``remove_outliers``),
    normalize (docs/metrics.md 0), cap small flat openings (``cap_openings``) and decide the correspondence,
    coverage and what cannot be computed.  ``checkpoint`` is reached by the scan options' work only."""
    if correspondence not in CORRESPONDENCE_CHOICES:
        raise SkelInputError(f"correspondence must be one of {', '.join(CORRESPONDENCE_CHOICES)}, got {correspondence!r}")
    cloud = as_points("cloud", cloud)
    if len(cloud) < 2:
        raise SkelInputError("cloud: at least 2 points are needed")
    scan = None
    if viewpoints is not None or remove_outliers or cap_openings:
        scan = ScanReport()
    if viewpoints is not None:
        try:
            viewpoints = check_viewpoints(viewpoints)
        except ValueError as exc:
            raise SkelInputError(str(exc)) from None
        if params.boundedness_method != "rays":
            raise SkelInputError("viewpoint-aware boundedness counts the rays estimator's directions: "
                                 "use boundedness_method rays with viewpoints")
    skel = index = mode = None
    if skeletal is not None:
        skel = as_points("skeletal point set", skeletal)
        if correspondence == "reverse":
            if skeletal_index is not None:
                raise SkelInputError("give either a skeletal index or reverse correspondence, not both")
            mode = "reverse"
        elif skeletal_index is not None:
            index = _check_index(skeletal_index, len(skel), len(cloud))
            mode = "index"
        else:
            mode = "pointwise" if len(skel) == len(cloud) else "none"
    elif skeletal_index is not None:
        raise SkelInputError("a skeletal index needs a skeletal point set")
    if remove_outliers:
        t0 = time.perf_counter()
        cloud, skel, index, strays, cloud_rows, dropped = without_strays(cloud, skel, index, mode == "pointwise",
                                                                         params, checkpoint=checkpoint)
        scan.outliers = dict(strays.to_dict(), removed_rows=cloud_rows.tolist())
        scan.outliers_removed, scan.skeletal_rows_removed = True, dropped
        scan.timings["outliers"] = time.perf_counter() - t0
        if skel is not None and len(skel) == 0:
            raise SkelInputError("skeletal point set: every row went with the stray points")
        if len(cloud) < 2:
            raise SkelInputError("cloud: fewer than 2 points are left without the stray points")
    check_extent("cloud", cloud)
    try:
        norm = Normalization.from_cloud(cloud, params.normalize_by, params.normalized_size)
    except ValueError:
        raise SkelInputError("cloud: all points coincide") from None
    ctx = EvalContext(params=params, cloud=cloud, norm=norm, cloud_n=_read_only(norm.apply(cloud)), mode=mode,
                      scan=scan)
    if viewpoints is not None:
        ctx.viewpoints_n = norm.apply(viewpoints)
        scan.viewpoints = viewpoints.tolist()
    if skel is not None:
        ctx.skeletal, ctx.skeletal_n, ctx.index = skel, norm.apply(skel), index

    if curve is not None:
        ctx.curve = CurveSkeleton.coerce(curve, "curve")
        check_magnitude("curve skeleton", ctx.curve.vertices)
    if correspondence == "reverse" and skeletal is None:
        if ctx.curve is None:
            raise SkelInputError("reverse correspondence needs a skeletal point set or a curve skeleton")
        ctx.mode = "reverse"
    if reference_curve is not None:
        if ctx.curve is None:
            raise SkelInputError("a reference curve is compared with a curve skeleton: give one")
        ref = CurveSkeleton.coerce(reference_curve, "reference curve")
        check_magnitude("reference curve", ref.vertices)
        if reference_radius is not None:
            ref = _with_radius(ref, reference_radius)
        ctx.reference = ref
        if reference_outside is not None:
            ctx.reference_outside = _per_reference_vertex(ref, reference_outside)
        if ref.n_edges == 0:
            ctx.not_computed["ground truth"] = "the reference curve has no edges"
        ctx.reference_n = ref.transformed(norm.apply)
    elif reference_radius is not None:
        raise SkelInputError("a reference radius needs a reference curve")
    elif reference_outside is not None:
        raise SkelInputError("the reference's outside distances need a reference curve")
    if ctx.curve is not None:
        ctx.curve_n = ctx.curve.transformed(norm.apply)
        ctx.samples = sample_curve(ctx.curve_n, params.curve_samples, collinear_cos=params.collinear_cos,
                                   method=params.curve_sampling)

    if cap_openings:
        _cap(ctx, checkpoint)
    if params.boundedness_density_aware:  # points filled into the sparse parts, for boundedness only
        fill = density_fill(ctx.cloud_n, params, checkpoint)
        if len(fill):
            h = rays_radius(ctx.bounded_cloud_n, params.rays_radius_factor)
            filled = np.vstack([ctx.bounded_cloud_n, fill])
            spacing = rays_radius(filled, 1.0)
            if spacing > 0:  # the filled points must not narrow the rays: h stays the scanned cloud's
                ctx.capped_cloud_n = _read_only(filled)
                ctx.bounded_params = params.replace(rays_radius_factor=h / spacing)

    if ctx.mode == "none":
        reason = (f"the skeletal set has {len(ctx.skeletal)} points and the cloud {len(cloud)}; "
                  "give a skeletal index or use reverse correspondence")
        ctx.not_computed.update({"topology": reason, "skeletal centeredness": reason})
    ctx.with_coverage = len(cloud) <= int(params.coverage_max_points)
    if not ctx.with_coverage and (ctx.skeletal is not None or ctx.curve is not None):
        ctx.not_computed["coverage"] = (
            f"the cloud has {len(cloud):,} points, above coverage_max_points = {int(params.coverage_max_points):,} "
            "(exact coverage of a skeletal set takes 15-45 s at 1M points on tube-like shapes; raise it with "
            "--set coverage_max_points=N)"
        )
    return ctx


def _read_only(a: np.ndarray) -> np.ndarray:
    """The evaluation's own normalized clouds are never written: read-only, boundedness reuses its prepared
    cloud for them without hashing a million rows on every edit's update (docs/boundedness.md 3.15)."""
    a.flags.writeable = False
    return a


def _cap(ctx: EvalContext, checkpoint: Checkpoint) -> None:
    """``--cap-openings``: find the openings, cap the small flat ones into ``capped_cloud_n``."""
    t0 = time.perf_counter()
    ctx.openings = find_openings(ctx.cloud, ctx.params, checkpoint=checkpoint)
    caps = cap_openings(ctx.openings, len(ctx.cloud), ctx.params)
    if len(caps.points):
        ctx.capped_cloud_n = _read_only(np.vstack([ctx.cloud_n, ctx.norm.apply(caps.points)]))
    ctx.scan.openings = [dict(o.to_dict(), rows=o.rows.tolist(), capped=i in caps.capped, refused=caps.refused.get(i))
                         for i, o in enumerate(ctx.openings)]
    ctx.scan.cap_points = int(len(caps.points))
    ctx.scan.timings["openings"] = time.perf_counter() - t0


def _with_radius(ref: CurveSkeleton, radius) -> CurveSkeleton:
    """``ref`` with ``reference_radius=``: one per vertex of the cleaned curve, or of the raw vertices
    it came from (its ``vertex_map``); NaN or <= 0 = unknown (estimated from the cloud)."""
    import dataclasses

    r = np.asarray(radius, dtype=float).ravel()
    if r.shape != (ref.n_vertices,):
        if ref.vertex_map is None or r.size <= int(np.max(ref.vertex_map, initial=-1)):
            raise SkelInputError(f"reference radius: {r.size} values for a reference curve of {ref.n_vertices} vertices")
        r = r[ref.vertex_map]
    if np.any(np.isinf(r)):
        raise SkelInputError("reference radius: contains inf")
    return dataclasses.replace(ref, radius=r)


def _per_reference_vertex(ref: CurveSkeleton, values) -> np.ndarray:
    """``reference_outside=``: one value per vertex of the cleaned curve, or of the raw vertices it came
    from (its ``vertex_map``, as a facts file lists them)."""
    v = np.asarray(values, dtype=float).ravel()
    if v.shape != (ref.n_vertices,) and ref.vertex_map is not None and v.size > int(np.max(ref.vertex_map, initial=-1)):
        v = v[ref.vertex_map]
    return v  # its length and values are checked by the ground truth (docs/metrics.md 5.3.1)


def _check_index(skeletal_index: np.ndarray, n_skel: int, n_cloud: int) -> np.ndarray:
    index = np.asarray(skeletal_index)
    if index.dtype.kind not in "iu":
        if index.dtype.kind != "f" or not np.all(np.isfinite(index)) or np.any(index != np.round(index)):
            raise SkelInputError("skeletal index: cloud rows must be whole numbers")
    index = index.astype(np.int64).ravel()
    if index.shape != (n_skel,):
        raise SkelInputError(f"skeletal index: has {len(index)} rows, needs one cloud row per skeletal point ({n_skel})")
    if len(index) and (index.min() < 0 or index.max() >= n_cloud):
        bad = int(index.min()) if index.min() < 0 else int(index.max())
        raise SkelInputError(f"skeletal index: cloud row {bad} out of range (the cloud has {n_cloud} rows, 0-based)")
    return index
