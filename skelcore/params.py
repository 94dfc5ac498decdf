"""Every constant of docs/metrics.md as one validated, frozen dataclass (the single source of truth)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, fields
from typing import Any, Literal


@dataclass(frozen=True)
class Params:
    """Parameters of the evaluation; defaults reproduce the reference tool (docs/metrics.md).

    Attributes
    ----------
    normalize_by : "longest_side" (reference tool) or "diagonal" (paper's text), docs/metrics.md 0.
    normalized_size : the chosen bounding-box measure becomes this length (1.6), docs/metrics.md 0.
    beta_star, c_star : thresholds; bounded means beta > beta_star, centred c > c_star (strict).
    eps_quantile : quantile of the cloud's nearest-neighbour distances giving eps*, docs/metrics.md 1
        (0.99 reference tool, 1.0 = the paper's max).
    min_bar_fraction, fallback_fraction : K < min_bar_fraction * N_o triggers
        K = N_o - round(fallback_fraction * N_o) + 1 (docs/metrics.md 1).
    boundedness_method : "rays" (default, rotation invariant) or "paper" (reference tool), docs/metrics.md 2.
    rays_radius_factor : h = factor x median nearest-neighbour spacing of the cloud, docs/metrics.md 2.
    rays_rows : latitude rows of the equal-area raster used by the rays estimator (2 x as many
        longitude bins); 48 keeps it within 0.004 of the exact union area (tests/engine/test_boundedness.py).
    rays_exact_pairs : up to this many (query, cloud point) pairs the rays estimator uses every pair;
        beyond, queries share their far field in clusters (boundedness.py docstring).
    rays_near_angle : a clustered query's own near field reaches h / rays_near_angle (x 1/2, 1, 2, ...,
        32 are tried: cells and near field scale together to the cheapest estimate).
    rays_cluster_cell : side of the cluster cells, in units of h (scaled as above); keep
        1 / rays_near_angle >= 10 x rays_cluster_cell (5 x erred up to 0.08).
    paper_plane_threshold, paper_area_threshold : triangle-drop rule of the paper estimator.
    k_center : neighbours for skeletal-point centeredness; None = round(0.01 N_s) with the
        reference tool's clamps (<10 -> 10, >50 -> 30), docs/metrics.md 3.
    curve_samples : total samples S along the curve skeleton, docs/metrics.md 3.
    curve_sampling : "toolbox" (default, reference tool: each edge walked from its lower-index vertex,
        so the samples depend on the vertex numbering) or "invariant" (each branch walked from a
        canonical end chosen by coordinates), docs/metrics.md 3.
    slab_factor : slab width alpha = factor x bounding-box diagonal of the normalized cloud.
    ring_growth : ring isolation ratio (keep while next distance < ratio x last kept).
    collinear_cos : ``|cos|`` at or above which a degree-2 vertex's neighbours count as collinear.
    tangent_k, smooth_k : neighbours for PCA tangents and for the tangent comparison, docs/metrics.md 4.
    coverage_slack : s of SkelScope's coverage (docs/metrics.md "Coverage"): a cloud point is covered
        when it lies within (1 + s) r(x) + tau of some skeleton element x of inscribed radius r(x).
    coverage_tau_factor : tau = factor x the cloud's median nearest-neighbour spacing (coverage and
        the reference comparison's precision / recall).
    coverage_radius_quantile : the balls' radii r(x) grow by the cloud's noise shortfall, from this
        quantile of the excess ``|p - x| - r(x)`` of the cloud points nearest to them (docs/metrics.md 5.2
        "Noise"); 0: r(x) alone.
    coverage_max_points : coverage is computed for clouds of at most this many points (0: never);
        a skeletal set as large as the cloud costs about N^1.4 on tube-like shapes (torus, both cores:
        2.4 s at 256k, 16 s at 1M; docs/metrics.md 5.2).
    coverage_exact_points : up to this many cloud points coverage is exact; above, it is estimated on a
        random subsample of this many cloud points and at most as many skeleton elements (their radii
        from the whole cloud), every other cloud point taking its nearest sampled point's gap and verdict
        (the JSON's ``coverage.*.subsample`` says so; docs/metrics.md 5.2, docs/performance.md 6.6).
    frame_inside_fraction : the ``frame`` warning fires when fewer skeleton points than this fraction
        lie inside the cloud's bounding box (grown by 10 % of its diagonal).
    frame_extent_ratio : ... or when the skeleton's bounding-box diagonal is more than this many
        times larger (or smaller, when it also lies outside) than the cloud's.
    collapse_extent : the ``collapse`` warning fires when the skeleton's bounding-box diagonal is
        below this fraction of the cloud's.

    Diagnostics (docs/diagnostics.md; local radius r = distance from a curve point to the cloud):

    diag_max_points : the spur test explains at most this many cloud points (a random subsample
        beyond; the result says so).
    diag_step : the curve is walked every diag_step x its median local radius.
    spur_reach : a terminal branch is spurious when its far end stays within spur_reach x r_J of its
        junction (r_J: the local radius at the junction) ...
    spur_unique : ... or when fewer than this share of the cloud points nearest to it lie beyond the
        rest of the skeleton's grown balls ((1 + spur_slack) r, no spacing-sized tau) ...
    spur_min_points : ... or fewer than this many points do (1: none; a count, unlike the share,
        grows with the density).
    spur_slack : see spur_unique.
    spur_resolved_spacings : a terminal branch is judged only where its junction's radius r_J is at
        least this many cloud spacings (the median nearest-neighbour distance of the 16 points nearest
        the junction); below, the cloud does not resolve a twig there and the branch is counted
        ``unresolved``, neither spurious nor justified.
    spur_twig_spacings : ... and a branch failing only the explanation measure is judged only where its
        far end reaches at least this many junction spacings past the junction's ball (spur_reach x
        r_J): a real twig that short bulges out of its parent by less than the cloud's spacing and
        gets no sample of its own beyond the parent's grown balls (``unresolved`` too) ...
    spur_twig_tip_spacings : ... unless its far end lies farther from the cloud than its reach past
        the junction's ball plus this many junction spacings: a real twig's tip stands at most that
        far past its parent's sampled surface, so such a tip is in the air (judged).
    spur_stub_share : a stub (its far end within spur_reach x r_J: inside the junction's inscribed
        ball, so inside the shape) shorter than this share of the curve's length is counted among the
        ``stubs``, not spurious: it changes no metric by more than that share.
    spur_one_sided : on a cloud seen from one side (the mean direction from the curve to its cloud
        points, across the axis, at least this long: docs/diagnostics.md "Spurious branches") a
        terminal branch failing only the explanation measure is counted ``unseen``, not judged.
    spur_cut_gap : a terminal branch's tip is a cut end (not judged: the curve is broken there, which
        ``disconnected`` names) when another piece of the curve lies within this many local radii of
        it (the larger of the two ends'), ahead of it ...
    spur_cut_angle : ... the gap's direction within this many degrees of the branch's own at its tip,
        and the cloud fills the gap (within (1 + spur_slack) x the radius interpolated between its ends).
    spurs_warn_count : ``spurious_branches`` fires from this many spurious branches.
    cycles_voxels : voxels along the longest side of the cloud's box for the shape's interior ...
    cycles_voxel_spacing : ... but a voxel is at least this many median nearest-neighbour spacings
        of the cloud wide, so that the surface's voxels close.
    cycles_close_voxels : no more cycles are legitimate than the interior with the voxels near the
        skeleton's cycles has tunnels once gaps of up to 2 x this many voxels are closed (two strands
        side by side through a thin part invent the tunnel between them).
    cycles_warn_spurious, cycles_warn_missing : ``spurious_cycles`` / ``missing_cycles`` fire from
        this many spurious / missing cycles.
    cycles_support_voxels, cycles_support_points, cycles_support_share : the tunnels that no cycle
        goes around are counted on the interior again without the voxels of isolated points: those
        whose block of this many voxels a side holds fewer than max(points, share x the median such
        count over the cloud's points) points (stray points in the air) ...
    cycles_strict_share : ... and must persist when the inside share rises from beta_star to this
        (a tube's inside sees its surface along nearly all 26 rays; a gap between noisy strands
        along fewer), and in the interior's part at least open_resolved_diameter spacings across:
        docs/diagnostics.md "Cycles".
    cycles_resolved_voxels : ... and at least this many voxels across (the grid's own resolution:
        where the box sets the voxel, two branches closer than the grid resolves join into a ring).
    outside_min_radii : ``outside`` fires when a branch has at least this many local radii of
        length outside the shape (where its curve samples have boundedness <= beta_star and the
        cycle test's voxels are not inside) ...
    outside_min_share : ... or at least this share of the curve's length is outside.
    outside_reach : ``outside`` also fires for a branch, however short, that reaches farther than
        this many local radii from the cloud (the radius where it attaches: at its junction for a
        terminal branch), at a point whose nearest cloud points lie on one side of it (docs/diagnostics.md
        "Outside"): three spurs poking 8 radii out of a neuron were a few % of its length. Traced
        skeletons' nodes lie up to about one radius outside a decimated mesh.
    outside_one_sided : ... one side: the mean of the unit vectors to its 16 nearest cloud points
        is at least this long (0: surrounded, as inside a tube or a ball; 1: all in one direction);
        the length test also counts a point outside only where this holds.
    outside_voxel_radii : the length test runs only when the interior's voxel is at most this many
        median local radii (coarser voxels cannot tell a part's inside from a few radii beyond it:
        a traced neuron, voxel about 9 radii); otherwise only the reach test runs.
    outside_skeletal_share : ``outside`` fires when more than this share of a skeletal point set
        is outside (unbounded, in no inside voxel) in one cluster (points within outside_link x the
        cloud's median spacing).
    outside_link : see outside_skeletal_share.
    components_link : the cloud's pieces join its points within this many median spacings (each to
        its nearest few): ``disconnected`` fires when a piece of the cloud holds more than one piece of
        the curve (at 2 spacings a random surface sample falls into hundreds of bits, at 4 it is one;
        8 from the tuning neurons, whose one-sided and unevenly sampled clouds fall apart at 4).
    surface_max_centeredness : a bounded curve sample whose raw centeredness (Eq. 11) is below this is
        off axis: on a round cross-section it lies less than this share of the radius from the wall
        (docs/diagnostics.md "Along the surface"; traced neurons' nodes lie 0.3-0.5 radii off centre).
    surface_junction_radii : samples within this many of a junction's local radii of it are not judged
        (the slab cuts the other branches there).
    surface_min_samples, surface_min_share, surface_min_radii : ``along_surface`` fires for a branch
        with at least this many off-axis samples, this share of its samples judged, and this many
        local radii of their stretches.
    surface_slab_radii : branches are judged only when half the centeredness slab (slab_factor x the
        diagonal) is at most this many median local radii (the synthetic suite: up to 2.8 with its
        offset axes; the traced neurons at 30k: 12, where the slab cuts stretches of neurite).
    missing_depth : a region of unexplained cloud points (beyond every skeleton element's ball grown
        by coverage_slack and tau) counts as a missing part (warning ``incomplete``) when it reaches
        this many radii of its border beyond that border (the border: its points next to explained
        ones; its radius: the RMS distance of the border's largest piece from its centroid); a
        contraction stopping a radius short of a rounded end reaches about one or less
        (docs/diagnostics.md "Missing parts").
    missing_min_share : ... and when it holds at least this share of the cloud (noise, a few points).
    missing_min_area, missing_small_depth : ... or when it holds the surface of at least this many
        squared median ball radii (points x the cloud's median spacing squared; 36: a tube's 6 radii)
        and reaches this depth: on a branching arbor one branch is a small share of the cloud, and
        its depth in its own border radius tells it from a shallow strip once it has a border and
        points beyond; the strips an intact traced neuron leaves reach up to 1.3
        (docs/diagnostics.md "Completeness").
    missing_air_ball : an element in no solid voxel of the interior (and one-sided on an open
        surface) explains nothing when its ball is over this many x the median ball of the elements
        inside, or when it faces the shape from outside (one median ball beyond its nearest cloud
        point is inside): an edge through the air crosses gaps wider than the shape, the axis of a
        tube seen from one side keeps the tube's radius (docs/diagnostics.md "Completeness").
    missing_large_share : a region holding this share of the cloud counts whatever its depth (a
        skeleton shrunk to the centre of a ring: its ball is wide, the ring unexplained).
    missing_min_completeness : ``incomplete`` also fires when the skeleton explains less than this
        share of the cloud, however it is split (a mapping that halves a skeleton leaves several
        regions, none large).
    missing_depth_quantile : quantile of a region's distances to its border taken as its reach
        (robust to stray points).
    missing_beside_radii, missing_beside_quantile : a region whose ``missing_beside_quantile`` distance
        to the skeleton is at most this many local radii (half the shape's chord along the inward
        normal, read off the cloud) lies beside a branch: the far wall of an off-centre axis, the wide
        sides of a flat part. It does not count, and the completeness floor counts it as explained
        (docs/diagnostics.md "Missing parts", "Beside a branch"; 3.0 between the synthetic suite's
        off-centre and flat curves, at most 2.7, and its missing parts, at least 3.3).
    missing_beside_end_radii, missing_beside_beyond : ... unless more than this share of its points
        lie beyond an end of the skeleton by more than this many local radii (a cut branch, the
        hammer's head past the handle's end: 0.3-1.0; an off-centre axis's caps: at most 0.06).
    missing_link_factor : unexplained points closer than this many median NN spacings are one region.
    missing_max_points : above this many cloud points the missing parts are found on a random
        subsample of this many and every cloud point takes its nearest sample's verdict (the result
        says so; docs/diagnostics.md gives the verdicts unchanged).
    missing_max_elements : a skeletal set with more points is thinned to one point per grid cell
        (half the cloud's median spacing, grown until at most this many remain) before its balls are
        built: the balls' slack dwarfs the cells.
    trust_extent_quantile : ``frame`` and ``collapse`` measure extents on the box from this quantile to
        1 - it of each coordinate, so that a few stray points do not move them.

    Real scans (docs/metrics.md section 6; SkelScope's own, the paper's values unchanged by default):

    open_k, open_angle : a cloud point is on the boundary when the largest angle between its open_k
        nearest neighbours' directions in its tangent plane exceeds open_angle degrees (PCL's
        BoundaryEstimation, default 90).
    open_link : boundary points closer than open_link x the cloud's median spacing belong to one opening.
    open_empty : the fill of an opening keeps the points farther than open_empty x the median spacing
        from every cloud point (where the surface is missing) ...
    open_min_fill : ... and an opening with fewer such points is not one (a sampling gap).
    open_max_points : the boundary test runs on a random subsample of this many points above it.
    open_end_flatness, open_end_roundness : an opening is an open tube end when its rim lies within
        open_end_flatness x its radius of its plane (RMS), the rim's distances from its centre vary by
        less than open_end_roundness (coefficient of variation) and the rim surrounds the centre;
        else a missing side.
    open_surface_share : ``open_surface`` fires when at least this share of a skeleton's elements is
        unbounded only because its rays leave through openings.
    open_resolved_diameter : a boundary point counts towards an opening only where the part is at
        least this many of its spacings across (2 x its distance to the skeleton); thinner, the part is
        sampled too thinly to resolve, where its neighbours are curved too (smallest / middle eigenvalue
        of their covariance above open_thin_planarity: a flat cap's centre lies on the skeleton) ...
    open_fill_reach : a missing side counts when at least half its fill lies within open_fill_reach x
        the local radius (distance to the cloud) of the nearest skeleton element: across its part, not
        across the gap between two parts.
    boundedness_density_aware : boundedness casts also against points filled into the cloud's sparsely
        sampled parts, h kept the scanned cloud's (docs/metrics.md 6.8); False = the paper's.
    sparse_ratio : ``sparse_boundedness`` fires when at least open_surface_share of a skeleton's elements
        are unbounded where the cloud's local spacing (the median over outlier_local_k points) exceeds
        this many x its median spacing.
    thin_min_share : ... and warning ``thin_parts`` (which switches nothing off) names such parts when
        their boundary points are at least this share of the cloud.
    open_one_sided : ... such parts are seen from one side when the mean unit direction from their axis
        to their points, averaged over them, is longer than this share of its mean length (closed
        neuron clouds 0.18-0.29, one-sided scans 0.68-0.69): their mirrored points close them.
    cap_max_share : ``--cap-openings`` refuses an opening whose cap would add more than this share of
        the cloud's points ...
    cap_flatness : ... or whose rim lies farther than this x its radius from its plane (RMS).
    viewpoint_rows : with viewpoints, boundedness counts directions on an equal-area raster of
        viewpoint_rows x 2 viewpoint_rows.
    viewpoint_share_cell : with viewpoints, elements farther than 4 cells from the cloud share one cast
        of every direction per cubic cell of this side, in units of h (0: each element cast alone;
        docs/metrics.md 6.3).
    outlier_k, outlier_std_ratio : statistical test (PCL / Open3D): a point is flagged when its mean
        distance to its outlier_k nearest neighbours exceeds the cloud's median of that by more than
        outlier_std_ratio robust standard deviations (1.4826 x MAD) ...
    outlier_radius, outlier_min_neighbours : ... and the radius test: fewer than outlier_min_neighbours
        other points within outlier_radius x the median spacing.  A stray point fails both.
    outlier_local_k : both radius tests are also taken with the local spacing (the median nearest
        distance of this many cloud points nearest to the point) as yardstick: a stray fails both.
    outlier_off_surface_cos, outlier_surface_points : ... and it lies off the surface, not in a gap of
        it: the median ``|cos|`` between its offset from its outlier_surface_points nearest non-isolated
        points and their normals exceeds outlier_off_surface_cos, and none of them is a rim point
        (open_k, open_angle), or it lies beyond their box.  A one-sided scan's lone points lie along
        the surface or across a rim.
    outlier_view_share, outlier_view_cos : ... and, on a one-sided scan (the depth image along some axis
        keeps at least outlier_view_share of the cloud; scan/view_axis.py), it does not lie along that
        axis from most of its nearest surface points (``|cos|`` above outlier_view_cos): there it lies in
        their shadow, a sample whose neighbours they hide.
    outlier_skeletal_radius : a skeletal point with fewer than outlier_min_neighbours other skeletal
        points within this many cloud spacings is a stray's image (contracted sets are dense: on the
        hammer and the apple tree every skeletal point has two within 1.7).

    Ground truth (docs/metrics.md 5.3.1; given a reference curve; skelcore.metrics.ground_truth):

    gt_thresholds, gt_threshold_max : precision / recall / F1 are averaged over the thresholds
        k / gt_thresholds x gt_threshold_max local radii, k = 1..gt_thresholds.
    gt_match_radii : junctions and endpoints match a reference node within this many of its radii.
    gt_branch_radii : branch split / merge: a reference branch and one of ours are associated when at
        least this many local radii of its length lie within this many local radii of ours.
    gt_sample_step : both curves are sampled every this many x the reference's smallest radius.
    gt_radius_k : where the reference has no radius, it is the median distance to this many cloud points.
    gt_diag_thresholds : the absolute thresholds of docs/metrics.md 5.3.2, shares of the reference's
        bounding-box diagonal, written as text ("0.01 0.02 0.05": 1, 2 and 5 %).
    gt_cover_share : a branch or a root-to-leaf path counts as found when more than this share of its
        length lies within gt_threshold_max local radii of the other curve (docs/metrics.md 5.3.2).
    gt_substantial : ESA / DSA / PDS call a distance substantial above this share of the diagonal.
    gt_held_radii : where the reference's nodes are known to lie off the surface the cloud was drawn
        from (a traced neuron on its decimated mesh), a node is held (the cloud can show it) when it
        lies inside or at most this many of its radii outside; precision / recall / F1 are also given
        on the held reference (docs/metrics.md 5.3.1). = gt_threshold_max: a node farther out is beyond
        every threshold for a curve inside the surface.
    repair_max_rounds : skelcore.repair acts in at most this many rounds, one action or one batch each
        (docs/repair.md).
    repair_max_tries : candidate actions tried (each evaluated) per round before giving up.
    repair_max_components : a curve with more components than this is refused by skelcore.repair
        (joining thousands of fragments pairwise is not a repair; skeletonize again).
    repair_completeness_drop, repair_outside_rise : the never-worse rule: an action is rejected when the
        curve's completeness drops, or its outside length share rises, by more than this.
    repair_score_drop : ... or when curve boundedness or curve centeredness drops by more than this.
    repair_fill_missing : skelcore.repair also tries to fill a missing part (a new stretch of curve).
    repair_fill_points : a missing region of more points is skeletonized (``skelscope``) for its fill on
        the means of its points per cell of a grid with at most this many cells (docs/repair.md "The
        repair's cost"; tuned on neurons 1734350788 and 1734350908).
    repair_all_round : a missing region is seen all round when at least this share of the cloud's
        cross-sections through it is its own (a tube's end, a thick part cut off, a whole missing
        branch); its slabs' centroids are tried before its axis curve (docs/repair.md "A thick part's
        fill").
    repair_join_step : a join between components is tried only when every point along it, every this
        many x the voxel size of the shape's interior, lies inside the shape.
    repair_recentre : skelcore.repair also moves off-centre curve vertices (c <= c_star) to the centre of
        their cross-section.
    repair_centre_gain : a re-centring that removes no defect is kept when curve centeredness rises by at
        least this (and completeness, boundedness and the defect count do not get worse).
    repair_outside_gain : an action on an outside branch that leaves as many defects (no more missing
        cycles or components) is kept when the curve's outside length share falls by at least this
        (and the never-worse bounds hold).
    repair_batch_tries : per round and batched kind (spurs, spurious cycles), how many batches of its
        actions apart from one another skelcore.repair judges together before its single tries
        (docs/repair.md "Batches"); 0: no batches, one action per round.
    repair_batch_gap : the members of a batch lie farther apart than this many x the curve's median
        edge length (and share no vertex or neighbour), so that each one's effect is its own.
    """

    normalize_by: Literal["longest_side", "diagonal"] = "longest_side"
    normalized_size: float = 1.6
    beta_star: float = 0.75
    c_star: float = 0.75
    eps_quantile: float = 0.99
    min_bar_fraction: float = 0.05
    fallback_fraction: float = 0.95
    boundedness_method: Literal["rays", "paper"] = "rays"
    rays_radius_factor: float = 2.0
    rays_rows: int = 48
    rays_exact_pairs: int = 4_000_000
    rays_near_angle: float = 0.1
    rays_cluster_cell: float = 1.0
    paper_plane_threshold: float = 0.8
    paper_area_threshold: float = 1e-4
    k_center: int | None = None
    curve_samples: int = 200
    curve_sampling: Literal["toolbox", "invariant"] = "toolbox"
    slab_factor: float = 0.02
    ring_growth: float = 1.5
    collinear_cos: float = 0.99
    tangent_k: int = 8
    smooth_k: int = 4
    coverage_slack: float = 0.5
    coverage_tau_factor: float = 2.0
    coverage_radius_quantile: float = 0.1
    coverage_max_points: int = 262144
    coverage_exact_points: int = 262144
    frame_inside_fraction: float = 0.5
    frame_extent_ratio: float = 10.0
    collapse_extent: float = 0.1
    # diagnostics: branches, spurs, cycles, outside (docs/diagnostics.md)
    diag_max_points: int = 200_000
    diag_step: float = 0.25
    spur_reach: float = 1.0
    spur_unique: float = 0.1
    spur_min_points: int = 1
    spur_slack: float = 0.25
    spur_resolved_spacings: float = 2.0
    spur_twig_spacings: float = 1.5
    spur_twig_tip_spacings: float = 3.25
    spur_stub_share: float = 0.005
    spur_one_sided: float = 0.18
    spur_cut_gap: float = 3.0
    spur_cut_angle: float = 60.0
    spurs_warn_count: int = 1
    cycles_voxels: int = 96
    cycles_voxel_spacing: float = 1.5
    cycles_warn_spurious: int = 1
    cycles_close_voxels: int = 4
    cycles_warn_missing: int = 1
    cycles_support_voxels: int = 5
    cycles_support_points: int = 3
    cycles_support_share: float = 0.05
    cycles_strict_share: float = 0.9
    cycles_resolved_voxels: float = 3.0
    outside_min_radii: float = 0.5
    outside_min_share: float = 0.05
    outside_reach: float = 8.0
    outside_one_sided: float = 0.7
    outside_voxel_radii: float = 3.0
    outside_skeletal_share: float = 0.05
    outside_link: float = 3.0
    components_link: float = 8.0
    surface_max_centeredness: float = 0.45
    surface_junction_radii: float = 1.5
    surface_min_samples: int = 2
    surface_min_share: float = 0.5
    surface_min_radii: float = 2.0
    surface_slab_radii: float = 4.0

    # diagnostics: missing parts (docs/diagnostics.md)
    missing_depth: float = 1.25
    missing_min_share: float = 0.01
    missing_min_area: float = 36.0
    missing_small_depth: float = 2.0
    missing_air_ball: float = 2.0
    missing_large_share: float = 0.5
    missing_min_completeness: float = 0.6
    missing_depth_quantile: float = 0.95
    missing_beside_radii: float = 3.0
    missing_beside_quantile: float = 0.95
    missing_beside_end_radii: float = 1.5
    missing_beside_beyond: float = 0.15
    missing_link_factor: float = 4.0
    missing_max_points: int = 200_000
    missing_max_elements: int = 20_000

    trust_extent_quantile: float = 0.005
    # real scans: openings, viewpoints, stray points (docs/metrics.md section 6)
    open_k: int = 30
    open_angle: float = 90.0
    open_link: float = 6.0
    open_empty: float = 3.0
    open_min_fill: int = 10
    open_max_points: int = 50_000
    open_end_flatness: float = 0.15
    open_end_roundness: float = 0.3
    open_surface_share: float = 0.02
    open_resolved_diameter: float = 8.0
    open_thin_planarity: float = 0.0
    thin_min_share: float = 0.01
    open_one_sided: float = 0.35
    open_fill_reach: float = 1.5
    sparse_ratio: float = 2.0
    boundedness_density_aware: bool = False
    cap_max_share: float = 0.1
    cap_flatness: float = 0.2
    viewpoint_rows: int = 16
    viewpoint_share_cell: float = 0.5
    outlier_k: int = 8
    outlier_std_ratio: float = 6.0
    outlier_radius: float = 10.0
    outlier_min_neighbours: int = 2
    outlier_skeletal_radius: float = 5.0
    outlier_local_k: int = 30
    outlier_off_surface_cos: float = 0.5
    outlier_surface_points: int = 3
    outlier_view_share: float = 0.65
    outlier_view_cos: float = 0.5
    # ground truth (docs/metrics.md 5.3.1)
    gt_thresholds: int = 20
    gt_threshold_max: float = 1.0
    gt_match_radii: float = 2.0
    gt_branch_radii: float = 1.0
    gt_sample_step: float = 0.1
    gt_radius_k: int = 8
    gt_diag_thresholds: str = "0.01 0.02 0.05"
    gt_cover_share: float = 0.8
    gt_substantial: float = 0.02
    gt_held_radii: float = 1.0
    # repair (docs/repair.md)
    repair_max_rounds: int = 40
    repair_max_tries: int = 6
    repair_max_components: int = 200
    repair_completeness_drop: float = 0.0
    repair_outside_rise: float = 0.0
    repair_score_drop: float = 0.02
    repair_join_step: float = 0.5
    repair_fill_missing: bool = True
    repair_fill_points: int = 8000
    repair_all_round: float = 0.93
    repair_recentre: bool = True
    repair_centre_gain: float = 0.01
    repair_outside_gain: float = 0.01
    repair_batch_tries: int = 3
    repair_batch_gap: float = 2.0

    def __post_init__(self) -> None:
        def bad(name: str, why: str) -> None:
            raise ValueError(f"parameter {name}={getattr(self, name)!r}: {why}")

        if self.normalize_by not in ("longest_side", "diagonal"):
            bad("normalize_by", "must be 'longest_side' or 'diagonal'")
        if self.boundedness_method not in ("rays", "paper"):
            bad("boundedness_method", "must be 'rays' or 'paper'")
        if self.curve_sampling not in ("toolbox", "invariant"):
            bad("curve_sampling", "must be 'toolbox' or 'invariant'")
        for name in ("normalized_size", "rays_radius_factor", "slab_factor", "paper_area_threshold", "rays_cluster_cell",
                     "coverage_tau_factor", "collapse_extent"):
            if not float(getattr(self, name)) > 0:
                bad(name, "must be > 0")
        if not float(self.coverage_slack) >= 0:
            bad("coverage_slack", "must be >= 0")
        if not 0 <= float(self.coverage_radius_quantile) < 1:
            bad("coverage_radius_quantile", "must be in [0, 1)")
        if not float(self.frame_extent_ratio) > 1:
            bad("frame_extent_ratio", "must be > 1")
        for name in ("beta_star", "c_star", "min_bar_fraction", "fallback_fraction", "collinear_cos",
                     "frame_inside_fraction"):
            if not 0.0 <= float(getattr(self, name)) <= 1.0:
                bad(name, "must be in [0, 1]")
        if not 0.0 < float(self.eps_quantile) <= 1.0:
            bad("eps_quantile", "must be in (0, 1]")
        if not float(self.ring_growth) > 1.0:
            bad("ring_growth", "must be > 1")
        for name in ("curve_samples", "tangent_k", "smooth_k", "rays_rows", "rays_exact_pairs"):
            if int(getattr(self, name)) < 1:
                bad(name, "must be a positive integer")
        if int(self.coverage_max_points) < 0:
            bad("coverage_max_points", "must be >= 0")
        if int(self.coverage_exact_points) < 1:
            bad("coverage_exact_points", "must be a positive integer")
        if not 0.0 < float(self.rays_near_angle) < 1.0:
            bad("rays_near_angle", "must be in (0, 1)")
        for name in ("missing_depth", "missing_link_factor", "missing_small_depth", "missing_min_area",
                     "missing_air_ball"):
            if not float(getattr(self, name)) > 0:
                bad(name, "must be > 0")
        for name in ("missing_beside_radii", "missing_beside_end_radii"):
            if not float(getattr(self, name)) >= 0:
                bad(name, "must be >= 0 (0: no region is beside a branch)")
        for name in ("missing_min_share", "missing_large_share", "missing_min_completeness",
                     "missing_depth_quantile", "missing_beside_quantile", "missing_beside_beyond"):
            if not 0.0 <= float(getattr(self, name)) <= 1.0:
                bad(name, "must be in [0, 1]")
        for name in ("missing_max_points", "missing_max_elements"):
            if int(getattr(self, name)) < 1000:
                bad(name, "must be an integer >= 1000")
        if self.k_center is not None and int(self.k_center) < 1:
            bad("k_center", "must be a positive integer or None")
        if not 0.0 <= float(self.spur_cut_angle) <= 180.0:
            bad("spur_cut_angle", "must be in [0, 180]")
        for name in ("diag_step", "spur_reach", "cycles_voxel_spacing", "cycles_resolved_voxels", "outside_min_radii", "outside_link",
                     "components_link", "surface_min_radii", "surface_slab_radii",
                     "outside_reach", "outside_voxel_radii"):
            if not float(getattr(self, name)) > 0:
                bad(name, "must be > 0")
        for name in ("surface_max_centeredness", "surface_min_share", "spur_unique", "spur_one_sided", "outside_min_share", "outside_skeletal_share", "outside_one_sided",
                     "cycles_support_share", "cycles_strict_share"):
            if not 0.0 <= float(getattr(self, name)) <= 1.0:
                bad(name, "must be in [0, 1]")
        for name in ("surface_min_samples", "diag_max_points", "cycles_voxels", "cycles_close_voxels", "spurs_warn_count", "cycles_warn_spurious",
                     "cycles_warn_missing", "cycles_support_voxels", "cycles_support_points"):
            if int(getattr(self, name)) < 1:
                bad(name, "must be a positive integer")
        for name in ("surface_junction_radii", "spur_slack", "spur_resolved_spacings", "spur_twig_spacings", "spur_twig_tip_spacings",
                     "spur_stub_share", "spur_cut_gap"):
            if not float(getattr(self, name)) >= 0:
                bad(name, "must be >= 0")
        if int(self.spur_min_points) < 0:
            bad("spur_min_points", "must be >= 0")
        if not 0.0 <= float(self.trust_extent_quantile) < 0.5:
            bad("trust_extent_quantile", "must be in [0, 0.5)")
        for name in ("open_link", "open_empty", "open_resolved_diameter", "open_fill_reach", "sparse_ratio", "open_end_flatness", "open_end_roundness", "cap_flatness",
                     "outlier_std_ratio", "outlier_radius", "outlier_skeletal_radius"):
            if not float(getattr(self, name)) > 0:
                bad(name, "must be > 0")
        if not 0.0 < float(self.open_angle) < 360.0:
            bad("open_angle", "must be in (0, 360) degrees")
        for name in ("open_surface_share", "cap_max_share", "thin_min_share", "open_thin_planarity", "open_one_sided",
                     "outlier_off_surface_cos", "outlier_view_share", "outlier_view_cos"):
            if not 0.0 <= float(getattr(self, name)) <= 1.0:
                bad(name, "must be in [0, 1]")
        if not float(self.viewpoint_share_cell) >= 0:
            bad("viewpoint_share_cell", "must be >= 0")
        for name in ("open_k", "open_min_fill", "open_max_points", "viewpoint_rows", "outlier_k", "outlier_local_k",
                     "outlier_min_neighbours", "outlier_surface_points"):
            if int(getattr(self, name)) < 1:
                bad(name, "must be a positive integer")
        if int(self.open_k) < 3:
            bad("open_k", "must be at least 3")
        for name in ("gt_threshold_max", "gt_match_radii", "gt_branch_radii", "gt_sample_step"):
            if not float(getattr(self, name)) > 0:
                bad(name, "must be > 0")
        for name in ("repair_max_rounds", "repair_max_tries", "repair_max_components", "repair_fill_points"):
            if int(getattr(self, name)) < 1:
                bad(name, "must be a positive integer")
        for name in ("repair_completeness_drop", "repair_outside_rise", "repair_score_drop", "repair_centre_gain",
                     "repair_outside_gain"):
            if not float(getattr(self, name)) >= 0:
                bad(name, "must be >= 0")
        if not 0.0 <= float(self.repair_all_round) <= 1.0:
            bad("repair_all_round", "must be in [0, 1]")
        if not float(self.repair_join_step) > 0:
            bad("repair_join_step", "must be > 0")
        if int(self.repair_batch_tries) < 0:
            bad("repair_batch_tries", "must be >= 0")
        if not float(self.repair_batch_gap) >= 0:
            bad("repair_batch_gap", "must be >= 0")
        for name in ("gt_thresholds", "gt_radius_k"):
            if int(getattr(self, name)) < 1:
                bad(name, "must be a positive integer")
        if not 0.0 < float(self.gt_cover_share) < 1.0:
            bad("gt_cover_share", "must be in (0, 1)")
        if not float(self.gt_substantial) > 0:
            bad("gt_substantial", "must be > 0")
        if not float(self.gt_held_radii) >= 0:
            bad("gt_held_radii", "must be >= 0 (radii outside the surface)")
        try:
            shares = [float(x) for x in str(self.gt_diag_thresholds).replace(",", " ").split()]
        except ValueError:
            shares = []
        if not shares or min(shares) <= 0:
            bad("gt_diag_thresholds", "must be shares > 0 of the diagonal, e.g. '0.01 0.02 0.05'")

    def replace(self, **changes: Any) -> "Params":
        """A copy with some fields changed; an unknown name fails loudly."""
        known = {f.name for f in fields(self)}
        unknown = sorted(set(changes) - known)
        if unknown:
            raise ValueError(f"unknown parameter(s): {', '.join(unknown)}")
        return dataclasses.replace(self, **changes)

    def with_strings(self, assignments: list[str]) -> "Params":
        """Apply ``NAME=VALUE`` strings (the CLI's ``--set``), converting to each field's type."""
        changes: dict[str, Any] = {}
        defaults = {f.name: f.default for f in fields(self)}
        for item in assignments:
            name, sep, raw = item.partition("=")
            name = name.strip()
            if not sep or not name:
                raise ValueError(f"--set expects NAME=VALUE, got {item!r}")
            if name not in defaults:
                raise ValueError(f"unknown parameter {name!r}")
            changes[name] = _convert(name, raw.strip(), defaults[name])
        return self.replace(**changes)

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    def __repr__(self) -> str:
        """``Params(...)`` with only the fields that differ from the defaults (docs/metrics.md's values)."""
        changed = [f"{f.name}={getattr(self, f.name)!r}" for f in fields(self) if getattr(self, f.name) != f.default]
        return f"Params({', '.join(changed)})"


def _convert(name: str, raw: str, default: Any) -> Any:
    if name == "k_center":
        return None if raw.lower() in ("none", "auto", "") else int(raw)
    try:
        if isinstance(default, bool):
            return raw.lower() in ("1", "true", "yes", "on")
        if isinstance(default, int):
            return int(raw)
        if isinstance(default, float):
            return float(raw)
    except ValueError:
        raise ValueError(f"parameter {name}: cannot read {raw!r} as {type(default).__name__}") from None
    return raw


def k_center_for(n_skeletal: int, params: Params) -> int:
    """docs/metrics.md 3: k = round(0.01 N_s), <10 -> 10, >50 -> 30 (reference-tool quirk), unless set."""
    if params.k_center is not None:
        return int(params.k_center)
    from .geometry import matlab_round

    k = matlab_round(0.01 * n_skeletal)
    if k < 10:
        k = 10
    if k > 50:
        k = 30
    return k
