"""Two tiny evolution runs in a small world, built once per test session and shared by the
test modules that need real run directories (re-evaluation, fitness, fronts, resume)."""

from __future__ import annotations

from pathlib import Path

from evolution.cli import evolve_main
from evolution.run.stats import read_stats, without_timing

SMALL_WORLD = """
[environment]          # a small world where a few blocks get gathered, so ft varies
environment = 1
arena_width = 6.0
arena_height = 6.0
zone_width = 6.0
zone_depth = 2.0
block_counts = [8, 0, 0]
max_cycles = 80
num_robots = 10
"""

def comparable_stats(run: Path) -> list[dict]:
    """A run's statistics without what legitimately differs between equal runs (timings, the
    count of retried evaluations), for comparing a resumed or healed run with an unbroken one."""
    return without_timing([{k: v for k, v in r.items() if k != "failures"} for r in read_stats(run / "stats.jsonl")])


_BUILT: dict[str, tuple[Path, Path, Path, Path]] = {}


def experiment_file(root: Path, name: str, method: str, objectives: str, generations: int = 3,
                    extra: str = "") -> Path:
    path = root / f"{name}.toml"
    path.write_text(f"""
[experiment]
name = "{name}"
method = "{method}"
objectives = {objectives}
generations = {generations}
population = 6
trials = 2
seed = 3
{extra}
""" + SMALL_WORLD)
    return path


def evolve(exp: Path, out: Path, *more: str) -> None:
    assert evolve_main([str(exp), "--out", str(out), "--workers", "1", "--no-progress", *more]) == 0


def build(tmp_path_factory) -> tuple[Path, Path, Path, Path]:
    """(SO experiment, SO run, MO experiment, MO run): HyperNEAT-M SO and NEAT-M MO, 2 generations.

    Tests must not change these directories (copy them first)."""
    if "runs" not in _BUILT:
        root = tmp_path_factory.mktemp("small-runs")
        so = experiment_file(root, "so", "hyperneat-m", '["task"]', generations=2)
        mo = experiment_file(root, "mo", "neat-m", '["task", "morphology"]', generations=2)
        evolve(so, root / "so")
        evolve(mo, root / "mo")
        _BUILT["runs"] = (so, root / "so", mo, root / "mo")
    return _BUILT["runs"]
