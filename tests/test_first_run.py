"""A new user's first run: the one-time compile of the numba kernels says so, in one line, once
(not once per worker), and later runs, which load the cached machine code, say nothing."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
LINE = "compiling the simulation kernels once"
RUN = """
import sys
from evolution.cli import evolve_main
sys.exit(evolve_main([sys.argv[1], "--out", sys.argv[2], "--workers", "2", "--no-progress",
                      "--generations", "1", "--population", "4", "--steps", "20"]))
"""


@pytest.mark.slow
def test_first_compile_says_so_once_and_later_runs_are_silent(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba-cache"), "PYTHONPATH": str(ROOT),
           "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    preset = str(ROOT / "configs" / "quick.toml")
    first = subprocess.run([sys.executable, "-c", RUN, preset, str(tmp_path / "a")], env=env,
                           capture_output=True, text=True, timeout=900)
    assert first.returncode == 0, first.stderr
    assert first.stderr.count(LINE) == 1, first.stderr  # two workers, one line
    again = subprocess.run([sys.executable, "-c", RUN, preset, str(tmp_path / "b")], env=env,
                           capture_output=True, text=True, timeout=900)
    assert again.returncode == 0, again.stderr
    assert LINE not in again.stderr
