# cablesim: `make run` runs the main job on the shipped default case, `make test` runs the tests.
# Both create .venv and install the package (with its test extras) first if needed.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
CLI    := $(VENV)/bin/cablesim
STAMP  := $(VENV)/.installed

.PHONY: install run test bench clean paper-numbers

$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

install: $(STAMP)

run: $(STAMP)
	$(CLI) sweep configs/paper-example.yaml

test: $(STAMP)
	$(PY) -m pytest -q

bench: $(STAMP)
	$(PY) benchmarks/bench_dynamics.py
	$(PY) benchmarks/bench_sweep.py
	$(PY) benchmarks/bench_continuation.py
	$(PY) benchmarks/bench_accelerate.py
	$(PY) benchmarks/bench_heavy.py

paper-numbers: $(STAMP)
	$(PY) benchmarks/paper_numbers.py $(OUTD)

# numba caches compiled kernels beside the sources but does not notice when a kernel called
# from another module changes: after editing cablesim/dynamics/, clear the cache.
clean:
	rm -rf runs/*/ .pytest_cache .hypothesis
	find cablesim -name '*.nbi' -delete -o -name '*.nbc' -delete

# ---------------------------------------------------------------------------------------------
# Paper figures: `make fig3a`, ..., `make figures`. Each scene runs cablesim on its case file in
# configs/paper/ and writes runs/paper/<fig>.h5 and .png; make reruns a scene only when its case
# file changed. FAST=1 runs the same targets on coarser grids with shorter caps, into
# runs/paper-fast/.
# ---------------------------------------------------------------------------------------------
FIGS := fig2 fig3a fig3b fig4 fig5a fig5b fig6 fig7a fig7b fig7c fig8a fig8b fig8c
# Frequency-response figures also get their continuation: every periodic response, stable and
# unstable, with its bifurcations, drawn over the brute-force points (runs/paper/<fig>-continuation.png).
CONTS := fig3a fig4 fig5a fig6 fig7a fig8a
CFG  := configs/paper
ifdef FAST
OUTD := runs/paper-fast
SWEEP_FAST = --set sweep.omega.num=$(1) --set sweep.duration=$(2) --set sweep.window=$(3)
HIST_FAST  = --set history.duration=$(1)
FV_FAST    = --set free_vibration.duration=$(1)
else
OUTD := runs/paper
SWEEP_FAST =
HIST_FAST  =
FV_FAST    =
endif
RUN := $(CLI)
# A history that stops early (exit 3: a segment went slack) has written its results up to then,
# and the figure shows them with the reason; keep it instead of failing the target.
KEEP_PARTIAL = || test $$? -eq 3

.PHONY: figures $(FIGS) $(CONTS:%=%-continuation)
figures: $(FIGS) $(CONTS:%=%-continuation)
$(FIGS): %: $(OUTD)/%.png
$(CONTS:%=%-continuation): %-continuation: $(OUTD)/%-continuation.h5

$(OUTD)/%-continuation.h5: $(CFG)/%.yaml $(OUTD)/%.h5 | $(STAMP)
	$(RUN) continue $< -o $@ --overlay $(OUTD)/$*.h5

$(OUTD)/%.png: $(OUTD)/%.h5
	$(RUN) plot $< -o $@

$(OUTD)/fig2.h5: $(CFG)/fig2.yaml | $(STAMP)
	$(RUN) free-vibration $< -o $@ --no-plot $(call FV_FAST,4) $(KEEP_PARTIAL)
$(OUTD)/fig3a.h5: $(CFG)/fig3a.yaml | $(STAMP)
	$(RUN) sweep $< -o $@ --no-plot $(call SWEEP_FAST,23,1000,100)
$(OUTD)/fig3b.h5: $(CFG)/fig3b.yaml | $(STAMP)
	$(RUN) history $< -o $@ --no-plot $(call HIST_FAST,600) $(KEEP_PARTIAL)
$(OUTD)/fig4.h5: $(CFG)/fig4.yaml | $(STAMP)
	$(RUN) sweep $< -o $@ --no-plot $(call SWEEP_FAST,11,800,100)
$(OUTD)/fig5a.h5: $(CFG)/fig5a.yaml | $(STAMP)
	$(RUN) sweep $< -o $@ --no-plot $(call SWEEP_FAST,11,400,50)
$(OUTD)/fig5b.h5: $(CFG)/fig5b.yaml | $(STAMP)
	$(RUN) history $< -o $@ --no-plot $(call HIST_FAST,150) $(KEEP_PARTIAL)
$(OUTD)/fig6.h5: $(CFG)/fig6.yaml | $(STAMP)
	$(RUN) sweep $< -o $@ --no-plot $(call SWEEP_FAST,16,800,100)
$(OUTD)/fig7a.h5: $(CFG)/fig7a.yaml | $(STAMP)
	$(RUN) sweep $< -o $@ --no-plot $(call SWEEP_FAST,16,800,100)
$(OUTD)/fig7-mode%.h5: $(CFG)/fig7-mode%.yaml | $(STAMP)
	$(RUN) history $< -o $@ --no-plot $(call HIST_FAST,200) $(KEEP_PARTIAL)
$(OUTD)/fig7b.png: $(OUTD)/fig7-mode1.h5 $(OUTD)/fig7-mode2.h5 $(CFG)/fig7b.figure.yaml
	$(RUN) plot $(OUTD)/fig7-mode1.h5 $(OUTD)/fig7-mode2.h5 --figure $(CFG)/fig7b.figure.yaml -o $@
$(OUTD)/fig7c.png: $(OUTD)/fig7-mode1.h5 $(OUTD)/fig7-mode2.h5 $(CFG)/fig7c.figure.yaml
	$(RUN) plot $(OUTD)/fig7-mode1.h5 $(OUTD)/fig7-mode2.h5 --figure $(CFG)/fig7c.figure.yaml -o $@
$(OUTD)/fig8a.h5: $(CFG)/fig8a.yaml | $(STAMP)
	$(RUN) sweep $< -o $@ --no-plot $(call SWEEP_FAST,13,1000,100)
$(OUTD)/fig8b.h5: $(CFG)/fig8b.yaml | $(STAMP)
	$(RUN) history $< -o $@ --no-plot $(call HIST_FAST,300) $(KEEP_PARTIAL)
$(OUTD)/fig8c.h5: $(CFG)/fig8c.yaml | $(STAMP)
	$(RUN) history $< -o $@ --no-plot $(call HIST_FAST,600) $(KEEP_PARTIAL)
