# One-command set-up on a fresh Debian machine as root: system packages, .venv, the project.
# chromium: the test suite renders skelcore compare's report.html in headless Chromium.
# gcc, python3-dev: the install compiles the kernels (skelcore/metrics/_raycast.c, _balls.c, _centroids.c, _rings.c, _emst.c, _components.c, _surround.c, _point_passes.c, _region_links.c; skelcore/skeleton/_farthest.c).
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
APT_PACKAGES := xvfb xauth libxcb-icccm4 libxcb-keysyms1 libxcb-cursor0 libxcb-image0 \
	libxcb-render-util0 libxcb-xinerama0 libxcb-shape0 libxcb-randr0 libxcb-xkb1 libxkbcommon-x11-0 \
	libegl1 libgl1 libdbus-1-3 libfontconfig1 chromium gcc python3-dev

.PHONY: setup system venv run test test-interop docs screenshots bench samples clean

system:
	@missing=""; for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing system packages:$$missing"; \
	  if [ "$$(id -u)" = 0 ]; then SUDO=""; else SUDO="sudo"; fi; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing >/dev/null; \
	fi

$(VENV)/.installed: pyproject.toml setup.py skelcore/metrics/_raycast.c skelcore/metrics/_balls.c skelcore/metrics/_centroids.c skelcore/metrics/_rings.c skelcore/metrics/_pairwise_sum.h skelcore/metrics/_emst.c skelcore/metrics/_components.c skelcore/metrics/_surround.c skelcore/metrics/_point_passes.c skelcore/metrics/_region_links.c skelcore/skeleton/_farthest.c
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	touch $@

venv: $(VENV)/.installed

setup: system venv

run: setup
	bash scripts/run_main_job.sh

# Two workers (pytest-xdist), one test file per worker at a time (--dist loadfile: a file's fixtures are
# built once), the files heaviest first by tests/file_costs.txt (tests/conftest.py); each worker has its own
# Xvfb (pytest-xvfb). One worker took 8.7 min, two 4.9 (docs/guide/testing.md).
test: setup
	$(PY) -m pytest -q -p no:cacheprovider -n 2 --dist loadfile tests

# Open3D (a ~400 MB wheel) and cloud-volume are kept out of `make test`: this installs the interop
# extra and runs the tests of other libraries' objects, which skip Open3D's cases without it.
test-interop: setup
	$(PY) -m pip install -q -e '.[interop]'
	$(PY) -m pytest -q -p no:cacheprovider tests/engine/test_interop_objects.py tests/engine/test_interop_outputs.py \
		tests/engine/test_io_tool_formats.py tests/engine/test_io_convert.py

# The documentation site (docs/conf.py) into docs/_build/html, warnings as errors; the gallery's scripts
# (examples/gallery/plot_*.py) run during the build. The `test` extra holds the docs extra's packages.
docs: setup
	MPLBACKEND=Agg $(PY) -m sphinx -W --keep-going -q -b html docs docs/_build/html
	@echo "open docs/_build/html/index.html"

screenshots: setup
	xvfb-run -a -s "-screen 0 1600x1000x24" $(PY) scripts/make_screenshots.py
	xvfb-run -a -s "-screen 0 1366x768x24" $(PY) scripts/make_screenshots.py --laptop
	xvfb-run -a -s "-screen 0 1920x1080x24" $(PY) scripts/make_screenshots.py --laptop
	QT_SCALE_FACTOR=1.5 xvfb-run -a -s "-screen 0 1366x768x24" $(PY) scripts/make_screenshots.py --laptop

# The benchmark suite (benchmarks/bench_*.py, pytest-benchmark; not part of `make test`), then its table in
# docs/benchmark_results.md: each case's median and its ratio to the anchor (gudhi's Rips H0 of the hammer)
# timed in the same run. The 1M-point cases: make bench BENCH_ARGS=--bench-large
BENCH_JSON ?= build/benchmark_results.json
BENCH_ARGS ?=
bench: setup
	mkdir -p $(dir $(BENCH_JSON))
	$(PY) -m pytest -p no:cacheprovider benchmarks --benchmark-json=$(BENCH_JSON) $(BENCH_ARGS)
	$(PY) benchmarks/report.py $(BENCH_JSON) -o docs/benchmark_results.md --readme README.md

samples: setup
	$(PY) scripts/make_samples.py

clean:
	rm -rf $(VENV) build *.egg-info docs/_build docs/gallery
