# make test   : create .venv if missing, install the project with its test extras, run the fast tests
# make demo   : set up and run the main job
# make bench  : print the environment and generation benchmarks
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: test test-slow demo bench lint clean

$(PY):
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[dev,video,ray,rl,marl]"
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

lint: $(STAMP)
	$(PY) -m ruff check .

clean:
	rm -rf $(VENV) out .pytest_cache
