# Everything a fresh machine needs: `make demo` renders the paper's scene,
# `make test` runs the whole suite on every Blender of the test matrix.
#
# Each Blender is a venv with its own Python and the numpy that Blender
# bundles (requirements/blender-<version>.txt). The newest is the main one,
# .venv: the demo, the benchmarks and the packaging run there.
PY313 ?= $(shell pyenv root 2>/dev/null)/versions/3.13.0/bin/python3.13
PY311 ?= python3.11
NEWEST := 5.3
OLDER := 4.2 4.5
VENV := .venv

python_of = $(if $(filter $(NEWEST),$(1)),$(PY313),$(PY311))
venv_of = $(if $(filter $(NEWEST),$(1)),$(VENV),.venv-$(1))

.PHONY: all venv demo test test-engine bench bench-mitsuba bench-report clean package $(addprefix test-,$(NEWEST) $(OLDER)) \
	$(foreach part,addon engine-a engine-b engine-versions numpy,$(foreach v,$(NEWEST) $(OLDER),test-$(v)-$(part)))

all: test

# $(call make_venv,<Blender version>)
define make_venv
	test -x $(@D)/bin/python || $(call python_of,$(1)) -m venv $(@D)
	$(@D)/bin/python -m pip install -q --upgrade pip
	$(@D)/bin/python -m pip install -q -r $<
	touch $@
endef

$(VENV)/.installed: requirements/blender-$(NEWEST).txt
	$(call make_venv,$(NEWEST))

.venv-%/.installed: requirements/blender-%.txt
	$(call make_venv,$*)

venv: $(VENV)/.installed $(foreach v,$(OLDER),.venv-$(v)/.installed)

# The paper's scene three ways side by side (beams, the paper's splat map,
# Cycles), then through the engine's command line, all into out/.
demo: $(VENV)/.installed
	$(VENV)/bin/python examples/demo.py
	$(VENV)/bin/python -m caustic_addon render examples/paper.toml examples/round.obj -o out/paper_cli.png --exposure 2

test-engine: venv
	$(foreach v,$(NEWEST) $(OLDER),$(call venv_of,$(v))/bin/python -m pytest -c tests/pytest.ini tests/engine &&) true

# The engine's whole suite runs with the newest Python and numpy (5.3). The
# older Blenders share Python 3.11 and run the add-on's whole suite, which
# renders through the engine on their numpy; with the oldest numpy (4.2)
# the engine's tests of what differs between Pythons and numpy versions
# run too: its kernels' cache and compiled code, the numpy API it names,
# its command line, its messages, Embree's wheel and the heap. The suites
# run as parts of about five to ten minutes, two at a time, each part's
# output kept whole (a part keeps about 1.4 of the 2 cores busy): the first
# half of the newest's engine suite beside the packaging (its first test
# compiles every kernel, in one process), then the longest first, so that
# both cores stay busy to the end: each Blender's add-on suite, which needs
# the zips and their kernels, and the rest of the engine's. Those wait for
# the packaging too: make starts a part whose prerequisites are ready
# before an earlier one's, which left an add-on suite alone at the end.
PARTS := $(NEWEST)-engine-a $(NEWEST)-addon 4.2-addon 4.5-addon 4.2-engine-versions $(NEWEST)-engine-b 4.5-numpy
ENGINE_A := $(sort $(wildcard tests/engine/test_[a-k]*.py))
ENGINE_B := $(filter-out $(ENGINE_A),$(sort $(wildcard tests/engine/test_*.py)))
ENGINE_VERSIONS := $(addprefix tests/engine/,test_kernels.py test_shipped_numpy_api.py test_cli.py \
	test_scenes_and_errors.py test_embree.py test_heap.py)
test: venv package $(addprefix test-,$(PARTS))

ifeq ($(MAKECMDGOALS),test)
MAKEFLAGS += --jobs=2 --output-sync=target
endif

pytest_of = $(call venv_of,$(1))/bin/python -m pytest -c tests/pytest.ini
versions_of = $(foreach v,$(NEWEST) $(OLDER),test-$(v)-$(1))

test-$(NEWEST): test-%: test-%-addon test-%-engine-a test-%-engine-b
test-4.2: test-4.2-addon test-4.2-engine-versions
test-4.5: test-4.5-addon test-4.5-numpy

# The engine's tests and the add-on's have helper modules of the same
# names: each part is a pytest run of its own.
$(call versions_of,addon): test-%-addon: venv package
	@echo "== Blender $*: the add-on =="
	$(call pytest_of,$*) tests/addon

$(call versions_of,engine-a): test-%-engine-a: venv
	@echo "== Blender $*: the engine, $(notdir $(firstword $(ENGINE_A))) to $(notdir $(lastword $(ENGINE_A))) =="
	$(call pytest_of,$*) $(ENGINE_A)

