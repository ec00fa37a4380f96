# make test   : create .venv if missing, install the project with its test extras, run the fast tests
# make demo   : set up and run the main job
# make bench  : print the environment benchmark
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: test test-slow demo bench lint clean

$(PY):
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[dev,video]"
	touch $(STAMP)

test: $(STAMP)
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(PY) -m pytest -q

test-slow: $(STAMP)
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(PY) -m pytest -q -m slow; rc=$$?; \
	  if [ $$rc -eq 5 ]; then echo "no slow tests"; exit 0; else exit $$rc; fi

demo: $(STAMP)
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(PY) examples/random_episode.py --out out/random_episode.gif

bench: $(STAMP)
	$(PY) benchmarks/bench_env.py

lint: $(STAMP)
	$(PY) -m ruff check .

clean:
	rm -rf $(VENV) out .pytest_cache
