"""Fault tolerance: retried evaluations, dying workers, killed and interrupted runs, backends."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from small_runs import comparable_stats

from evolution.cli import evolve_main
from evolution.run import backends
from evolution.run.stats import read_stats

ROOT = Path(__file__).resolve().parent.parent
TINY = """
[experiment]
name = "tiny"
generations = {generations}
population = 8
trials = 1
seed = 5
[environment]
environment = 1
max_cycles = 100
num_robots = 5
"""


def experiment(tmp_path: Path, generations: int = 2) -> Path:
    path = tmp_path / f"tiny{generations}.toml"
    path.write_text(TINY.format(generations=generations))
    return path


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("ref")
    exp = experiment(tmp)
    assert evolve_main([str(exp), "--out", str(tmp / "run"), "--backend", "serial", "--no-progress"]) == 0
    return exp, comparable_stats(tmp / "run")


def crash_once(marker: Path, how: str):
    """An EvalContext.evaluate that fails on the first call for a genome (per marker file)."""
    original = backends.EvalContext.evaluate

    def evaluate(self, genome, generation):
        flag = marker / f"{generation}-{genome.key}"
        if genome.key % 3 == 0 and not flag.exists():
            flag.touch()
            if how == "exit":
                os._exit(3)                        # the worker process dies
            raise RuntimeError(f"injected failure for genome {genome.key}")
        return original(self, genome, generation)

    return evaluate


@pytest.mark.parametrize("backend,how", [("serial", "raise"), ("process", "raise"), ("process", "exit")])
def test_failed_evaluations_are_retried(tmp_path, monkeypatch, reference, backend, how):
    exp, expected = reference
    (tmp_path / "marks").mkdir()
    monkeypatch.setattr(backends.EvalContext, "evaluate", crash_once(tmp_path / "marks", how))
    assert evolve_main([str(exp), "--out", str(tmp_path / "run"), "--backend", backend, "--workers", "2",
                        "--no-progress"]) == 0
    assert any((tmp_path / "marks").iterdir())      # faults really happened
    assert comparable_stats(tmp_path / "run") == expected      # and were healed by retries
    assert all(r["failures"] == 0 for r in read_stats(tmp_path / "run" / "stats.jsonl"))


def test_persistent_failure_gives_worst_fitness_and_is_logged(tmp_path, monkeypatch, reference):
    exp, _ = reference
    original = backends.EvalContext.evaluate

    def evaluate(self, genome, generation):
        if genome.key == 3:
            raise RuntimeError("this genome always breaks")
        return original(self, genome, generation)

    monkeypatch.setattr(backends.EvalContext, "evaluate", evaluate)
    assert evolve_main([str(exp), "--out", str(tmp_path / "run"), "--backend", "serial", "--max-retries", "1",
                        "--no-progress"]) == 0
    records = read_stats(tmp_path / "run" / "stats.jsonl")
    assert records[0]["failures"] == 1
    log = (tmp_path / "run" / "errors.log").read_text()
    assert "generation 0 genome 3: RuntimeError: this genome always breaks" in log


def test_a_genome_that_kills_its_worker_is_the_only_one_charged(tmp_path, monkeypatch, reference):
    """Worker deaths are charged to the genome that causes them, not to the others in the pool."""
    exp, _ = reference
    original = backends.EvalContext.evaluate

    def evaluate(self, genome, generation):
        if genome.key in (3, 4, 5):
            os._exit(3)                                # these genomes always kill their worker
        return original(self, genome, generation)

    monkeypatch.setattr(backends.EvalContext, "evaluate", evaluate)
    assert evolve_main([str(exp), "--out", str(tmp_path / "run"), "--backend", "process", "--workers", "2",
                        "--max-retries", "1", "--generations", "1", "--no-progress"]) == 0
    records = read_stats(tmp_path / "run" / "stats.jsonl")
    assert records[0]["failures"] == 3                 # exactly the three killers, each after 2 attempts
    log = (tmp_path / "run" / "errors.log").read_text()
    assert sorted(int(line.split("genome ")[1].split(":")[0]) for line in log.splitlines()
                  if line.startswith("generation 0 genome")) == [3, 4, 5]


def run_cli(args: list[str]) -> subprocess.Popen:
    env = dict(os.environ, SDL_VIDEODRIVER="dummy", PYTHONPATH=str(ROOT))
    return subprocess.Popen([sys.executable, "-m", "evolution", *args], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def wait_for(path: Path, timeout: float = 60.0) -> None:
    end = time.time() + timeout
    while not path.exists():
        if time.time() > end:
            raise TimeoutError(path)
        time.sleep(0.05)


def test_sigkill_mid_run_resumes_to_the_same_result(tmp_path):
    exp = experiment(tmp_path, generations=6)
    assert evolve_main([str(exp), "--out", str(tmp_path / "full"), "--backend", "serial", "--no-progress"]) == 0
    proc = run_cli([str(exp), "--out", str(tmp_path / "killed"), "--backend", "serial", "--no-progress"])
    wait_for(tmp_path / "killed" / "checkpoints" / "gen-0003.ckpt")
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    assert len(read_stats(tmp_path / "killed" / "stats.jsonl")) < 6
    assert evolve_main([str(exp), "--out", str(tmp_path / "killed"), "--resume", "--backend", "serial",
                        "--no-progress"]) == 0
    assert comparable_stats(tmp_path / "killed") == comparable_stats(tmp_path / "full")


def test_sigint_finishes_the_generation_and_leaves_a_resumable_run(tmp_path):
    exp = experiment(tmp_path, generations=6)
    assert evolve_main([str(exp), "--out", str(tmp_path / "full"), "--backend", "serial", "--no-progress"]) == 0
    proc = run_cli([str(exp), "--out", str(tmp_path / "stopped"), "--workers", "2", "--no-progress"])
    wait_for(tmp_path / "stopped" / "checkpoints" / "gen-0002.ckpt")
    proc.send_signal(signal.SIGINT)
    out, _ = proc.communicate(timeout=60)
    assert proc.returncode == 130, out
    assert "resume" in out
    done = read_stats(tmp_path / "stopped" / "stats.jsonl")
    assert 2 <= len(done) < 6
    newest = sorted((tmp_path / "stopped" / "checkpoints").glob("gen-*.ckpt"))[-1]
    assert newest.name == f"gen-{len(done):04d}.ckpt"          # statistics and checkpoint agree
    assert evolve_main([str(exp), "--out", str(tmp_path / "stopped"), "--resume", "--no-progress"]) == 0
    assert comparable_stats(tmp_path / "stopped") == comparable_stats(tmp_path / "full")


@pytest.mark.slow  # starting a local Ray takes ~15 s
def test_all_backends_agree(tmp_path, reference):
    pytest.importorskip("ray")
    exp, expected = reference
    assert evolve_main([str(exp), "--out", str(tmp_path / "process"), "--backend", "process", "--workers", "2",
                        "--no-progress"]) == 0
    assert comparable_stats(tmp_path / "process") == expected
    assert evolve_main([str(exp), "--out", str(tmp_path / "ray"), "--backend", "ray", "--workers", "2",
                        "--no-progress"]) == 0
    assert comparable_stats(tmp_path / "ray") == expected


def test_unknown_backend_and_missing_ray_message(tmp_path, monkeypatch, capsys, reference):
    exp, _ = reference
    with pytest.raises(SystemExit):
        evolve_main([str(exp), "--backend", "dask"])
    import builtins

    real_import = builtins.__import__

    def no_ray(name, *args, **kwargs):
        if name == "ray":
            raise ImportError("no ray here")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_ray)
    assert evolve_main([str(exp), "--out", str(tmp_path / "r"), "--backend", "ray", "--no-progress"]) == 2
    assert "pip install" in capsys.readouterr().err
