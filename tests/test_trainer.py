"""End-to-end runs of the trainer on a tiny world: files, resume, parallelism, bad input."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from evolution.cli import evolve_main, replay_main
from evolution.run.champion import ChampionError, load_champion
from evolution.run.checkpoint import CheckpointError, load_checkpoint
from evolution.run.evaluate import trial_seed
from evolution.run.stats import read_stats, without_timing

TINY = """
[experiment]
name = "tiny"
method = "{method}"
objectives = {objectives}
generations = 3
population = 8
trials = 2
seed = 11

[environment]
environment = 1
max_cycles = 120
num_robots = 6
"""


def write_experiment(tmp_path: Path, method: str = "hyperneat-m", objectives: str = '["task"]') -> Path:
    path = tmp_path / f"{method}-{len(objectives)}.toml"
    path.write_text(TINY.format(method=method, objectives=objectives))
    return path


@pytest.fixture(scope="module")
def serial_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("serial")
    exp = write_experiment(tmp)
    assert evolve_main([str(exp), "--out", str(tmp / "run"), "--workers", "1", "--no-progress"]) == 0
    return exp, tmp / "run"


def test_run_writes_stats_checkpoints_and_champion(serial_run):
    _, run = serial_run
    records = read_stats(run / "stats.jsonl")
    assert [r["generation"] for r in records] == [0, 1, 2]
    assert (run / "stats.csv").read_text().startswith("generation,")
    assert (run / "stats.png").stat().st_size > 0
    assert sorted(p.name for p in (run / "checkpoints").iterdir()) == ["gen-0001.ckpt", "gen-0002.ckpt", "gen-0003.ckpt"]
    assert load_checkpoint(run / "checkpoints" / "gen-0003.ckpt")["population"].generation == 3
    champion = load_champion(run / "champion.json")
    assert champion.objectives["task"] == max(r["task_best"] for r in records)
    assert champion.controller.num_inputs == len(champion.morphology)
    doc = json.loads((run / "champion.json").read_text())
    assert doc["genome"]["connections"]                           # the genome as plain data


def test_resume_from_generation_two_continues_the_same_lineage(serial_run, tmp_path):
    exp, run = serial_run
    copy = tmp_path / "copy"
    shutil.copytree(run, copy)
    ckpt = copy / "checkpoints" / "gen-0002.ckpt"
    assert evolve_main([str(exp), "--out", str(copy), "--resume-from", str(ckpt), "--workers", "1", "--no-progress"]) == 0
    assert without_timing(read_stats(copy / "stats.jsonl")) == without_timing(read_stats(run / "stats.jsonl"))


def test_two_workers_give_identical_statistics(serial_run, tmp_path):
    exp, run = serial_run
    assert evolve_main([str(exp), "--out", str(tmp_path / "par"), "--workers", "2", "--no-progress"]) == 0
    assert without_timing(read_stats(tmp_path / "par" / "stats.jsonl")) == without_timing(read_stats(run / "stats.jsonl"))


def test_trial_seeds_depend_on_run_generation_and_trial_only():
    assert trial_seed(1, 2, 3) == trial_seed(1, 2, 3)
    assert len({trial_seed(1, g, t) for g in range(5) for t in range(5)}) == 25


def test_existing_run_is_not_overwritten(serial_run, capsys):
    exp, run = serial_run
    before = (run / "stats.jsonl").read_bytes()
    assert evolve_main([str(exp), "--out", str(run), "--workers", "1", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "not empty" in err and f"--resume {run}" in err
    assert (run / "stats.jsonl").read_bytes() == before


@pytest.mark.parametrize("text,needle", [
    ("[experiment]\ngenerations = 'many'\n", "generations"),
    ("[experiment]\ngeneratons = 3\n", "generatons"),
    ("[experiment]\nmethod = 'neat-x'\n", "method"),
    ("[environment]\nenvironment = 9\n", "environment=9"),
    ("[experiment\n", "not valid TOML"),
    ("[other]\nx = 1\n", "unknown section"),
    ("", "experiment file is empty"),
    ("# nothing but a comment\n", "experiment file is empty"),
    ("experiment = 3\n", "allowed: a [experiment] table"),
    ("[experiment]\ntrials = 100000\n", "trials=100000; allowed: an integer in [1, 1000]"),
    ("[experiment]\nmethod = 'neat-m'\n[substrate]\nbottom_on_node0 = true\n", "[substrate] is used by method"),
])
def test_broken_experiment_file_is_one_line_error(tmp_path, capsys, text, needle):
    """Broken or unworkable experiment files: one line naming the file and the field, exit 2,
    no run directory made."""
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert evolve_main([str(path), "--out", str(tmp_path / "run"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert needle in err and str(path) in err
    assert not (tmp_path / "run").exists()
    assert not (tmp_path / "run").exists()


def test_broken_neat_config_is_named(tmp_path, capsys):
    cfg = tmp_path / "broken.cfg"
    cfg.write_text("[NEAT]\npop_size = 3\n")
    exp = tmp_path / "exp.toml"
    exp.write_text(f'[experiment]\nneat_config = "{cfg}"\n')
    assert evolve_main([str(exp), "--out", str(tmp_path / "run"), "--no-progress"]) == 2
    assert str(cfg) in capsys.readouterr().err


def test_truncated_checkpoint_is_refused_and_previous_used(serial_run, tmp_path, capsys):
    exp, run = serial_run
    copy = tmp_path / "copy"
    shutil.copytree(run, copy)
    newest = copy / "checkpoints" / "gen-0003.ckpt"
    newest.write_bytes(newest.read_bytes()[:-50])
    with pytest.raises(CheckpointError, match="truncated or corrupt"):
        load_checkpoint(newest)
    assert evolve_main([str(exp), "--out", str(copy), "--resume-from", str(newest), "--no-progress"]) == 2
    assert "gen-0003.ckpt" in capsys.readouterr().err
    # --resume without a file falls back to the newest readable checkpoint (generation 2).
    assert evolve_main([str(exp), "--out", str(copy), "--resume", "--workers", "1", "--no-progress"]) == 0
    assert without_timing(read_stats(copy / "stats.jsonl")) == without_timing(read_stats(run / "stats.jsonl"))


def test_replay_and_broken_champions(serial_run, tmp_path, capsys):
    _, run = serial_run
    out = tmp_path / "team.gif"
    assert replay_main([str(run / "champion.json"), "--steps", "30", "--out", str(out), "--frame-every", "10"]) == 0
    assert out.read_bytes()[:3] == b"GIF"
    broken = tmp_path / "broken.json"
    broken.write_text((run / "champion.json").read_text()[:100])
    assert replay_main([str(broken), "--out", str(tmp_path / "x.gif")]) == 2
    assert "not valid JSON" in capsys.readouterr().err
    other = json.loads((run / "champion.json").read_text())
    other["version"] = 99
    (tmp_path / "v99.json").write_text(json.dumps(other))
    with pytest.raises(ChampionError, match="version"):
        load_champion(tmp_path / "v99.json")
    assert replay_main([str(tmp_path / "missing.json")]) == 2


def test_neat_m_and_multi_objective_runs(tmp_path):
    exp = write_experiment(tmp_path, method="neat-m", objectives='["task", "morphology"]')
    assert evolve_main([str(exp), "--out", str(tmp_path / "mo"), "--workers", "1", "--no-progress"]) == 0
    records = read_stats(tmp_path / "mo" / "stats.jsonl")
    assert all("front" in r and r["front"]["genomes"] for r in records)
    front_files = sorted((tmp_path / "mo" / "front").glob("*.json"))
    assert len(front_files) == len(records[-1]["front"]["genomes"])
    objectives = [load_champion(f).objectives for f in front_files]
    assert all({"task", "morphology", "controller"} <= set(o) for o in objectives)


def test_stop_signals_ask_then_insist_and_put_the_handlers_back(capsys):
    """The first signal asks (the generation finishes), a second abandons it; on leaving, each
    signal has the handler it had before (a run inside a program must not keep its handlers)."""
    import os
    import signal

    from evolution.run.signals import SIGNALS, StopSignals

    def mine(signum, frame):
        raise AssertionError("the program's handler ran inside the run")

    before = {sig: signal.getsignal(sig) for sig in SIGNALS}
    signal.signal(signal.SIGTERM, mine)
    try:
        with StopSignals(lambda: 7) as stop:
            assert not stop.requested
            os.kill(os.getpid(), signal.SIGTERM)
            assert stop.requested and "finishing generation 7" in capsys.readouterr().out
            with pytest.raises(KeyboardInterrupt):
                os.kill(os.getpid(), signal.SIGINT)
        assert signal.getsignal(signal.SIGTERM) is mine
        assert signal.getsignal(signal.SIGINT) is before[signal.SIGINT]
        assert signal.getsignal(signal.SIGHUP) is before[signal.SIGHUP]
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)


def test_a_finished_run_leaves_the_signal_handlers_as_they_were(tmp_path):
    import signal

    before = signal.getsignal(signal.SIGINT)
    exp = write_experiment(tmp_path)
    assert evolve_main([str(exp), "--out", str(tmp_path / "run"), "--workers", "1", "--no-progress",
                        "--generations", "1"]) == 0
    assert signal.getsignal(signal.SIGINT) is before
