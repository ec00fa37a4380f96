# make demo           : create .venv if missing, install the core (no torch, no Ray), run the main job
# make test           : ... install everything the tests import (test extras + RL, Ray, video), run the fast tests
# make test-slow      : ... the same install, run the slow tests (CI runs make test, then make test-slow)
# (With only ".[dev]" installed the RL, Ray and MP4 tests skip; everything else runs.)
# make bench          : print the environment and generation benchmarks
# make bench-learning : the learning benchmark (S1 and M1 at a mid budget, held-out comparison)
# make docs-images    : regenerate every figure of docs/ (examples/docs_images.py)
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
# one stamp per install level; the full level includes the core
CORE   := $(VENV)/.installed-core
ALL    := $(VENV)/.installed-all
PIP    := $(PY) -m pip install --quiet --disable-pip-version-check

.PHONY: test test-slow demo bench bench-learning lint docs-images clean

$(PY):
	$(PYTHON) -m venv $(VENV)

$(CORE): pyproject.toml | $(PY)
	$(PIP) -e .
	touch $(CORE)

$(ALL): pyproject.toml | $(PY)
	$(PIP) -e ".[dev,video,ray,rl]"
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
	SDL_VIDEODRIVER=dummy $(PY) benchmarks/bench_generation.py

# Does evolution learn? S1 and M1 at a mid budget (about an hour on 2 idle cores), then the
# champions against scripted teams on held-out layouts (docs/evidence.md). Resumable:
# make bench-learning ARGS=--resume
bench-learning: $(CORE)
	SDL_VIDEODRIVER=dummy $(PY) benchmarks/bench_learning.py --out runs/bench-learning $(ARGS)

lint: $(ALL)
	$(PY) -m ruff check .

docs-images: $(CORE)
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(PY) examples/docs_images.py

clean:
	rm -rf $(VENV) out .pytest_cache
