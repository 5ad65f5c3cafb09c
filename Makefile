# The two commands a newcomer needs: `make demo` and `make test`. Each builds .venv itself.
VENV ?= .venv
# the Python that builds .venv (3.11 or newer; 3.12 and later get JAX 0.12)
PYTHON ?= python3
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

DOCS_STAMP := $(VENV)/.installed-docs

.PHONY: demo test test-all lint bench studies docs clean

# Installs into .venv with uv where it is on PATH or can be bootstrapped into .venv from
# PyPI (a fresh set-up in about 20 s), else with pip (about a minute).
define install
	if command -v uv >/dev/null 2>&1; then UV=uv; \
	elif $(PY) -m pip install --quiet --disable-pip-version-check uv >/dev/null 2>&1; then UV=$(VENV)/bin/uv; fi; \
	if [ -n "$$UV" ] && $$UV pip install --quiet --python $(PY) $(1); then :; \
	else $(PY) -m pip install --quiet --disable-pip-version-check $(1); fi
endef

# Then the bytecode of magdesign and of every module the command imports is written (uv
# writes none; compiling all of site-packages costs 15 s of CPU, these 3 s), so that where
# Python may not write it (PYTHONDONTWRITEBYTECODE, a read-only .venv) no run compiles its
# imports (2 s of CPU a run).
$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@$(call install,-e '.[test]')
	$(PY) -m compileall -q magdesign >/dev/null
	PYTHONDONTWRITEBYTECODE= $(PY) -c "import magdesign.cli"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/magdesign solve --timing

# the fast tier, which touches every module; test-all adds the tests marked slow. Each
# module runs on one worker, in the order tests/conftest.py gives (the longest first):
# xdist would otherwise order the modules by their number of tests.
XDIST := -n 2 --dist loadscope --no-loadscope-reorder

test: $(STAMP)
	$(PY) -m pytest -q $(XDIST) -m "not slow"

test-all: $(STAMP)
	$(PY) -m pytest -q $(XDIST) --durations=15

# ruff: lint and format, as configured in pyproject.toml
lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

$(DOCS_STAMP): pyproject.toml $(STAMP)
	@$(call install,-e '.[docs]')
	touch $(DOCS_STAMP)

# the site, built offline into site/ (mkdocs.yml: strict, so a warning fails it)
docs: $(DOCS_STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --site-dir site

bench: $(STAMP)
	for f in benchmarks/*.py; do $(PY) $$f || exit 1; done

studies: $(STAMP)
	for f in studies/[!_]*.py; do $(PY) $$f || exit 1; done

clean:
	rm -rf $(VENV) studies/out site
