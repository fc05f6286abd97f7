# cablesim: `make run` runs the main job on the shipped default case, `make test` runs the tests.
# Both create .venv and install the package (with its test extras) first if needed.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
CLI    := $(VENV)/bin/cablesim
STAMP  := $(VENV)/.installed

.PHONY: install run test test-all bench clean out-of-plane

$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	$(CLI) compile
	@touch $(STAMP)

install: $(STAMP)

run: $(STAMP)
	$(CLI) sweep configs/paper-example.yaml

# `make test` skips the checks marked slow; `make test-all` runs every test. Both spread the
# tests over every core (pytest-xdist, -n auto).
test: $(STAMP)
	$(PY) -m pytest -q -n auto -m 'not slow'

test-all: $(STAMP)
	$(PY) -m pytest -q -n auto

bench: $(STAMP)
	$(PY) benchmarks/bench_dynamics.py
	$(PY) benchmarks/bench_sweep.py
	$(PY) benchmarks/bench_continuation.py
	$(PY) benchmarks/bench_charts.py
	$(PY) benchmarks/bench_accelerate.py
	$(PY) benchmarks/bench_accelerate_heavy.py
	$(PY) benchmarks/bench_heavy.py
	$(PY) benchmarks/bench_approximate.py
	$(PY) benchmarks/bench_adaptive.py
	$(PY) benchmarks/bench_tolerances.py
	$(PY) benchmarks/bench_spatial.py
	$(PY) benchmarks/bench_spatial_continuation.py
	$(PY) benchmarks/bench_heavy_orbits.py
	$(if $(AGAINST),$(PY) benchmarks/bench_revisions.py --against $(AGAINST))

# The chapter "Out of the plane" of docs/paper-reproduction.md: its figure and numbers (about 2 min).
out-of-plane: $(STAMP)
	$(PY) benchmarks/out_of_plane.py -o docs/out-of-plane.png --json docs/out-of-plane.json

