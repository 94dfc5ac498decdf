"""examples/quickstart.ipynb executed in a real Jupyter kernel (nbclient + ipykernel) running this
interpreter, and its outputs checked: the picture of ``ev.show``, the summary table of
``ev``'s HTML repr, show_ab's picture and tables, and the defects naming the truncation."""

from __future__ import annotations

import base64
import io
import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")
pytest.importorskip("pyvista")

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
KERNEL = "skelscope-test"


@pytest.fixture(scope="module")
def executed(tmp_path_factory):
    """The notebook after a run in a kernel whose spec (written to a temporary Jupyter path) starts
    ``sys.executable -m ipykernel_launcher``: the venv's Python, whatever kernels the machine has."""
    root = tmp_path_factory.mktemp("jupyter")
    spec = root / "kernels" / KERNEL
    spec.mkdir(parents=True)
    spec.joinpath("kernel.json").write_text(json.dumps({
        "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": "SkelScope (test)", "language": "python"}))
    mp = pytest.MonkeyPatch()
    mp.setenv("JUPYTER_PATH", str(root))
    mp.setenv("JUPYTER_RUNTIME_DIR", str(root / "runtime"))
    mp.setenv("IPYTHONDIR", str(root / "ipython"))  # no user profile or startup file in the run
    try:
        nb = nbformat.read(EXAMPLES / "quickstart.ipynb", as_version=4)
        nbclient.NotebookClient(nb, kernel_name=KERNEL, timeout=600, startup_timeout=300,
                                resources={"metadata": {"path": str(EXAMPLES)}}).execute()
    finally:
        mp.undo()
    return nb


def _cell(nb, text: str):
    found = [c for c in nb.cells if c.cell_type == "code" and text in c.source]
    assert len(found) == 1, text
    return found[0]


def _data(cell, mime: str) -> list:
    return [o["data"][mime] for o in cell.outputs if mime in o.get("data", {})]


def _png(b64: str) -> np.ndarray:
    from matplotlib import image as mpimg

    img = mpimg.imread(io.BytesIO(base64.b64decode(b64)), format="png")
    return np.rint(img[..., :3] * 255).astype(int)


def _magenta(img: np.ndarray) -> int:
    return int((np.abs(img - np.array([255, 0, 255])) <= 30).all(axis=2).sum())


def test_the_notebook_was_saved_without_outputs():
    nb = nbformat.read(EXAMPLES / "quickstart.ipynb", as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code")


@pytest.mark.slow
def test_show_draws_a_picture_in_the_cell(executed):
    pngs = _data(_cell(executed, 'ev.show("smoothness")'), "image/png")
    assert len(pngs) == 1
    img = _png(pngs[0])
    assert img.shape[0] > 200 and img.shape[1] > 200
    assert _magenta(img) > 10  # the curve's ends and junction have no smoothness (NaN, docs/metrics.md 4 and 5.5)
    assert len(_data(_cell(executed, "ev.show_barcodes()"), "image/png")) == 1


@pytest.mark.slow
def test_the_evaluation_shows_the_papers_table(executed):
    html = _data(_cell(executed, "ev = skelcore.evaluate("), "text/html")
    assert len(html) == 1
    text = html[0]
    assert "<th>skeletal points</th><th>curve skeleton</th>" in text
    for metric in ("boundedness", "centeredness", "smoothness"):
        assert re.search(rf"<td>{metric}</td><td>[01]\.\d{{3}} \(n=4000\)</td><td>[01]\.\d{{3}} \(n=\d+\)</td>", text)
    assert re.search(r"<td>d_B / d_Wp</td><td>0\.\d{4} / 0\.\d{4}</td>", text)
    assert "defects:</b> none found" in text


@pytest.mark.slow
def test_show_ab_and_the_defects_name_the_truncation(executed):
    cell = _cell(executed, "skelcore.show_ab(")
    img = _png(_data(cell, "image/png")[0])
    assert img.shape[1] == 2 * img.shape[0] * 640 // 480  # two 640 x 480 panels
    tables = _data(cell, "text/html")[0]
    assert tables.count('<table class="skelscope-table">') == 2
    cao, cut = tables.split("truncated")[0], tables.split("truncated")[1]
    assert "none found" in cao and "[incomplete] the curve skeleton does not reach 1 part" in cut
    out = "".join(o.get("text", "") for o in _cell(executed, "ev_cut.warnings").outputs)
    assert re.search(r"^\[incomplete\] .*completeness 0\.\d+$", out, re.M)
    assert "completeness of the truncated curve: 0." in out
