# fsi-lab: the two set-up commands are `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
export QT_QPA_PLATFORM ?= offscreen

.PHONY: demo gui qt-libs screenshots test lint bench validate clean h5dump-tool

# A venv with the package (editable) and the given extras; rebuilt when pyproject.toml changes.
$(VENV)/.installed-%: pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[$*]'
	touch $@

# h5dump reads run files in the crash-safety tests; install it where we may.
h5dump-tool:
	@command -v h5dump >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    (apt-get update -qq && apt-get install -y -qq hdf5-tools) >/dev/null; \
	  else echo "h5dump is missing: install your distribution's hdf5-tools package" >&2; exit 1; fi; }

demo: $(VENV)/.installed-gui
	$(BIN)/fsi-lab run profiles/wet-beam-sim.toml --out runs

# The X11 libraries Qt's xcb platform plugin loads and PySide6's wheels do not carry
# (libxcb-cursor0, libxcb-icccm4, libxcb-keysyms1, ...: the list is in fsi_lab/gui/display.py);
# installed where we may, as for hdf5-tools, named otherwise. --screenshot needs none of them.
qt-libs: $(VENV)/.installed-gui
	@missing="$$($(BIN)/python -m fsi_lab.gui.display --missing-packages)" || exit 1; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    echo "installing the Qt system libraries: $$missing" >&2; \
	    (apt-get update -qq && apt-get install -y -qq --no-install-recommends $$missing) >/dev/null; \
	  else echo "the GUI needs these system packages (Debian/Ubuntu names): $$missing" >&2; \
	    exit 1; fi; fi

# The desktop application on the demo profile, on this machine's display (not offscreen,
# unless QT_QPA_PLATFORM was set by the caller).
gui: $(VENV)/.installed-gui qt-libs
	$(if $(filter environment% command%,$(origin QT_QPA_PLATFORM)),,env -u QT_QPA_PLATFORM) \
	  $(BIN)/fsi-lab gui profiles/wet-beam-sim.toml

# The README's pictures of each tab at 1366x768 (offscreen; about a minute).
screenshots: $(VENV)/.installed-gui
	$(BIN)/python docs/screenshots.py

# ruff first: a lint error stops the run before the tests start. The tests run in
# TEST_WORKERS processes (pytest-xdist), a test file to a worker so that each file's fixtures
# are built once; TEST_WORKERS=0 runs them in this process. The 20 slowest tests are listed
# at the end: the suite must stay under 15 minutes on two cores.
TEST_WORKERS ?= 2
test: $(VENV)/.installed-dev,gui h5dump-tool
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -n $(TEST_WORKERS) --dist loadfile --durations=20

# ruff with the rule set stated in pyproject.toml ([tool.ruff.lint]); LINT narrows it to some
# paths (make lint LINT="fsi_lab/testing tests/test_hooks.py").
LINT ?= .
lint: $(VENV)/.installed-dev,gui
	$(BIN)/ruff check $(LINT)

# The benchmark environment has the references we compare with (pysdkit's HVD); they are
# not dependencies of fsi-lab, so they live in a venv of their own.
BENCH_VENV := .venv-bench
$(BENCH_VENV)/.installed: pyproject.toml
	test -x $(BENCH_VENV)/bin/python || $(PYTHON) -m venv $(BENCH_VENV)
	$(BENCH_VENV)/bin/python -m pip install --quiet --upgrade pip
	$(BENCH_VENV)/bin/python -m pip install --quiet -e '.[gui,cluster]' pysdkit
	touch $@

bench: $(BENCH_VENV)/.installed
	$(BENCH_VENV)/bin/python -m bench

# The validation matrix: Monte-Carlo trials of records with known truth, with a peer method in
# the same run (TRIALS per case; a name filter may follow, e.g. make validate ARGS="20 Duffing").
ARGS ?= 40
validate: $(VENV)/.installed-dev,gui
	$(BIN)/python -m validation $(ARGS)

clean:
	rm -rf $(VENV) $(BENCH_VENV) runs build *.egg-info
