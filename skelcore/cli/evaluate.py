"""``skelcore evaluate``: score a skeleton against its cloud and print the paper's table, SkelScope's
coverage row, the reference comparison, the "ground truth" block and the trust warnings (exit 3 on a warning with --strict)."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from ..errors import SkelInputError
from ..params import Params
from ..skeleton_mapping import check_mapping, map_skeleton
from .common import (clear_progress_line, format_defects, format_ground_truth, format_reference, format_table, params_from_args, positive_float,
                     print_warnings, stderr_progress)

__all__ = ["register", "run_evaluate", "EXIT_WARNINGS"]

#: exit status of ``--strict`` when the evaluation carries a trust warning (2 stays "bad input")
EXIT_WARNINGS = 3


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``skelcore evaluate CLOUD ...``."""
    p = sub.add_parser(
        "evaluate",
        help="score a skeleton against its point cloud",
        description="Score a skeleton against its cloud. Exit 0 on success, 2 on bad input or an "
        "output that cannot be written (one line on stderr), 3 with --strict when a warning was given.",
    )
    p.add_argument("cloud", help="original point cloud (PLY, PCD, LAS/LAZ, XYZ/TXT/CSV/PTS, NPY/NPZ, OBJ, OFF)")
    p.add_argument("--skeletal", metavar="F",
                   help="skeletal point set (one row per cloud row, or see --skeletal-index / --correspondence); "
                   "a CGAL correspondence polylines file brings its own index")
    p.add_argument("--skeletal-index", metavar="F",
                   help="one 0-based cloud row per skeletal row (NPY, or one integer per line)")
    p.add_argument("--correspondence", choices=("auto", "reverse"), default="auto",
                   help="reverse: map every cloud point to its nearest skeletal point (or, with only --curve, "
                   "its nearest point on the curve) and score that pointwise set (default auto)")
    p.add_argument("--curve", metavar="F", help="curve skeleton (PLY with edges, OBJ, CG, SWC, polylines, PyGEL .graph, JSON/NPZ)")
    p.add_argument("--reference-curve", metavar="F",
                   help="ground-truth curve skeleton to compare --curve with (in the cloud's frame; its vertex radius "
                   "when the file has one, else estimated from the cloud): prints a \"ground truth\" block")
    p.add_argument("--reference-facts", metavar="F",
                   help="how far each reference vertex lies outside the surface the cloud was drawn from (CSV with the "
                   "columns vertex and outside_by_radii, as a real suite's truth/ID_gt_facts.csv): the ground truth "
                   "block adds precision, recall and F1 on the reference the cloud can show (docs/metrics.md 5.3.1)")
    p.add_argument("--skeleton-scale", type=positive_float, metavar="S", default=1.0,
                   help="multiply skeletal and curve coordinates by S (e.g. voxel size) ...")
    p.add_argument("--skeleton-offset", type=float, nargs=3, metavar=("X", "Y", "Z"), default=(0.0, 0.0, 0.0),
                   help="... then add this offset, to bring them into the cloud's frame")
    p.add_argument("--json", metavar="F", help="write the results as JSON")
    p.add_argument("--per-point", metavar="PREFIX",
                   help="write PREFIX_skeletal.csv, PREFIX_curve_samples.csv, PREFIX_curve_vertices.csv, PREFIX_cloud.csv")
    p.add_argument("--barcodes", metavar="F", help="write every H0 bar of both diagrams as CSV")
    p.add_argument("--export-ply", metavar="DIR", help="write coloured PLY files of the skeleton into DIR")
    p.add_argument("--boundedness-method", choices=("rays", "paper"), help="boundedness estimator (default rays)")
    p.add_argument("--curve-sampling", metavar="{toolbox,invariant}",
                   help="where the curve's samples go: toolbox (default, the reference tool's: depends on how the "
                   "curve's vertices are numbered) or invariant (each branch from a canonical end; docs/metrics.md 3)")
    p.add_argument("--viewpoint", type=float, nargs=3, action="append", metavar=("X", "Y", "Z"),
                   help="a sensor position in the cloud's units (repeatable): boundedness counts only what the "
                   "sensors could have seen (a scan from some sides only; default: a PCD's VIEWPOINT when set)")
    p.add_argument("--remove-outliers", action="store_true",
                   help="evaluate without the cloud's stray points (and their skeletal rows); found and reported anyway")
    p.add_argument("--cap-openings", action="store_true",
                   help="close small flat openings of the cloud with points on their planes for boundedness "
                   "(as the paper did for its cave)")
    p.add_argument("--density-aware", action="store_true",
                   help="boundedness casts also against points filled into the cloud's sparsely sampled parts "
                   "(docs/metrics.md 6.8; default: the paper's boundedness)")
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[], help="set any Params field (repeatable)")
    p.add_argument("--strict", action="store_true", help="exit 3 when the evaluation carries a warning")
    p.add_argument("--quiet", action="store_true", help="do not print progress")
    p.set_defaults(func=run_evaluate)


