# make demo           : create .venv if missing, install the core (no torch, no Ray), run the main job
# make test           : ... install everything the tests import (test extras + RL, MARL, Ray, video), run the fast tests
# make test-slow      : ... the same install, run the slow tests (CI runs make test, then make test-slow)
# (With only ".[dev]" installed the RL, Ray and MP4 tests skip; everything else runs.)
# make bench          : print the environment, controller and generation benchmarks
# make bench-learning : the learning benchmark (S1 and M1 at a mid budget, held-out comparison)
# make docs-images    : regenerate every figure of docs/ (examples/docs_images.py)
# make mutation       : mutation testing (mutmut) of the study-critical modules; survivors -> mutation-survivors.txt
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
# one stamp per install level; the full level includes the core
CORE   := $(VENV)/.installed-core
ALL    := $(VENV)/.installed-all
PIP    := $(PY) -m pip install --quiet --disable-pip-version-check

.PHONY: test test-slow demo bench bench-learning lint docs-images clean mutation

$(PY):
	$(PYTHON) -m venv $(VENV)

$(CORE): pyproject.toml | $(PY)
	$(PIP) -e .
	touch $(CORE)

$(ALL): pyproject.toml | $(PY)
	$(PIP) -e ".[dev,video,ray,rl,marl]"
	touch $(CORE) $(ALL)

test: $(ALL)
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(PY) -m pytest -q

test-slow: $(ALL)
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(PY) -m pytest -q -m slow; rc=$$?; \
	  if [ $$rc -eq 5 ]; then echo "no slow tests"; exit 0; else exit $$rc; fi

# The main job on built-in defaults: a short HyperNEAT-M run (configs/quick.toml), its
# statistics plot, and a replay GIF of the champion team. out/quick is recreated each time.
demo: $(CORE)
	rm -rf out/quick
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(VENV)/bin/gathering-evolve configs/quick.toml --out out/quick
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(VENV)/bin/gathering-replay out/quick/champion.json --out out/quick/team.gif
	@echo "plot: out/quick/stats.png   replay: out/quick/team.gif   champion: out/quick/champion.json"

bench: $(CORE)
	$(PY) benchmarks/bench_env.py
	$(PY) benchmarks/bench_controller.py
	SDL_VIDEODRIVER=dummy $(PY) benchmarks/bench_generation.py

# Does evolution learn? S1 and M1 at a mid budget (about an hour on 2 idle cores), then the
# champions against scripted teams on held-out layouts (docs/evidence.md). Resumable:
# make bench-learning ARGS=--resume
bench-learning: $(CORE)
	SDL_VIDEODRIVER=dummy $(PY) benchmarks/bench_learning.py --out runs/bench-learning $(ARGS)

# Mutation testing ([tool.mutmut] in pyproject.toml; docs/testing.md). CPU-heavy: restrict it with
# MUTANTS, mutmut's name globs, e.g. make mutation MUTANTS='evolution.reproduction.pareto*'.
MUTANTS ?=
mutation: $(ALL)
	$(PY) -m pip install --quiet "mutmut>=3.8,<4"
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy nice -n 15 $(VENV)/bin/mutmut run --max-children 2 $(MUTANTS)
	$(VENV)/bin/mutmut results > mutation-survivors.txt
	@echo "survivors: $$(grep -c ': survived' mutation-survivors.txt) (mutation-survivors.txt; 'mutmut show NAME' for one)"

lint: $(ALL)
	$(PY) -m ruff check .

docs-images: $(CORE)
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(PY) examples/docs_images.py

clean:
	rm -rf $(VENV) out .pytest_cache mutants mutation-survivors.txt
