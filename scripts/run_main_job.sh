#!/usr/bin/env bash
# `make run`: score the bundled sample with the CLI, then open the viewer on it. With no display,
# the viewer does its scripted run under Xvfb and says where the picture is.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
S=resources/samples
[ -f "$S/yshape_cloud.ply" ] || $PY scripts/make_samples.py
mkdir -p out
echo "== skelcore evaluate $S/yshape_cloud.ply =="
.venv/bin/skelcore evaluate "$S/yshape_cloud.ply" --skeletal "$S/yshape_lbc_skeletal.ply" --curve "$S/yshape_lbc_curve.ply" \
  --json out/yshape.json --per-point out/yshape --barcodes out/yshape_barcodes.csv --export-ply out/yshape_ply
echo "results written to out/ (yshape.json, yshape_*.csv, yshape_ply/)"
if ! $PY -c "import app.main_window" 2>/dev/null; then
  exit 0
fi
ARGS=("$S/yshape_cloud.ply" --skeletal "$S/yshape_lbc_skeletal.ply" --curve "$S/yshape_lbc_curve.ply" --metric centeredness)
if [ -n "${DISPLAY:-}" ] && [ -z "${CI:-}" ]; then
  exec .venv/bin/skelscope "${ARGS[@]}"
fi
echo "no display: scripted viewer run under Xvfb"
xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/skelscope "${ARGS[@]}" --screenshot out/yshape_viewer.png --quit
echo "viewer screenshot: $(pwd)/out/yshape_viewer.png"
