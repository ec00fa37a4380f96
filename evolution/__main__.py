"""``python -m evolution`` = ``gathering-evolve``."""

from .cli import run_evolve

run_evolve()
