"""``skelcore figure DIR -o FIG.png|.pdf``: the paper's graphic table alone, for a paper.

One row per (shape, condition, method) that finished (first seed), columns: the skeleton over the
cloud, the two H0 barcodes (drawn as vectors), and the skeleton coloured by boundedness,
centeredness and smoothness (the pyvista renders of :mod:`.render`, cached in ``DIR/renders``),
with a shared 0..1 colour bar. matplotlib is imported inside the function.
"""

from __future__ import annotations

import os
from typing import Sequence

from ..errors import SkelInputError
from ..io.atomic import atomic_open
from .render import VIEWS, draw_barcodes, render_job
from .job_store import Store
from ..scores import format_score

__all__ = ["make_figure"]


def make_figure(out_dir: str | os.PathLike, output: str | os.PathLike, *, shapes: Sequence[str] | None = None,
                methods: Sequence[str] | None = None, conditions: Sequence[str] | None = None, dpi: int = 150) -> int:
    """Draw the figure; returns the number of rows. SkelInputError on a bad folder, filter or suffix."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib import image as mpimg
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import ListedColormap, Normalize
    from matplotlib.figure import Figure

    from .. import colors
    from .run_compare import load_index

    output = os.fspath(output)
    ext = os.path.splitext(output)[1].lower()
    if ext not in (".png", ".pdf", ".svg"):
        raise SkelInputError("figure must end in .png, .pdf or .svg", output)
    index = load_index(out_dir)
    for given, known, what in ((shapes, index["shapes"], "shape"), (methods, index["methods"], "method"),
                               (conditions, index["conditions"], "condition")):
        unknown = sorted(set(given or ()) - set(known))
        if unknown:
            raise SkelInputError(f"unknown {what}(s) {', '.join(unknown)} (the run has: {', '.join(known)})", out_dir)
    store = Store(out_dir)
    order = {n: i for i, n in enumerate(index["shapes"])}
    picked = []
    seen = set()
    for j in sorted(index["jobs"], key=lambda j: (order[j["shape"]], index["conditions"].index(j["condition"]),
                                                  index["methods"].index(j["method"]))):
        if (shapes and j["shape"] not in shapes) or (methods and j["method"] not in methods) or \
                (conditions and j["condition"] not in conditions):
            continue
        ident = (j["shape"], j["condition"], j["method"])
        rec = store.get(j["key"])
        if ident in seen or rec is None or rec.get("status") != "ok":
            continue
        seen.add(ident)
        picked.append((j, rec))
    if not picked:
        raise SkelInputError("no finished job matches: nothing to draw", out_dir)

    n = len(picked)
    fig = Figure(figsize=(2.0 * len(VIEWS) + 1.2, 2.0 * n + 0.6), dpi=dpi)
    titles = {"skeleton": "skeleton", "barcodes": "H0 barcodes", "boundedness": "boundedness",
              "centeredness": "centeredness", "smoothness": "smoothness"}
    gs = fig.add_gridspec(n, len(VIEWS) + 1, width_ratios=[0.6] + [1.0] * len(VIEWS), wspace=0.05, hspace=0.08)
    for i, (j, rec) in enumerate(picked):
        arrays = store.arrays(j["key"])
        pngs = render_job(out_dir, j["key"], arrays)
        ax = fig.add_subplot(gs[i, 0])
        ax.set_axis_off()
        sc = rec.get("scores", {})
        topo = "" if sc.get("d_B") is None else f"\nd_B {format_score(sc['d_B'], 4)}\nd_Wp {format_score(sc['d_Wp'], 4)}"
        ax.text(0.0, 0.5, f"{j['shape']}\n{rec.get('label', j['condition'])}\n{j['method']}{topo}", fontsize=7,
                va="center", ha="left", transform=ax.transAxes)
        for k, view in enumerate(VIEWS):
            ax = fig.add_subplot(gs[i, k + 1])
            if view == "barcodes":
                draw_barcodes(ax, arrays)
                ax.tick_params(labelsize=5)
                ax.xaxis.label.set_size(5)
            else:
                ax.imshow(mpimg.imread(pngs[view]))
                ax.set_axis_off()
            if i == 0:
                ax.set_title(titles[view], fontsize=8)
    lut = colors.lookup_table("viridis") / 255.0
    bar = fig.colorbar(ScalarMappable(Normalize(0, 1), ListedColormap(lut)), ax=fig.axes, orientation="horizontal",
                       fraction=0.6 / (2.0 * n + 0.6), pad=0.02, aspect=60)
    bar.set_label("local value (magenta = invalid)", fontsize=7)
    bar.ax.tick_params(labelsize=6)
    folder = os.path.dirname(os.path.abspath(output))
    if not os.path.isdir(folder):
        raise SkelInputError("output folder does not exist", folder)
    with atomic_open(output, "wb") as fh:
        fig.savefig(fh, format=ext[1:], bbox_inches="tight")
    return n
