"""One test per class of failure: data loss, hangs, tracebacks, silent acceptance, analysis
input and resume. Every refusal is one line ``error: ...`` with exit status 2 and leaves
the files it was given byte for byte as they were."""

from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from small_runs import comparable_stats

from evolution.cli import analyze_main, evolve_main, replay_main
from evolution.compare import compare_main
from evolution.run import backends
from evolution.run.stats import read_stats
from gathering_env import parallel_env

ROOT = Path(__file__).resolve().parent.parent
# A small arena so that a few steps already gather something (best ft > 0).
TINY = """
[experiment]
name = "tiny"
generations = {generations}
population = 6
trials = 1
seed = 5
[environment]
environment = 1
max_cycles = 150
num_robots = 8
arena_width = 10.0
arena_height = 10.0
zone_width = 6.0
zone_depth = 2.0
"""


def write_tiny(folder: Path, generations: int = 2) -> Path:
    path = folder / f"tiny{generations}.toml"
    path.write_text(TINY.format(generations=generations))
    return path


def snapshot(root: Path) -> dict[str, str]:
    """Every file under ``root`` (relative path -> sha256): 'unchanged byte for byte'."""
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


def call(main, args: list[str]) -> int:
    """Exit status of a CLI main called in-process (argparse errors raise SystemExit)."""
    try:
        return main(args)
    except SystemExit as stop:
        return stop.code


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and len(err.splitlines()) == 1 and "Traceback" not in err, err
    return err


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A finished 3-generation run (serial) and its experiment file."""
    tmp = tmp_path_factory.mktemp("finished")
    exp = write_tiny(tmp, generations=3)
    assert evolve_main([str(exp), "--out", str(tmp / "run"), "--workers", "1", "--no-progress"]) == 0
    assert max(r["task_best"] for r in read_stats(tmp / "run" / "stats.jsonl")) > 0
    return exp, tmp / "run"


# ---------------------------------------------------------------- data loss
def partial_dirs(run: Path, root: Path) -> dict[str, Path]:
    a = root / "champion-and-plot"
    a.mkdir()
    for name in ("champion.json", "stats.png"):
        shutil.copy(run / name, a / name)
    b = root / "no-checkpoints"          # the user deleted checkpoints and stats to save space
    (b / "front").mkdir(parents=True)
    for name in ("experiment.json", "champion.json"):
        shutil.copy(run / name, b / name)
    shutil.copy(run / "champion.json", b / "front" / "genome-7.json")
    c = root / "user-files"
    c.mkdir()
    (c / "notes.txt").write_text("my notes\n")
    return {"a": a, "b": b, "c": c}


@pytest.mark.parametrize("resume", [False, True])
def test_partial_run_directory_is_refused_and_unchanged(finished, tmp_path, capsys, resume):
    exp, run = finished
    for folder in partial_dirs(run, tmp_path).values():
        before = snapshot(folder)
        args = ["--resume", str(folder)] if resume else [str(exp), "--out", str(folder)]
        assert evolve_main([*args, "--workers", "1", "--no-progress"]) == 2
        err = one_error_line(capsys)
        assert str(folder) in err
        assert snapshot(folder) == before


def test_other_commands_never_overwrite_foreign_files(finished, tmp_path, capsys):
    _, run = finished
    before = snapshot(run)
    assert analyze_main([str(run), "--out", str(run)]) == 2           # a run directory is not a report folder
    assert "not empty" in one_error_line(capsys)
    assert call(compare_main, ["--policy", "random", "--steps", "5", "--episodes", "1", "--out", str(run)]) == 2
    assert "not empty" in one_error_line(capsys)
    assert replay_main([str(run / "champion.json"), "--steps", "5", "--png", str(run / "champion.json")]) == 2
    assert "--png" in one_error_line(capsys)
    notes = tmp_path / "notes.gif"
    notes.write_text("not a picture")
    assert replay_main([str(run / "champion.json"), "--steps", "5", "--out", str(notes)]) == 2
    assert "not a .gif file this command wrote" in one_error_line(capsys)
    assert snapshot(run) == before and notes.read_text() == "not a picture"
    # An earlier output of the same command is replaced.
    report = tmp_path / "report"
    assert analyze_main([str(run), "--out", str(report)]) == 0
    assert analyze_main([str(run), "--out", str(report)]) == 0
    gif = tmp_path / "team.gif"
    assert replay_main([str(run / "champion.json"), "--steps", "5", "--out", str(gif)]) == 0
    assert replay_main([str(run / "champion.json"), "--steps", "5", "--out", str(gif)]) == 0


# ---------------------------------------------------------------- hangs
def test_sizes_are_bounded_before_allocating(finished, tmp_path, capsys):
    exp, _ = finished
    assert call(evolve_main, [str(exp), "--population", "100000000", "--out", str(tmp_path / "r")]) == 2
    assert "--population" in one_error_line(capsys)
    big = tmp_path / "big.toml"
    big.write_text("[experiment]\npopulation = 100000000\n")
    assert evolve_main([str(big), "--out", str(tmp_path / "r")]) == 2
    assert "population=100000000; allowed: an integer in [2, 10000]" in one_error_line(capsys)
    assert call(evolve_main, [str(exp), "--workers", "100000", "--out", str(tmp_path / "r")]) == 2
    assert "--workers" in one_error_line(capsys)
    assert not (tmp_path / "r").exists()


def children(pid: int) -> set[int]:
    found = set()
    for task in Path(f"/proc/{pid}/task").iterdir():
        text = (task / "children").read_text().split()
        found |= {int(c) for c in text}
    return found


def alive(pid: int) -> bool:
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except FileNotFoundError:
        return False
    return "\nState:\tZ" not in status


def signal_mask(pid: int, field: str) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1], 16)
    raise KeyError(field)


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs Linux /proc")
def test_orphaned_workers_exit_after_the_trainer_is_sigkilled(tmp_path):
    exp = tmp_path / "slow.toml"
    exp.write_text(TINY.format(generations=50).replace("max_cycles = 150", "max_cycles = 5000"))
    env = dict(os.environ, SDL_VIDEODRIVER="dummy", PYTHONPATH=str(ROOT))
    trainer = subprocess.Popen([sys.executable, "-m", "evolution", str(exp), "--out", str(tmp_path / "run"),
                                "--workers", "2", "--no-progress"], cwd=ROOT, env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers: set[int] = set()
    try:
        deadline = time.time() + 60
        while len(workers) < 2 and time.time() < deadline:
            workers = {c for c in children(trainer.pid) if alive(c)}
            time.sleep(0.1)
        assert len(workers) >= 2, "the pool workers did not start"
        time.sleep(0.5)  # let the initializers run
        for w in workers:
            assert signal_mask(w, "SigIgn") & (1 << (signal.SIGINT - 1))          # Ctrl-C is the trainer's
            assert not signal_mask(w, "SigCgt") & (1 << (signal.SIGTERM - 1))     # no inherited handler
        trainer.send_signal(signal.SIGKILL)
        trainer.wait(timeout=30)
        deadline = time.time() + 30  # generous: the watchdog polls every 0.5 s
        while any(alive(w) for w in workers) and time.time() < deadline:
            time.sleep(0.1)
        assert not any(alive(w) for w in workers), "orphaned workers kept running"
    finally:
        if trainer.poll() is None:
            trainer.kill()
            trainer.wait(timeout=30)
        for w in workers:  # only if the test failed: never leave processes behind
            if alive(w):
                os.kill(w, signal.SIGKILL)


# ---------------------------------------------------------------- tracebacks
@pytest.mark.parametrize("case", ["out-is-file", "out-under-file", "experiment-is-dir", "champion-is-dir",
                                  "analyze-file", "frame-every-0", "compare-episodes-0", "resume-from-dir",
                                  "png-suffix", "resume-which-run", "resume-two-dirs", "evolve-steps-0",
                                  "evolve-robots-0", "evolve-environment-7"])
def test_unusable_paths_and_options_are_one_line_errors(finished, tmp_path, capsys, case):
    exp, run = finished
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    main, args, needle = {
        "out-is-file": (evolve_main, [str(exp), "--out", str(a_file)], f"{a_file}: is a file"),
        "out-under-file": (evolve_main, [str(exp), "--out", str(a_file / "run")], "is a file, not a folder"),
        "experiment-is-dir": (evolve_main, [str(run), "--out", str(tmp_path / "r")], f"{run}: is a folder"),
        "champion-is-dir": (replay_main, [str(run), "--out", str(tmp_path / "t.gif")], f"{run}: is a folder"),
        "analyze-file": (analyze_main, [str(a_file), "--out", str(tmp_path / "rep")], f"{a_file}: is a file"),
        "frame-every-0": (replay_main, [str(run / "champion.json"), "--frame-every", "0"], "--frame-every"),
        "compare-episodes-0": (compare_main, ["--policy", "random", "--episodes", "0"], "--episodes"),
        "resume-from-dir": (evolve_main, ["--resume-from", str(run)], "--resume-from"),
        "png-suffix": (replay_main, [str(run / "champion.json"), "--png", str(tmp_path / "x.jpg")], "--png"),
        "resume-which-run": (evolve_main, ["--resume"], "--resume: which run?"),
        "resume-two-dirs": (evolve_main, ["--resume", str(run), "--out", str(tmp_path / "r")], "differs from --out"),
        # a world override names its flag, not the experiment file's key
        "evolve-steps-0": (evolve_main, [str(exp), "--steps", "0", "--out", str(tmp_path / "r")], "--steps"),
        "evolve-robots-0": (evolve_main, [str(exp), "--robots", "0", "--out", str(tmp_path / "r")], "--robots"),
        "evolve-environment-7": (evolve_main, [str(exp), "--environment", "7", "--out", str(tmp_path / "r")],
                                 "--environment"),
    }[case]
    assert call(main, args) == 2
    assert needle in one_error_line(capsys)
    assert not (tmp_path / "r").exists() and not (tmp_path / "rep").exists()


def test_unwritable_run_directory_mid_run_is_one_line_and_resumable(tmp_path, capsys, monkeypatch):
    from evolution.run import recorder as trainer_module

    exp = write_tiny(tmp_path, generations=2)
    real = trainer_module.append_stats
    calls = []

    def append_then_fail(path, record):
        calls.append(record["generation"])
        if record["generation"] == 1:
            raise PermissionError(13, "Permission denied", str(path))
        real(path, record)

    monkeypatch.setattr(trainer_module, "append_stats", append_then_fail)
    run = tmp_path / "run"
    assert evolve_main([str(exp), "--out", str(run), "--workers", "1", "--no-progress"]) == 2
    err = one_error_line(capsys)
    assert "stats.jsonl: permission denied" in err and f"--resume {run}" in err
    monkeypatch.setattr(trainer_module, "append_stats", real)
    assert evolve_main(["--resume", str(run), "--workers", "1", "--no-progress"]) == 0
    assert [r["generation"] for r in read_stats(run / "stats.jsonl")] == [0, 1]


def test_local_ray_that_fails_to_start_is_one_line(finished, tmp_path, capsys, monkeypatch):
    ray = pytest.importorskip("ray")
    exp, _ = finished

    def broken_init(**kwargs):
        raise ConnectionError("could not start the GCS server\nsecond line")

    monkeypatch.setattr(ray, "init", broken_init)
    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    assert evolve_main([str(exp), "--out", str(tmp_path / "r"), "--backend", "ray", "--no-progress"]) == 2
    assert "--backend ray: Ray did not start (second line)" in one_error_line(capsys)
    assert not (tmp_path / "r").exists()                 # nothing written before the backend is up
    with socket.socket() as s:                           # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    assert evolve_main([str(exp), "--out", str(tmp_path / "r"), "--backend", "ray", "--ray-address",
                        f"127.0.0.1:{port}", "--no-progress"]) == 2
    assert f"--ray-address 127.0.0.1:{port}: cannot connect" in one_error_line(capsys)
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize("kwargs,error,needle", [
    (dict(options=5), TypeError, "options=5"),
    (dict(options=[("morphology", None)]), TypeError, "options="),
    (dict(seed=True), TypeError, "seed=True"),
    (dict(seed=1.5), TypeError, "seed=1.5"),
    (dict(seed=-1), ValueError, "seed=-1"),
])
def test_env_reset_names_the_bad_argument(kwargs, error, needle):
    env = parallel_env(max_cycles=5)
    with pytest.raises(error, match=needle.replace("(", r"\(").replace("[", r"\[")):
        env.reset(**kwargs)
    env.reset(seed=np.int64(3))      # numpy integers are seeds too
    with pytest.raises(TypeError, match="actions must be a dict"):
        env.step([0.0, 0.0])


# ---------------------------------------------------------------- silent acceptance
def test_impossible_world_fails_at_start_up(tmp_path, capsys):
    crowded = tmp_path / "crowded.toml"
    crowded.write_text("[environment]\nenvironment = 2\nblock_counts = [3000, 3000, 3000]\n")
    assert evolve_main([str(crowded), "--out", str(tmp_path / "r"), "--no-progress"]) == 2
    err = one_error_line(capsys)
    assert str(crowded) in err and "block_counts=(3000, 3000, 3000)" in err and "allowed: at most 45%" in err
    # A single block larger than the arena.
    huge = tmp_path / "huge.toml"
    huge.write_text("[environment]\nblock_sizes = [0.4, 0.6, 50.0]\n")
    assert evolve_main([str(huge), "--out", str(tmp_path / "r"), "--no-progress"]) == 2
    assert "does not fit into the arena" in one_error_line(capsys)
    assert not (tmp_path / "r").exists()
    with pytest.raises(ValueError, match="block_counts"):
        parallel_env(block_counts=(3000, 3000, 3000))       # the env API: at construction, not at reset


def test_world_check_by_hand():
    """Cover of the free floor, by hand: robots of radius 0.15 and one small block (half
    diagonal 0.2 sqrt 2), each grown by half the 0.05 gap, in a 10 x 10 arena with a 6 x 2 zone
    (88 square units free). Robot pi 0.175^2 = 0.096211, block pi 0.307843^2 = 0.297720:
    0.45 * 88 = 39.6 allows (39.6 - 0.29772) / 0.096211 = 408.5 robots."""
    from gathering_env.config import WorldConfig
    from gathering_env.placement import check_room as _check_room
    from gathering_env.world import GatheringWorld

    small = dict(environment=None, arena_width=10.0, arena_height=10.0, zone_width=6.0, zone_depth=2.0,
                 block_counts=(1, 0, 0))

    def radii(robots):
        return np.array([0.2 * math.sqrt(2)] + [0.15] * robots)

    _check_room(WorldConfig.from_kwargs(**small, num_robots=408), radii(408))
    with pytest.raises(ValueError, match="cover 45%"):
        _check_room(WorldConfig.from_kwargs(**small, num_robots=409), radii(409))
    GatheringWorld.check_placement(WorldConfig.from_kwargs(**small, num_robots=100))
    with pytest.raises(ValueError, match="cover 45%"):
        GatheringWorld.check_placement(WorldConfig.from_kwargs(**small, num_robots=409))


@pytest.mark.parametrize("value", ["", ",", "task,,morphology"])
def test_empty_objectives_option_is_refused(finished, tmp_path, capsys, value):
    exp, _ = finished
    assert evolve_main([str(exp), "--objectives", value, "--out", str(tmp_path / "r"), "--no-progress"]) == 2
    assert "objectives=" in one_error_line(capsys)


@pytest.mark.parametrize("key,old,new,needle", [
    ("weight_mutate_rate", "0.05", "-0.1", "weight_mutate_rate = -0.1; allowed: a probability in [0, 1]"),
    ("conn_add_prob", "0.005", "1.5", "conn_add_prob = 1.5"),
    ("weight_mutate_power", "0.5", "nan", "weight_mutate_power = nan"),
    ("parent_fraction", "0.3", "0.0", "parent_fraction=0.0; allowed: (0, 1]"),
    ("max_stagnation", "20", "0", "max_stagnation = 0"),
    ("num_hidden", "0", "100000", "num_hidden = 100000"),
])
def test_neat_config_rates_and_bounds_are_checked(tmp_path, capsys, key, old, new, needle):
    text = (ROOT / "configs" / "hyperneat_m.neat.cfg").read_text()
    line = next(raw for raw in text.splitlines() if raw.split("=")[0].strip() == key)
    assert line.split("=")[1].strip() == old
    cfg = tmp_path / "bad.cfg"
    cfg.write_text(text.replace(line, f"{key} = {new}"))
    exp = tmp_path / "exp.toml"
    exp.write_text(f'[experiment]\nneat_config = "{cfg}"\n')
    assert evolve_main([str(exp), "--out", str(tmp_path / "r"), "--no-progress"]) == 2
    err = one_error_line(capsys)
    assert needle in err and str(cfg) in err
    assert not (tmp_path / "r").exists()


def test_a_run_whose_evaluations_all_fail_stops_with_an_error(finished, tmp_path, capsys, monkeypatch):
    exp, _ = finished

    def broken(self, genome, generation):
        raise RuntimeError("simulator exploded")

    monkeypatch.setattr(backends.EvalContext, "evaluate", broken)
    run = tmp_path / "run"
    assert evolve_main([str(exp), "--out", str(run), "--backend", "serial", "--max-retries", "0",
                        "--no-progress"]) == 2
    err = one_error_line(capsys)
    assert "every evaluation of generation 0 failed" in err and "simulator exploded" in err
    assert "errors.log" in err and f"--resume {run}" in err
    assert read_stats(run / "stats.jsonl") == []                  # no made-up statistics
    assert (run / "errors.log").read_text().count("simulator exploded") == 6


# ---------------------------------------------------------------- analysis input
def test_analysis_input_is_checked_and_files_are_named(finished, tmp_path, capsys):
    _, run = finished
    torn = tmp_path / "torn"
    shutil.copytree(run, torn)
    stats = torn / "stats.jsonl"
    stats.write_bytes(stats.read_bytes()[:-25])
    assert analyze_main([str(torn), "--out", str(tmp_path / "rep1")]) == 0
    err = capsys.readouterr().err
    assert f"warning: {stats}: last line (3) is cut short" in err
    # The same run twice (also spelled differently) counts once.
    assert analyze_main([str(run), str(run / ".." / run.name), "--out", str(tmp_path / "rep2")]) == 0
    captured = capsys.readouterr()
    assert captured.out.startswith("1 runs") and "counted once" in captured.err

    def broken(name: str, edit) -> Path:
        copy = tmp_path / name
        shutil.copytree(run, copy)
        edit(copy)
        return copy

    cases = [
        (broken("nan", lambda d: (d / "champion.json").write_text(
            (d / "champion.json").read_text().replace('"task": ', '"task": NaN, "x": '))),
         "champion.json: objectives.task = nan"),
        (broken("nochamp", lambda d: (d / "champion.json").unlink()), "champion.json: missing"),
        (broken("noobj", lambda d: (d / "champion.json").write_text('{"format": 1}')),
         "champion.json: field 'objectives' is missing"),
        (broken("corrupt", lambda d: (d / "champion.json").write_text('{"objectives": ')),
         "champion.json: not valid JSON"),
        (broken("badexp", lambda d: (d / "experiment.json").write_text("[1, 2")), "experiment.json: not valid JSON"),
    ]
    for folder, needle in cases:
        assert analyze_main([str(run), str(folder), "--out", str(tmp_path / "rep3")]) == 2
        err = one_error_line(capsys)
        assert needle in err and str(folder) in err, err
    assert not (tmp_path / "rep3").exists()


# ---------------------------------------------------------------- resume
def test_resume_with_the_run_directory_alone(finished, tmp_path, capsys):
    exp, run = finished
    killed = tmp_path / "killed"
    shutil.copytree(run, killed)
    (killed / "checkpoints" / "gen-0003.ckpt").unlink()            # as if killed during generation 2
    lines = (killed / "stats.jsonl").read_text().splitlines(keepends=True)
    (killed / "stats.jsonl").write_text("".join(lines[:2]) + lines[2][:30])
    assert evolve_main(["--resume", str(killed), "--workers", "1", "--no-progress"]) == 0
    assert comparable_stats(killed) == comparable_stats(run)
    assert (killed / "champion.json").read_bytes() == (run / "champion.json").read_bytes()


def test_resume_of_a_finished_run_says_so_and_changes_nothing(finished, capsys):
    exp, run = finished
    before = snapshot(run)
    best = max(r["task_best"] for r in read_stats(run / "stats.jsonl"))
    for args in (["--resume", str(run)], ["--resume-from", str(run / "checkpoints" / "gen-0003.ckpt")],
                 [str(exp), "--out", str(run), "--resume"]):
        assert evolve_main([*args, "--no-progress"]) == 0
        out = capsys.readouterr().out
        assert "already finished" in out and f"best ft {best:.2f}" in out, out
    assert snapshot(run) == before


def test_resume_falls_back_past_a_damaged_checkpoint_and_says_so(finished, tmp_path, capsys):
    exp, run = finished
    copy = tmp_path / "copy"
    shutil.copytree(run, copy)
    newest = copy / "checkpoints" / "gen-0003.ckpt"
    newest.write_bytes(newest.read_bytes()[:-40])
    assert evolve_main(["--resume", str(copy), "--workers", "1", "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert f"warning: {newest}: checkpoint is truncated or corrupt" in err and "gen-0002.ckpt" in err
    assert comparable_stats(copy) == comparable_stats(run)


def test_deleted_run_files_are_rebuilt_from_the_checkpoint(finished, tmp_path, capsys):
    exp, run = finished
    copy = tmp_path / "copy"
    shutil.copytree(run, copy)
    for name in ("champion.json", "experiment.json", "stats.jsonl", "stats.csv", "neat.cfg"):
        (copy / name).unlink()
    assert evolve_main(["--resume", str(copy), "--no-progress"]) == 0
    best = max(r["task_best"] for r in read_stats(run / "stats.jsonl"))
    assert best > 0 and f"best ft {best:.2f}" in capsys.readouterr().out
    for name in ("champion.json", "stats.jsonl", "stats.csv", "neat.cfg"):
        assert (copy / name).read_bytes() == (run / name).read_bytes(), name
    rebuilt, original = (json.loads((d / "experiment.json").read_text()) for d in (copy, run))
    assert {k: v for k, v in rebuilt.items() if k not in ("source", "neat_config")} == \
        {k: v for k, v in original.items() if k not in ("source", "neat_config")}
    # A folder mixing two runs is refused, not "repaired".
    (copy / "experiment.json").write_text(json.dumps({**original, "seed": 99}))
    before = snapshot(copy)
    assert evolve_main(["--resume", str(copy), "--no-progress"]) == 2
    assert "'seed' differs from checkpoint" in one_error_line(capsys)
    assert snapshot(copy) == before


def test_resume_from_another_runs_checkpoint_continues_into_a_new_folder(finished, tmp_path):
    exp, run = finished
    before = snapshot(run)
    branch = tmp_path / "branch"
    assert evolve_main(["--resume-from", str(run / "checkpoints" / "gen-0001.ckpt"), "--out", str(branch),
                        "--workers", "1", "--no-progress"]) == 0
    assert comparable_stats(branch) == comparable_stats(run)
    assert snapshot(run) == before
    assert (branch / "checkpoints" / "gen-0003.ckpt").exists()


def test_deleted_front_of_a_multi_objective_run_is_rebuilt(tmp_path):
    exp = tmp_path / "mo.toml"
    exp.write_text(TINY.format(generations=1).replace('seed = 5', 'seed = 5\nobjectives = ["task", "morphology"]'))
    run = tmp_path / "run"
    assert evolve_main([str(exp), "--out", str(run), "--workers", "1", "--no-progress"]) == 0
    front = snapshot(run / "front")
    assert front
    shutil.rmtree(run / "front")
    assert evolve_main(["--resume", str(run), "--no-progress"]) == 0
    assert snapshot(run / "front") == front


def test_a_closed_pipe_ends_the_cli_quietly():
    """`gathering-evolve --list | head -1`: the reader closing the pipe is no file-system error
    and no traceback; the command stops quietly with status 1 (Python's advice for EPIPE)."""
    proc = subprocess.Popen([sys.executable, "-m", "evolution", "--list"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    proc.stdout.close()
    err = proc.stderr.read().decode()
    proc.stderr.close()
    assert proc.wait(timeout=60) == 1 and err == ""
