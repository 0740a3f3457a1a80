# Everything a fresh machine needs: `make demo` renders the paper's scene,
# `make test` runs the whole suite on both supported Blenders.
PY313 ?= $(shell pyenv root 2>/dev/null)/versions/3.13.0/bin/python3.13
PY311 ?= python3.11
VENV := .venv
VENV311 := .venv311

.PHONY: all venv demo test test-engine bench clean

all: test

$(VENV)/.installed: requirements/py313.txt
	test -x $(VENV)/bin/python || $(PY313) -m venv $(VENV)
	$(VENV)/bin/python -m pip install -q --upgrade pip
	$(VENV)/bin/python -m pip install -q -r requirements/py313.txt
	touch $@

$(VENV311)/.installed: requirements/py311.txt
	test -x $(VENV311)/bin/python || $(PY311) -m venv $(VENV311)
	$(VENV311)/bin/python -m pip install -q --upgrade pip
	$(VENV311)/bin/python -m pip install -q -r requirements/py311.txt
	touch $@

venv: $(VENV)/.installed $(VENV311)/.installed

demo: $(VENV)/.installed
	$(VENV)/bin/python -m caustic_addon render examples/paper.toml examples/round.obj -o out/paper.png

test-engine: venv
	$(VENV)/bin/python -m pytest -c tests/pytest.ini tests/engine
	$(VENV311)/bin/python -m pytest -c tests/pytest.ini tests/engine

test: venv
	$(VENV)/bin/python -m pytest -c tests/pytest.ini tests
	$(VENV311)/bin/python -m pytest -c tests/pytest.ini tests

bench: $(VENV)/.installed
	$(VENV)/bin/python benchmarks/speed.py

clean:
	rm -rf $(VENV) $(VENV311) dist wheels out
