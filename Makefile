# make test   : create .venv if missing, install the project with its test extras, run the fast tests
# make demo   : set up and run the main job
# make bench  : print the environment and generation benchmarks
# make bench-learning : the learning benchmark (S1 and M1 at a mid budget, held-out comparison)
# make mutation: mutation testing (mutmut) of the study-critical modules; survivors -> mutation-survivors.txt
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: test test-slow demo bench bench-learning lint clean mutation

$(PY):
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[dev,video,ray,rl]"
	touch $(STAMP)

test: $(STAMP)
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(PY) -m pytest -q

test-slow: $(STAMP)
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(PY) -m pytest -q -m slow; rc=$$?; \
	  if [ $$rc -eq 5 ]; then echo "no slow tests"; exit 0; else exit $$rc; fi

# The main job on built-in defaults: a short HyperNEAT-M run (configs/quick.toml), its
# statistics plot, and a replay GIF of the champion team. out/quick is recreated each time.
demo: $(STAMP)
	rm -rf out/quick
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(VENV)/bin/gathering-evolve configs/quick.toml --out out/quick
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(VENV)/bin/gathering-replay out/quick/champion.json --out out/quick/team.gif
	@echo "plot: out/quick/stats.png   replay: out/quick/team.gif   champion: out/quick/champion.json"

bench: $(STAMP)
	$(PY) benchmarks/bench_env.py
	SDL_VIDEODRIVER=dummy $(PY) benchmarks/bench_generation.py

# Does evolution learn? S1 and M1 at a mid budget (about an hour on 2 idle cores), then the
# champions against scripted teams on held-out layouts (docs/evidence.md). Resumable:
# make bench-learning ARGS=--resume
bench-learning: $(STAMP)
	SDL_VIDEODRIVER=dummy $(PY) benchmarks/bench_learning.py --out runs/bench-learning $(ARGS)

# Mutation testing ([tool.mutmut] in pyproject.toml; docs/testing.md). CPU-heavy: restrict it with
# MUTANTS, mutmut's name globs, e.g. make mutation MUTANTS='evolution.reproduction.pareto*'.
MUTANTS ?=
mutation: $(STAMP)
	$(PY) -m pip install --quiet "mutmut>=3.8,<4"
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy nice -n 15 $(VENV)/bin/mutmut run --max-children 2 $(MUTANTS)
	$(VENV)/bin/mutmut results > mutation-survivors.txt
	@echo "survivors: $$(grep -c ': survived' mutation-survivors.txt) (mutation-survivors.txt; 'mutmut show NAME' for one)"

lint: $(STAMP)
	$(PY) -m ruff check .

clean:
	rm -rf $(VENV) out .pytest_cache mutants mutation-survivors.txt
