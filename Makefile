# The two commands a newcomer needs: `make demo` and `make test`. Each builds .venv itself.
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

DOCS_STAMP := $(VENV)/.installed-docs

.PHONY: demo test lint bench studies docs clean

$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/magdesign solve --timing

test: $(STAMP)
	$(PY) -m pytest -q -n 2

# ruff: lint and format, as configured in pyproject.toml
lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

$(DOCS_STAMP): pyproject.toml $(STAMP)
	$(PY) -m pip install --quiet --disable-pip-version-check -e '.[docs]'
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