def _check_outputs(args: argparse.Namespace, guard: tuple[str, ...]) -> None:
    """Every output can be written, checked before the (possibly long) evaluation."""
    from ..io.atomic import check_output_dir, check_output_file

    if args.json:
        check_output_file(args.json, guard)
    if args.barcodes:
        check_output_file(args.barcodes, guard)
    if args.per_point:
        check_output_file(f"{args.per_point}_skeletal.csv", guard)
    if args.export_ply:
        check_output_dir(args.export_ply)


def _viewpoints(args: argparse.Namespace) -> np.ndarray | None:
    """``--viewpoint`` (repeatable), else a PCD cloud's VIEWPOINT when it is not PCL's default."""
    from ..io import pcd_viewpoint

    if args.viewpoint:
        v = np.asarray(args.viewpoint, dtype=float)
        if not np.all(np.isfinite(v)):
            raise SkelInputError("--viewpoint: X Y Z must be finite numbers")
        return v
    v = pcd_viewpoint(args.cloud)
    if v is not None:
        print(f"skelcore: viewpoint {v[0]:g} {v[1]:g} {v[2]:g} from the PCD header of {args.cloud} "
              "(boundedness counts what it could see)", file=sys.stderr)
        return v[None, :]
    return None


def print_scan_notes(scan, args: argparse.Namespace) -> None:
    """One stderr line per thing the scan options did: the outliers removed, each opening capped or not."""
    if scan is None:
        return
    if args.remove_outliers and scan.outliers is not None:
        n_cloud = len(scan.outliers.get("removed_rows") or [])
        print(f"skelcore: --remove-outliers: {n_cloud} cloud point(s) and {scan.skeletal_rows_removed} skeletal "
              "row(s) left out", file=sys.stderr)
    if args.cap_openings:
        openings = scan.openings or []
        if not openings:
            print("skelcore: --cap-openings: the cloud has no openings", file=sys.stderr)
        for i, o in enumerate(openings):
            where = " ".join(f"{x:.4g}" for x in o["centre"])
            if o.get("capped"):
                print(f"skelcore: --cap-openings: capped opening {i + 1} ({o['kind']} at {where}) with "
                      f"{o['n_fill']} points", file=sys.stderr)
            else:
                print(f"skelcore: --cap-openings: not capped: opening {i + 1} ({o['kind']} at {where}): "
                      f"{o.get('refused')}", file=sys.stderr)


def _with_curve_sampling(params: Params, method: str | None) -> Params:
    """``--curve-sampling``: a one-line SkelInputError on a value other than toolbox or invariant."""
    from ..metrics.curve_sampling import SAMPLING_METHODS

    if method is None:
        return params
    if method not in SAMPLING_METHODS:
        raise SkelInputError(f"--curve-sampling must be {' or '.join(SAMPLING_METHODS)}, got {method!r}")
    return params.replace(curve_sampling=method)


