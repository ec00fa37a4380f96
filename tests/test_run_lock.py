"""One writer per run directory: two trainers racing for one --out, a resume of a run that is
still running, a stale lock of a SIGKILLed trainer, statistics that are not one run's record,
a run directory deleted mid-run. Every refusal is one line ``error: ...`` with exit status 2
and leaves the run directory byte for byte as it was."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from small_runs import comparable_stats
from test_hardening import call, one_error_line, snapshot, write_tiny

from evolution.cli import analyze_main, evolve_main
from evolution.run.lock import LOCK_FILE, RunLock
from evolution.run.stats import read_stats

ROOT = Path(__file__).resolve().parent.parent
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}


def evolve_process(*args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "evolution", *args, "--workers", "1", "--no-progress"],
                            env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_for(path: Path, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.02)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted 4-generation run (the record a locked, resumed run must reproduce)."""
    tmp = tmp_path_factory.mktemp("reference")
    exp = write_tiny(tmp, generations=4)
    assert evolve_main([str(exp), "--out", str(tmp / "run"), "--workers", "1", "--no-progress"]) == 0
    return exp, tmp / "run"


def test_a_held_lock_refuses_a_second_writer_naming_the_pid(reference, tmp_path, capsys):
    exp, run = reference
    copy = tmp_path / "copy"
    shutil.copytree(run, copy)
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time; from evolution.run.lock import RunLock; "
                               "RunLock(sys.argv[1]).acquire(); print('held', flush=True); time.sleep(60)",
                               str(copy)], env=ENV, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        before = snapshot(copy)
        assert evolve_main(["--resume", str(copy), "--generations", "6", "--workers", "1", "--no-progress"]) == 2
        err = one_error_line(capsys)
        assert f"{copy}: run directory is in use by process {holder.pid}" in err
        assert snapshot(copy) == before
        fresh = tmp_path / "fresh"
        fresh.mkdir()
        RunLock(fresh).acquire()  # this process holds it: a new run there is refused too
        assert evolve_main([str(exp), "--out", str(fresh), "--workers", "1", "--no-progress"]) == 2
        assert f"in use by process {os.getpid()}" in one_error_line(capsys)
    finally:
        holder.kill()
        holder.wait()


def test_two_trainers_started_at_once_on_one_out(tmp_path):
    exp = write_tiny(tmp_path, generations=25)
    out = tmp_path / "run"
    trainers = [evolve_process(str(exp), "--out", str(out), "--seed", str(seed)) for seed in (5, 6)]
    results = [(p.wait(timeout=300), p.stdout.read(), p.stderr.read(), p.pid) for p in trainers]
    assert sorted(rc for rc, *_ in results) == [0, 2], results
    (_, _, _, winner_pid), = [r for r in results if r[0] == 0]
    (_, _, loser_err, _), = [r for r in results if r[0] == 2]
    winner_seed = (5, 6)[[r[3] for r in results].index(winner_pid)]
    lines = loser_err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and str(out) in lines[0], loser_err
    assert f"in use by process {winner_pid}" in lines[0] or "folder is not empty" in lines[0]
    # The run directory holds the winner's run alone: its experiment and 25 consecutive generations.
    assert json.loads((out / "experiment.json").read_text())["seed"] == winner_seed
    assert [r["generation"] for r in read_stats(out / "stats.jsonl")] == list(range(25))


def test_resume_of_a_running_run_is_refused_and_a_killed_runs_lock_is_taken_over(reference, tmp_path, capsys):
    exp, run = reference
    out = tmp_path / "run"
    trainer = evolve_process(str(exp), "--out", str(out))
    try:
        wait_for(out / "checkpoints" / "gen-0002.ckpt")
        os.kill(trainer.pid, signal.SIGSTOP)  # still alive and holding the lock, deterministically
        before = snapshot(out)
        assert evolve_main(["--resume", str(out), "--workers", "1", "--no-progress"]) == 2
        assert f"{out}: run directory is in use by process {trainer.pid}" in one_error_line(capsys)
        assert snapshot(out) == before
    finally:
        trainer.kill()
        trainer.wait()
    assert evolve_main(["--resume", str(out), "--workers", "1", "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert f"lock of process {trainer.pid}, which is no longer running, taken over" in err
    # the resumed run is the uninterrupted one, generation for generation
    assert comparable_stats(out) == comparable_stats(run)
    assert (out / LOCK_FILE).read_text() == ""  # released at the end


def stats_lines(run: Path) -> list[str]:
    return (run / "stats.jsonl").read_text().splitlines()


@pytest.mark.parametrize("damage", ["interleaved", "garbage-in-the-middle"])
def test_statistics_that_are_not_one_runs_record_are_refused(reference, tmp_path, capsys, damage):
    _, run = reference
    copy = tmp_path / "copy"
    shutil.copytree(run, copy)
    lines = stats_lines(copy)
    if damage == "interleaved":  # what a second writer left: 0,1,2,3,1,2
        lines = lines + lines[1:3]
        needle = "record 5 is generation 1, expected 4"
    else:
        lines = lines[:2] + ["{not json"] + lines[2:]
        needle = "line 3 is not valid JSON"
    (copy / "stats.jsonl").write_text("\n".join(lines) + "\n")
    before = snapshot(copy)
    assert evolve_main(["--resume", str(copy), "--generations", "6", "--workers", "1", "--no-progress"]) == 2
    err = one_error_line(capsys)
    assert f"{copy / 'stats.jsonl'}: " in err and needle in err and "rebuilt from the checkpoint" in err
    assert snapshot(copy) == before
    assert call(analyze_main, [str(copy), "--out", str(tmp_path / "report"), "--reevaluate", "0"]) == 2
    err = one_error_line(capsys)
    assert f"{copy / 'stats.jsonl'}: " in err and needle in err
    assert not (tmp_path / "report").exists()


def test_a_run_directory_deleted_mid_run_is_not_a_success(tmp_path, capsys, monkeypatch):
    from evolution.run.trainer import Trainer

    exp = write_tiny(tmp_path, generations=4)
    out = tmp_path / "run"
    real = Trainer._fitness

    def fitness_then_delete(self, genomes, config):
        real(self, genomes, config)
        if self._generation == 1:
            shutil.rmtree(out)

    monkeypatch.setattr(Trainer, "_fitness", fitness_then_delete)
    assert evolve_main([str(exp), "--out", str(out), "--workers", "1", "--no-progress"]) == 2
    captured = capsys.readouterr()
    assert "finished" not in captured.out
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and f"{out}: the run directory was deleted or replaced" in lines[0], captured.err


def test_resume_refused_for_a_dead_ray_address_writes_nothing(reference, tmp_path, capsys):
    pytest.importorskip("ray")
    _, run = reference
    copy = tmp_path / "copy"
    shutil.copytree(run, copy)
    before = snapshot(copy)
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    assert evolve_main(["--resume", str(copy), "--generations", "6", "--backend", "ray", "--ray-address",
                        f"127.0.0.1:{port}", "--no-progress"]) == 2
    assert "cannot connect" in one_error_line(capsys)
    assert snapshot(copy) == before  # experiment.json (generations 6) was not rewritten first
