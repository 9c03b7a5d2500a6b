# The two commands of the README: `make demo` and `make test`. Each creates the
# virtual environment, installs what is needed (system packages too, as root),
# then runs.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
OUT    ?= demo-out

.PHONY: demo test lint setup system-packages clean

setup: $(STAMP)

system-packages:
	@PYTHON=$(PYTHON) bash tools/ensure-system-packages.sh

$(STAMP): pyproject.toml | system-packages
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	@touch $(STAMP)

demo: system-packages $(STAMP)
	$(PY) -m workbench reproduce
	$(PY) -m workbench illuminants show d65-two-peak

lint: $(STAMP)
	$(VENV)/bin/lint-imports

test: system-packages $(STAMP) lint
	$(PY) -m pytest -q

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .import_linter_cache