def run_evaluate(args: argparse.Namespace) -> int:
    from .. import io
    from ..stages import evaluate
    from ..io.correspondence_files import load_skeletal, load_skeletal_index
    from ..io.export import export_ply

    params = _with_curve_sampling(params_from_args(args), args.curve_sampling)
    if args.density_aware:
        params = params.replace(boundedness_density_aware=True)
    if not (args.skeletal or args.curve):
        raise SkelInputError("nothing to evaluate: give --skeletal and/or --curve")
    if args.skeletal_index and not args.skeletal:
        raise SkelInputError("--skeletal-index needs --skeletal")
    if args.reference_curve and not args.curve:
        raise SkelInputError("--reference-curve is compared with a curve skeleton: give --curve")
    if args.reference_facts and not args.reference_curve:
        raise SkelInputError("--reference-facts describes the reference's vertices: give --reference-curve")
    if args.skeletal_index and args.correspondence == "reverse":
        raise SkelInputError("give either --skeletal-index or --correspondence reverse, not both")
    inputs = {"cloud": args.cloud, "skeletal": args.skeletal, "curve": args.curve,
              "skeletal_index": args.skeletal_index, "reference_curve": args.reference_curve,
              "reference_facts": args.reference_facts}
    guard = tuple(p for p in inputs.values() if p)
    _check_outputs(args, guard)
    try:
        check_mapping(args.skeleton_scale, tuple(args.skeleton_offset))
    except ValueError as exc:  # argparse's float takes "nan" and "inf"
        raise SkelInputError(f"--skeleton-scale/--skeleton-offset: {exc}") from None
    if args.barcodes and args.skeletal is None and args.correspondence != "reverse":
        raise SkelInputError("--barcodes needs --skeletal (barcodes compare the cloud with the skeletal set)")

    cloud = io.load_cloud(args.cloud)
    skeletal = index = None
    if args.skeletal:
        skeletal, index, fmt = load_skeletal(args.skeletal, cloud)
        if index is not None and args.skeletal_index:
            raise SkelInputError("is a CGAL correspondence file, which carries its own index: drop --skeletal-index", args.skeletal)
        if index is not None and args.correspondence == "reverse":
            index = None  # the user asked for reverse projection instead
        if args.skeletal_index:
            index = load_skeletal_index(args.skeletal_index, len(skeletal), len(cloud))
    curve = io.load_curve(args.curve) if args.curve else None
    reference = io.load_curve(args.reference_curve) if args.reference_curve else None
    outside = _reference_facts(args.reference_facts, reference)

    skeletal, curve = map_skeleton(skeletal, curve, float(args.skeleton_scale), tuple(args.skeleton_offset))

    viewpoints = _viewpoints(args)
    progress = stderr_progress(args.quiet)
    ev = evaluate(cloud, skeletal, curve, params, progress=progress, skeletal_index=index,
                  correspondence=args.correspondence, reference_curve=reference, reference_outside=outside,
                  inputs=inputs, viewpoints=viewpoints, remove_outliers=args.remove_outliers,
                  cap_openings=args.cap_openings)
    clear_progress_line(progress)
    scores = ev.scores()
    print(format_table(scores))
    if ev.reference is not None:
        print(format_reference(scores))
    if ev.ground_truth is not None:
        print(format_ground_truth(ev.ground_truth.to_dict()))
    corr = f"correspondence: {ev.correspondence}; " if ev.correspondence else ""
    sampling = "" if params.curve_sampling == "toolbox" else f"curve sampling: {params.curve_sampling}; "
    print(f"{corr}boundedness estimator: {params.boundedness_method}; {sampling}total {ev.timings['total']:.2f} s")
    print(format_defects(ev.warning_dicts(), ev.not_computed))
    print_warnings(ev.warning_dicts())
    print_scan_notes(ev.scan, args)
    if "coverage" in ev.not_computed:  # the others come with their warning (no_correspondence)
        print(f"skelcore: not computed: coverage: {ev.not_computed['coverage']}", file=sys.stderr)
    if args.json:
        ev.write_json(args.json, inputs=guard)
    if args.per_point:
        ev.write_per_point(args.per_point, inputs=guard)
    if args.barcodes:
        if ev.topology is None:
            raise SkelInputError("--barcodes: no barcodes without a correspondence (see the warning)")
        ev.write_barcodes(args.barcodes, inputs=guard)
    if args.export_ply:
        mapping = (float(args.skeleton_scale), tuple(args.skeleton_offset))
        export_ply(ev, args.export_ply, inputs=guard, mappings={"skeletal": mapping, "curve": mapping})
    if args.strict and ev.warnings:
        print(f"skelcore: --strict: {len(ev.warnings)} warning(s), exit {EXIT_WARNINGS}", file=sys.stderr)
        return EXIT_WARNINGS
    return 0


def _reference_facts(path: str | None, reference):
    """``--reference-facts``: the facts file's outside_by_radii per vertex of the loaded reference
    (its rows are the reference file's vertices; the cleaned curve's ``vertex_map`` picks them)."""
    if not path:
        return None
    from ..benchmark.neurons import read_outside_radii

    out = read_outside_radii(path)
    if len(out) <= int(reference.vertex_map.max()):
        raise SkelInputError(f"the facts have {len(out)} rows for a reference of {int(reference.vertex_map.max()) + 1} vertices", path)
    return out[reference.vertex_map]
