# The two commands a newcomer needs: `make demo` and `make test`. Each builds .venv itself.
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test bench studies clean

$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/magdesign solve --timing

test: $(STAMP)
	$(PY) -m pytest -q -n 2

bench: $(STAMP)
	for f in benchmarks/*.py; do $(PY) $$f || exit 1; done

studies: $(STAMP)
	for f in studies/seed*.py; do $(PY) $$f || exit 1; done

clean:
	rm -rf $(VENV) studies/out
