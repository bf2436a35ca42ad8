# vibrogear: every target does its own set-up (apt stack, venv, editable install).
VENV   := .venv
PY     := $(VENV)/bin/python
VG     := $(VENV)/bin/vibrogear
STAMP  := $(VENV)/.installed
OUT    ?= out
export OPENBLAS_NUM_THREADS ?= 1
export XDG_CACHE_HOME ?= $(HOME)/.cache

# gearbox scenes and their studies
.PHONY: two-stage two-stage-helical two-stage-iso6336 single-stage gear-pair fva three-stage gearboxes housing-dynamics housing-step bench-gearbox bench-rhs nvh map map-gear-pair runup runup-gear-pair bench-runup
.PHONY: nnm nnm-impact-pair
.PHONY: states states-impact-pair bench-states bench-parallel
.PHONY: rotor setup demo test test-slow test-system test-mpi golden bench figures fig2 fig4 fig5 fig7 critical-zeta report clean housing housing-sweep housing-convergence housing-bench
.PHONY: optimize-damping optimize-two-stage reduction-accuracy

setup: $(STAMP)

$(STAMP): pyproject.toml constraints.txt scripts/setup.sh
	./scripts/setup.sh

## main job on the default scene: the two-stage gearbox (paper Figs 1-2; docs/gearbox.md)
demo: two-stage

## the CI test suite (fast; slow cases: make test-slow; whole runs across processes beyond one
## of each kind: make test-system), one worker process per core
## (pytest-xdist; a test file stays on one worker, so its module fixtures are built once)
test: $(STAMP) $(VENV)/.browser
	$(PY) -m pytest -n auto --dist loadfile

# the test tier's browser test renders report.html in Debian's chromium
$(VENV)/.browser: $(STAMP)
	./scripts/setup.sh --browser
	touch $@

test-slow: $(STAMP)
	$(PY) -m pytest -m slow -n auto --dist loadfile

## whole runs across processes (mpirun ranks, signals, kills, locks, resumes) that the CI tier
## keeps one of each kind of
test-system: $(STAMP)
	$(PY) -m pytest -m "system and not slow" -n auto --dist loadfile

## every test that starts mpirun itself (2 ranks; `make test` keeps one of each kind)
test-mpi: $(STAMP)
	$(PY) -m pytest -m mpi

## regression tier: rewrite tests/regression/golden/*.json from fresh runs; review the diff
golden: $(STAMP)
	$(PY) tests/regression/regenerate.py

bench: $(STAMP)
	$(PY) benchmarks/run_all.py

## gearbox scenes: modes, time response, sweep (Fig. 2), continuation, nvh, run-up
two-stage: $(STAMP)
	$(VG) run configs/two_stage.toml --out $(OUT)/two_stage

## the demo gearbox's reduced model against its full model (every housing DOF): frequency
## error, MAC and response error per reduction level (not in the demo: ~90 s on a fresh machine)
reduction-accuracy: $(STAMP)
	$(VG) run configs/two_stage.toml --set 'scene.analyses=["reduction_accuracy"]' --out $(OUT)/two_stage_reduction

two-stage-helical: $(STAMP)
	$(VG) run configs/two_stage_helical.toml --out $(OUT)/two_stage_helical

two-stage-iso6336: $(STAMP)
	$(VG) run configs/two_stage_iso6336.toml --out $(OUT)/two_stage_iso6336

## housing from a shipped millimetre STEP file: modes at the bores
housing-step: $(STAMP)
	$(VG) run configs/housing_step.toml --out $(OUT)/housing_step

single-stage: $(STAMP)
	$(VG) run configs/single_stage.toml --out $(OUT)/single_stage

gear-pair: $(STAMP)
	$(VG) run configs/gear_pair.toml --out $(OUT)/gear_pair

## real gearboxes nobody tuned for: the FVA two-stage industrial gearbox (imported from REXS)
## and a three-stage reducer built by hand
fva: $(STAMP)
	$(VG) run configs/fva_two_stage.toml --out $(OUT)/fva_two_stage

three-stage: $(STAMP)
	$(VG) run configs/three_stage.toml --out $(OUT)/three_stage

gearboxes: two-stage two-stage-helical single-stage gear-pair

## speed x load operating maps ([map]): two_stage 40 x 20; gear_pair 40 x 6 with LP/PD curves
map: $(STAMP)
	$(VG) map configs/two_stage.toml --out $(OUT)/two_stage_map

map-gear-pair: $(STAMP)
	$(VG) map configs/gear_pair.toml --out $(OUT)/gear_pair_map

## nonlinear normal modes ([nnm], docs/nnm.md): gear_pair's G1 mesh-mode backbone over its forced
## branch (out/gear_pair_nnm/nnm_backbone.png); the impact pair's over its primary resonance
nnm: $(STAMP)
	$(VG) run configs/gear_pair_nnm.toml --out $(OUT)/gear_pair_nnm

nnm-impact-pair: $(STAMP)
	$(VG) run configs/impact_pair_nnm.toml --out $(OUT)/impact_pair_nnm

## every operating state at every speed ([states], docs/states.md): attractors from random
## starts with their basins, branches from each, the danger map states.png
states: $(STAMP)
	$(VG) run configs/gear_pair.toml --set 'scene.analyses=["sweep", "states"]' --out $(OUT)/gear_pair_states