$(call versions_of,engine-b): test-%-engine-b: venv package
	@echo "== Blender $*: the engine, $(notdir $(firstword $(ENGINE_B))) to $(notdir $(lastword $(ENGINE_B))) =="
	$(call pytest_of,$*) $(ENGINE_B)

$(call versions_of,engine-versions): test-%-engine-versions: venv package
	@echo "== Blender $*: the engine on what differs between Pythons and numpy versions =="
	$(call pytest_of,$*) $(ENGINE_VERSIONS)

$(call versions_of,numpy): test-%-numpy: venv package
	@echo "== Blender $*: the engine on the numpy it ships =="
	$(call pytest_of,$*) tests/engine/test_shipped_numpy_api.py

# The extension: one zip per platform in dist/, each with the embreex, numba
# and llvmlite wheels for Blender 4.2-5.0 (Python 3.11) and 5.1+ (Python 3.13).
# The wheels blender_manifest.toml lists, and only those; the zip of this
# machine's platform also carries kernels/, its compiled kernels for both
# Pythons (packaging/ship_kernels.py: numba compiles for the platform it
# runs on). The zips are made and stripped in a folder of their own, then
# moved into dist/ whole: the Blenders' suites run side by side and each
# makes the package again (tests/addon/test_install.py), so a suite must
# never read a zip another is still writing or stripping.
WHEELS := $(shell sed -n 's|^ *"\./\(wheels/[^"]*\.whl\)",*|\1|p' blender_manifest.toml)
BLENDER_EXT = $(VENV)/bin/python $(firstword $(wildcard $(VENV)/lib/python3.13/site-packages/bpy/*/scripts/addons_core/bl_pkg/cli/blender_ext.py))

package: venv
	mkdir -p wheels dist
	$(VENV)/bin/python packaging/ship_kernels.py compile kernels & newest=$$!; \
	  $(call venv_of,$(firstword $(OLDER)))/bin/python packaging/ship_kernels.py compile kernels && wait $$newest
	for wheel in $(WHEELS); do test -f $$wheel || { \
	  tags=$${wheel%.whl}; python=$$(echo $$tags | cut -d- -f3); platform=$${tags##*-}; \
	  $(VENV)/bin/python -m pip download -q $$(basename $$wheel | cut -d- -f1)==$$(basename $$wheel | cut -d- -f2) \
	    --no-deps --only-binary=:all: --python-version $${python#cp} --platform $${platform%%.*} -d wheels || exit 1; }; \
	done
	out=$$(mktemp -d dist/.build-XXXXXX) && trap 'rm -rf "$$out"' EXIT && \
	  $(BLENDER_EXT) build --split-platforms --source-dir . --output-dir $$out && \
	  $(VENV)/bin/python packaging/ship_kernels.py strip $$out/caustics-*.zip && \
	  for zip in $$out/caustics-*.zip; do $(BLENDER_EXT) validate $$zip || exit 1; done && \
	  mv $$out/caustics-*.zip dist/

# The benchmark suite: every kept measurement that does not need Mitsuba 3
# (Cycles' accuracy before the engine's, whose plot shows both), then
# benchmarks/README.md written from benchmarks/results/*.json (hours).
# first_render.py times the extension `make package` builds; allocator.py
# runs in the newest and the oldest Blender. `make bench-mitsuba` adds the
# comparison with Mitsuba's particle tracer, where its venv has Mitsuba;
# `make bench-report` only writes the README again.
BENCH := cycles_accuracy accuracy speed passes beams_at_scale memory animation live instances paper sized_lamps \
	glints glossy_floor emitters sky_caustics liquid_glass smooth_edges coated_floor rough_glass rough_beside_smooth \
	through_glass dispersion cycles_dispersion flicker gallery
MITSUBA_PYTHON ?= /tmp/mitsuba-venv/bin/python

bench: package
	$(foreach b,$(BENCH),$(VENV)/bin/python benchmarks/$(b).py &&) true
	$(VENV)/bin/python benchmarks/first_render.py
	$(foreach v,$(NEWEST) $(firstword $(OLDER)),$(call venv_of,$(v))/bin/python benchmarks/allocator.py &&) true
	$(MAKE) bench-report

bench-mitsuba: $(VENV)/.installed
	@if $(MITSUBA_PYTHON) -c "import mitsuba" 2>/dev/null; then \
	  $(VENV)/bin/python benchmarks/mitsuba_folds.py --mitsuba-python $(MITSUBA_PYTHON); \
	else echo "bench-mitsuba: no Mitsuba 3 at $(MITSUBA_PYTHON) (MITSUBA_PYTHON=...): skipped"; fi
	$(MAKE) bench-report

bench-report: $(VENV)/.installed
	$(VENV)/bin/python benchmarks/report.py --readme README.md

clean:
	rm -rf $(VENV) $(foreach v,$(OLDER),.venv-$(v)) dist wheels out kernels .blender-user
