"""``python -m evolution`` = ``gathering-evolve``."""

from evolution.cli import run_evolve

run_evolve()