states-impact-pair: $(STAMP)
	$(VG) states configs/impact_pair.toml --out $(OUT)/impact_pair_states

## two_stage census: transient / record / clustering split, projection to 64 MPI ranks
bench-states: $(STAMP)
	$(PY) benchmarks/bench_states.py

## the parallel / serial wall split of states, sweep and map and the speed-up it allows on
## 16 and 64 workers (docs/performance.md, "Parallel runs"); small runs, a few minutes
bench-parallel: $(STAMP)
	$(PY) benchmarks/bench_parallel.py

## run-up / run-down transients ([runup]) in the scene's own output folder, so that the
## envelope figure overlays the sweep and branches of `make two-stage` / `make gear-pair`
runup: $(STAMP)
	$(VG) runup configs/two_stage.toml --out $(OUT)/two_stage

runup-gear-pair: $(STAMP)
	$(VG) runup configs/gear_pair.toml --out $(OUT)/gear_pair

## two_stage 10 s run-up: wall time (target <= 30 s), steps per mesh period
bench-runup: $(STAMP)
	$(PY) benchmarks/bench_runup.py

## two_stage spectra over speed (waterfalls with order lines) and the housing's ERP ([nvh])
nvh: $(STAMP)
	$(VG) nvh configs/two_stage.toml --out $(OUT)/two_stage_nvh

## housing wall thickness -> resonance speeds and bifurcation diagram of the two-stage gearbox
housing-dynamics: $(STAMP)
	$(PY) scripts/housing_dynamics.py --out $(OUT)/housing_dynamics

## two_stage: sweep speed vs scipy RK45 + dense numpy RHS; orbit + monodromy time
bench-gearbox: $(STAMP)
	$(PY) benchmarks/bench_gearbox.py

## two_stage right-hand side against its multiply-add floor; scipy at equal accuracy (1 period)
bench-rhs: $(STAMP)
	$(PY) benchmarks/bench_rhs_floor.py
	$(PY) benchmarks/bench_gearbox_integrator.py --model bench_gearbox:two_stage_short_case \
	  --periods 1 --record-periods 1 --out benchmarks/results/bench_gearbox_equal_accuracy_two_stage.json

## the seed's Fig. 2 on its gearbox (configs/two_stage_seed.toml): sweep min/max, zero line,
## continuation branches, motion classes -> $(OUT)/two_stage_seed/fig2.png (docs/gearbox.md)
fig2: $(STAMP)
	$(VG) run configs/two_stage_seed.toml --out $(OUT)/two_stage_seed

## impact-pair figures (paper Figs 4-8)
figures: fig4 fig5 fig7

fig4: $(STAMP)
	$(VG) run configs/impact_pair.toml --out $(OUT)/fig4_zeta0.015

fig5: $(STAMP)
	$(VG) run configs/impact_pair.toml --set impact_pair.zeta=0.03 --out $(OUT)/fig5_zeta0.03

fig7: $(STAMP)
	$(VG) run configs/impact_pair.toml --set impact_pair.zeta=0.05 --out $(OUT)/fig7_zeta0.05

## work-precision of the integrator and of shooting against the exact impact-pair solution
report: $(STAMP)
	$(VG) run configs/impact_pair.toml --set 'scene.analyses=["report"]' --out $(OUT)/report

## damping at which the two folds of the primary resonance meet (bisection of continuations)
critical-zeta: $(STAMP)
	$(VG) run configs/impact_pair.toml --set 'scene.analyses=["critical_damping"]' --out $(OUT)/critical_zeta

## [optimize]: the least damping without a fold of the impact pair's primary resonance
## (the cusp, zeta_c = 0.03375 of critical-zeta; docs/optimize.md)
optimize-damping: $(STAMP)
	$(VG) optimize configs/optimize_impact_damping.toml --out $(OUT)/optimize_impact_damping

## [optimize]: two-stage housing wall and free-gear drag against the peak radiated power (2 workers)
optimize-two-stage: $(STAMP)
	$(VG) optimize configs/optimize_two_stage.toml --out $(OUT)/optimize_two_stage

## rotor scenes: Friswell Example 5.9.1 and a stepped hollow shaft with a free gear
rotor: $(STAMP)
	$(VG) run configs/rotor_friswell_5_9_1.toml --out $(OUT)/rotor_friswell_5_9_1
	$(VG) run configs/rotor_stepped_free_gear.toml --out $(OUT)/rotor_stepped_free_gear

## housing master modes + bore coupling values (docs/housing.md)
housing: $(STAMP)
	$(VG) run configs/housing.toml --out $(OUT)/housing

## first frequencies against the wall thickness, points in parallel processes (resumable)
housing-sweep: $(STAMP)
	$(VG) run configs/housing_sweep.toml --out $(OUT)/housing_sweep

## frequency error vs DOF vs wall time, P1 and P2 (heavy: tens of minutes)
housing-convergence: $(STAMP)
	$(VG) run configs/housing_convergence.toml --out $(OUT)/housing_convergence

## 100 modes of a >= 150k-DOF P2 housing, serial and mpirun -n 2; cached rerun
housing-bench: $(STAMP)
	$(PY) benchmarks/bench_housing.py

clean:
	rm -rf $(OUT)