# numba's cache of the compiled kernels lives in cablesim/__pycache__/kernels-<hash of the compiled
# sources> (cablesim/jit.py): an edited kernel starts a fresh cache by itself; `make clean` only
# frees the space of the old ones.
clean:
	rm -rf runs/*/ .pytest_cache .hypothesis cablesim/__pycache__/kernels-*

# ---------------------------------------------------------------------------------------------
# Paper figures: `make fig3a`, ..., `make figures`. Each scene runs cablesim on its case file in
# configs/paper/ and writes runs/paper/<fig>.h5 and .png. make reruns a scene when its case file,
# cablesim's code (outside cablesim/plots/) or the scene's command-line settings change, and
# redraws a figure when the plotting code changes: each output folder holds stamp files whose
# content is a hash of the code (.code-sim, .code-plot) or the settings (.args-<scene>),
# rewritten only when it changes.
#
# FAST=1 runs the same scenes into runs/paper-fast/ on coarse grids that keep every frequency
# docs/paper-reproduction.md names (peaks, band points), with histories long enough for the
# jumps (`make -j2 figures FAST=1`: about 2 minutes on 2 cores once the kernels are compiled); each
# FAST figure is stamped as a preview (PREVIEW_STAMP= leaves the stamp off).
# ---------------------------------------------------------------------------------------------
FIGS := fig2 fig3a fig3b fig4 fig5a fig5b fig6 fig7a fig6-7a fig7b fig7c fig8a fig8b fig8c
# Frequency-response figures also get their continuation: every periodic response, stable and
# unstable, with its bifurcations, drawn over the brute-force points (runs/paper/<fig>-continuation.png).
CONTS := fig3a fig4 fig5a fig6 fig7a fig8a
# Scenes that only `make paper-numbers` needs: local refinements of the quoted peaks and the
# up/down sweep of Fig. 5(a) (case files configs/paper/<scene>.yaml; no FAST form).
REFINE := fig4-peak fig5a-updown
CFG  := configs/paper
# The cablesim command of each scene.
CMD_fig2 := free-vibration
CMD_fig3a := sweep
CMD_fig3b := history
CMD_fig4 := sweep
CMD_fig5a := sweep
CMD_fig5b := history
CMD_fig6 := sweep
CMD_fig7a := sweep
CMD_fig7-mode1 := history
CMD_fig7-mode2 := history
CMD_fig8a := sweep
CMD_fig8b := history
CMD_fig8c := history
CMD_fig4-peak := sweep
CMD_fig5a-updown := sweep

# `cablesim plot --stamp TEXT` draws TEXT on a figure.
PREVIEW_STAMP ?= 1
ifdef FAST
OUTD := runs/paper-fast
# The FAST grids: a coarse grid plus the frequencies the document quotes (the test
# tests/test_paper_reproduction.py checks that every quoted grid frequency is in them).
ARGS_fig2  := --set free_vibration.duration=4
ARGS_fig3a := --set 'sweep.omega=[0.5, 0.75, 1.0, 1.24, 1.26, 1.28, 1.5, 1.75, 2.0, 2.25, 2.44, 2.46, 2.48, 2.5, 2.52, 2.56, 2.6, 2.65, 2.75, 3.0, 3.5, 4.0, 4.5, 4.9, 5.0, 5.02, 5.04, 5.06, 5.08, 5.1, 5.2, 5.5, 6.0]'
ARGS_fig3b :=
ARGS_fig4  := --set 'sweep.omega=[1.0, 1.5, 2.0, 2.24, 2.4, 2.44, 2.48, 2.52, 2.56, 2.6, 2.8, 3.0, 3.5, 4.0, 4.5, 4.8, 4.96, 5.0, 5.04, 5.08, 5.12, 5.16, 5.5, 6.0]'
ARGS_fig5a := --set 'sweep.omega=[11.5, 11.7, 11.85, 11.9, 11.925, 11.95, 12.0, 12.1, 12.2, 12.3, 12.4, 12.475, 12.5, 12.525, 12.6, 12.7, 12.75, 12.775, 12.8, 12.825, 12.85, 12.9, 13.0, 13.2, 13.5]' --set sweep.duration=600
ARGS_fig5b :=
ARGS_fig6  := --set 'sweep.omega=[1.0, 1.4, 1.6, 1.7, 1.775, 1.8, 1.825, 1.85, 1.9, 2.0, 2.2, 2.3, 2.35, 2.4, 2.5, 2.7, 2.8, 2.85, 2.9, 3.0, 3.3, 3.6, 4.0]' --set sweep.duration=800
ARGS_fig7a := $(ARGS_fig6)
ARGS_fig7-mode1 :=
ARGS_fig7-mode2 :=
ARGS_fig8a := --set 'sweep.omega=[0.4, 0.42, 0.6, 0.7, 0.76, 0.8, 0.82, 0.84, 0.9, 1.0, 1.2, 1.4, 1.58, 1.6, 1.62, 1.64, 1.66, 1.7, 1.8, 2.0]' --set sweep.duration=3000
# The stiff case's continuation costs most: FAST follows it over the subharmonic band only.
ARGS_fig8a-continuation := --set 'continuation.omega={start: 1.3, stop: 2.0}'
ARGS_fig8b := --set history.duration=600
ARGS_fig8c := --set history.duration=1500
comma := ,
STAMP_OPT := $(if $(PREVIEW_STAMP),--stamp "preview: coarse grid$(comma) short runs")
else
OUTD := runs/paper
STAMP_OPT :=
endif
RUN := $(CLI)
# A history that stops early (exit 3: a segment went slack) has written its results up to then,
# and the figure shows them with the reason; a sweep with failed (slack) points has written them
# marked as failed. Keep both instead of failing the target.
KEEP_PARTIAL = || test $$? -eq 3

# Stamps: rewritten only when their content changes, so that make compares their times.
SIM_SRC  := $(filter-out cablesim/plots/%,$(shell find cablesim -name '*.py' | LC_ALL=C sort))
PLOT_SRC := $(shell find cablesim/plots -name '*.py' | LC_ALL=C sort)
hash = $(firstword $(shell cat $(1) | sha256sum))
update_stamp = @mkdir -p $(@D); printf '%s\n' $(1) | cmp -s - $@ || printf '%s\n' $(1) > $@
.PHONY: FORCE
FORCE:
# Keep every result and stamp that make builds on the way to a figure.
.PRECIOUS: $(OUTD)/%.h5 $(OUTD)/.args-%
$(OUTD)/.code-sim: FORCE
	$(call update_stamp,'$(call hash,$(SIM_SRC))')
$(OUTD)/.code-plot: FORCE
	$(call update_stamp,'$(call hash,$(PLOT_SRC)) $(STAMP_OPT)')
$(OUTD)/.args-%: FORCE
	$(call update_stamp,'$(subst ','"'"',$(ARGS_$*))')

.PHONY: figures refine paper-numbers $(FIGS) $(CONTS:%=%-continuation)
# The costly stiff scenes first, so that make -j2 runs them beside the rest.
figures: $(OUTD)/fig8a.h5 $(OUTD)/fig8b.h5 $(FIGS) $(CONTS:%=%-continuation)
refine: $(REFINE:%=$(OUTD)/%.h5)
$(FIGS): %: $(OUTD)/%.png
$(CONTS:%=%-continuation): %-continuation: $(OUTD)/%-continuation.h5

$(OUTD)/%-continuation.h5: $(CFG)/%.yaml $(OUTD)/%.h5 $(OUTD)/.code-sim $(OUTD)/.code-plot $(OUTD)/.args-%-continuation | $(STAMP)
	$(RUN) continue $< -o $@ --no-plot $(ARGS_$*-continuation) $(FORCE_$*-continuation)
	$(RUN) plot $@ $(OUTD)/$*.h5 -o $(@:.h5=.png) $(STAMP_OPT)

$(OUTD)/%.png: $(OUTD)/%.h5 $(OUTD)/.code-plot
	$(RUN) plot $< -o $@ $(STAMP_OPT)

# The stiff cable's full sweep (81 points of up to 6000 s) is above the default limit of 1e9 time
# steps by its upper bound (every point to its cap at the error-controlled scheme's largest step
# rate); its points stop once steady, far sooner: the scene runs it anyway.
FORCE_fig8a := --force
# Its continuation over the whole 0.4-2 rad/s is above the 1e8 Runge-Kutta steps of a first branch by
# the estimate (about 2000 orbits of 4e3 to 2e4 steps per forcing period): the scene runs it anyway.
FORCE_fig8a-continuation := --force
$(OUTD)/%.h5: $(CFG)/%.yaml $(OUTD)/.code-sim $(OUTD)/.args-% | $(STAMP)
	$(RUN) $(CMD_$*) $< -o $@ --no-plot $(ARGS_$*) $(FORCE_$*) $(KEEP_PARTIAL)

$(OUTD)/fig7b.png $(OUTD)/fig7c.png: $(OUTD)/fig%.png: $(OUTD)/fig7-mode1.h5 $(OUTD)/fig7-mode2.h5 $(CFG)/fig%.figure.yaml $(OUTD)/.code-plot
	$(RUN) plot $(OUTD)/fig7-mode1.h5 $(OUTD)/fig7-mode2.h5 --figure $(CFG)/fig$*.figure.yaml -o $@ $(STAMP_OPT)

# Figs. 6 and 7(a) on shared axes: the approximate and the exact analysis compared directly.
$(OUTD)/fig6-7a.png: $(OUTD)/fig6.h5 $(OUTD)/fig7a.h5 $(CFG)/fig6-7a.figure.yaml $(OUTD)/.code-plot
	$(RUN) plot $(OUTD)/fig6.h5 $(OUTD)/fig7a.h5 --figure $(CFG)/fig6-7a.figure.yaml -o $@ $(STAMP_OPT)

# Every number docs/paper-reproduction.md quotes, computed from the stored results (building
# those that are missing or out of date) and checked against docs/paper-numbers.json, which the
# tests compare with the document; WRITE=1 rewrites the file instead of checking it.
PAPER_H5 := $(filter-out fig6-7a fig7b fig7c,$(FIGS)) fig7-mode1 fig7-mode2 $(CONTS:%=%-continuation) $(REFINE)
ifdef FAST
paper-numbers:
	@echo "the document quotes the full results: run make paper-numbers without FAST" >&2; exit 2
else
paper-numbers: $(PAPER_H5:%=$(OUTD)/%.h5) | $(STAMP)
	$(PY) benchmarks/paper_numbers.py $(OUTD) $(if $(WRITE),--write,--check) docs/paper-numbers.json
endif
