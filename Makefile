# The two commands of the README: `make demo` and `make test`. Each creates the
# virtual environment, installs what is needed (system packages too, as root),
# then runs.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
OUT    ?= demo-out

.PHONY: demo test lint docs setup system-packages clean

setup: $(STAMP)

system-packages:
	@PYTHON=$(PYTHON) bash tools/ensure-system-packages.sh

$(STAMP): pyproject.toml | system-packages
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	@touch $(STAMP)

# The main job on the simulated hardware: a full calibration of the simulated
# headset (two physical effects hidden in it) through the real CS-2000 driver
# talking to the emulator on a pseudo-terminal, at 1/500 of real timing; then
# the diagnosis, the exported profile, the light colours for this headset,
# and the paper's tables reproduced.
demo: system-packages $(STAMP)
	rm -rf $(OUT)
	$(PY) -m workbench measure --simulate --effect channel-interaction:0.1 \
	    --effect black-offset:0.006 --time-scale 0.002 --plan paper --seed 1 --out $(OUT)/session
	$(PY) -m workbench diagnose $(OUT)/session --export $(OUT)/headset.vrprofile.json \
	    --report $(OUT)/diagnosis.html
	$(PY) -m workbench illuminants show d65-two-peak --profile $(OUT)/headset.vrprofile.json
	$(PY) -m workbench reproduce
	@echo "report: $(OUT)/diagnosis.html   profile: $(OUT)/headset.vrprofile.json"

lint: $(STAMP)
	$(VENV)/bin/lint-imports

# The documentation site (docs/, Sphinx + MyST + numpydoc) into docs/_build/html,
# read afresh (-E) with warnings as errors: a broken link or reference, or a
# docstring that does not parse, fails it. The API pages are regenerated.
docs: $(STAMP)
	rm -rf docs/api/generated
	$(PY) -m sphinx -b html -E -W --keep-going -q -j auto docs docs/_build/html

# The suite on every core: pytest-xdist, one worker a core; an idle worker takes tests queued
# behind a busy one (worksteal), so the 940-session acceptance suite, about half the CPU time,
# does not hold up the tests queued behind it. TEST_WORKERS=0 runs it in one process.
# One BLAS thread a worker: the workers already fill the cores, and OpenBLAS's own threads on
# top of them (one per core by default) fought them for the cores: the suite took 627 s on
# 2 cores with them, 458 s without (the acceptance suite 307 → 199 s), results the same.
TEST_WORKERS ?= auto
test: system-packages $(STAMP) lint docs
	OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 \
	    $(PY) -m pytest -q -n $(TEST_WORKERS) --dist worksteal

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .import_linter_cache docs/_build docs/api/generated
