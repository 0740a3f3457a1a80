# Everything a fresh machine needs: `make demo` renders the paper's scene,
# `make test` runs the whole suite on both supported Blenders.
PY313 ?= $(shell pyenv root 2>/dev/null)/versions/3.13.0/bin/python3.13
PY311 ?= python3.11
VENV := .venv
VENV311 := .venv311

.PHONY: all venv demo test test-engine bench clean package

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

# The paper's scene through Blender, with a Cycles render beside it, then
# the same scene through the engine's command line, all into out/.
demo: $(VENV)/.installed
	$(VENV)/bin/python tests/paper_scene.py --compare
	$(VENV)/bin/python -m caustic_addon render examples/paper.toml examples/round.obj -o out/paper_cli.png

test-engine: venv
	$(VENV)/bin/python -m pytest -c tests/pytest.ini tests/engine
	$(VENV311)/bin/python -m pytest -c tests/pytest.ini tests/engine

test: venv package
	$(VENV)/bin/python -m pytest -c tests/pytest.ini tests
	$(VENV311)/bin/python -m pytest -c tests/pytest.ini tests

# The extension: one zip per platform in dist/, each with the embreex wheels
# for Blender 4.2-5.0 (Python 3.11) and 5.1+ (Python 3.13).
EMBREEX := 4.4.0.post1
WHEEL_PLATFORMS := manylinux_2_28_x86_64 win_amd64 macosx_13_0_arm64
BLENDER_EXT = $(VENV)/bin/python $(firstword $(wildcard $(VENV)/lib/python3.13/site-packages/bpy/*/scripts/addons_core/bl_pkg/cli/blender_ext.py))

package: $(VENV)/.installed
	mkdir -p wheels dist
	for py in 3.11 3.13; do for platform in $(WHEEL_PLATFORMS); do \
	  cp=cp$$(echo $$py | tr -d .); \
	  ls wheels/embreex-$(EMBREEX)-$$cp-$$cp-*$$platform*.whl >/dev/null 2>&1 || \
	  $(VENV)/bin/python -m pip download -q embreex==$(EMBREEX) --no-deps --only-binary=:all: \
	    --python-version $$py --platform $$platform -d wheels || exit 1; \
	done; done
	$(BLENDER_EXT) build --split-platforms --source-dir . --output-dir dist
	for zip in dist/caustics-*.zip; do $(BLENDER_EXT) validate $$zip || exit 1; done

bench: $(VENV)/.installed
	$(VENV)/bin/python benchmarks/speed.py
	$(VENV)/bin/python benchmarks/accuracy.py
	$(VENV)/bin/python benchmarks/budget.py

clean:
	rm -rf $(VENV) $(VENV311) dist wheels out
