"""The examples follow the commands' rules: bad input is one line ``error: ...`` with exit
status 2 before any work, the output folder holds nothing but their own earlier output, and
a user's file (summary.md) or a trained model (model.zip) is never overwritten. Also the
commands' conflicting options (--ray-address, --png/--sensors-png) and a folder given as the
experiment."""

from __future__ import annotations

import importlib.util
import json
import shutil
from pathlib import Path

import pytest
import small_runs
from test_hardening import call, one_error_line, write_tiny

from evolution.cli import evolve_main, replay_main

ROOT = Path(__file__).resolve().parent.parent


def load_example(name: str, needs: str | None = None):
    """An example script as a module; skipped when the optional package ``needs`` is missing."""
    if needs is not None:
        pytest.importorskip(needs)
    spec = importlib.util.spec_from_file_location(f"example_{name}", ROOT / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def champion_run(tmp_path_factory):
    _, so, _, _ = small_runs.build(tmp_path_factory)
    return so


def ppo_run(root: Path, evaluation: str = '{"train_steps": 40, "env_steps": 160, "robot_steps": 480, '
                                           '"train_minutes": 0.1}') -> Path:
    run = root / "runs" / "ppo-shaped-local-env1"
    run.mkdir(parents=True)
    (run / "model.zip").write_bytes(b"PK")
    (run / "curve.csv").write_text("env_steps,minutes,ft,team_return\n40,0.1,5.0,1.0\n")
    (run / "evaluation.json").write_text(evaluation)
    return root / "runs"


@pytest.mark.parametrize("case, needle", [
    ("user-summary", "holds summary.md but no rows.json, so not an earlier output of this script"),
    ("user-notes", "folder is not empty (holds notes.txt)"),
    ("steps-0", "--steps: 0 is out of range"),
    ("paired-garbage", "--paired-seeds 'lots': not STEPS=SEEDS"),
    ("runs-missing", "not a folder; allowed: the folder of examples/rl_ppo.py runs"),
    ("champion-missing", "not a folder; allowed: a run directory written by gathering-evolve"),
    ("rows-foreign", "rows.json: entry 'x' is not a policy's row"),
    ("rows-nan", "holds a score that is not a finite number"),
    ("evaluation-broken", "evaluation.json: not valid JSON"),
    ("evaluation-nan", "evaluation.json: env_steps = nan; allowed: a finite number"),
    ("model-broken", "model.zip: not a readable"),
])
def test_rl_figures_refuses_bad_input_in_one_line_before_work(champion_run, tmp_path, capsys, case, needle):
    rl_figures = load_example("rl_figures", needs="stable_baselines3")
    out = tmp_path / "out"
    runs = ppo_run(tmp_path)
    argv = ["--runs", str(runs), "--champion", str(champion_run), "--out", str(out), "--steps", "50"]
    if case == "user-summary":
        out.mkdir()
        (out / "summary.md").write_text("my summary\n")
    elif case == "user-notes":
        out.mkdir()
        (out / "notes.txt").write_text("mine\n")
    elif case == "steps-0":
        argv[-1] = "0"
    elif case == "paired-garbage":
        argv += ["--paired-seeds", "lots"]
    elif case == "runs-missing":
        argv[1] = str(tmp_path / "nope")
    elif case == "champion-missing":
        argv[3] = str(tmp_path / "nope")
    elif case in ("rows-foreign", "rows-nan"):
        out.mkdir()
        rows = {"x": [1, 2]} if case == "rows-foreign" else {
            "random|env1|50": {"policy": "random", "ft_mean": float("nan"), "ft_std": 0.0}}
        (out / "rows.json").write_text(json.dumps(rows))
    elif case == "evaluation-broken":
        shutil.rmtree(runs)
        ppo_run(tmp_path, "{not json")
    elif case == "evaluation-nan":
        shutil.rmtree(runs)
        ppo_run(tmp_path, '{"train_steps": 40, "env_steps": NaN, "robot_steps": 480, "train_minutes": 0.1}')
    before = {p: p.read_bytes() for p in out.rglob("*")} if out.exists() else None
    assert call(rl_figures.main, argv) == 2
    assert needle in one_error_line(capsys)
    if before is None:
        assert not out.exists()                              # nothing written
    else:
        assert {p: p.read_bytes() for p in out.rglob("*")} == before  # the user's files untouched


def test_rl_ppo_refuses_to_overwrite_a_trained_model(tmp_path, capsys):
    rl_ppo = load_example("rl_ppo", needs="stable_baselines3")
    out = tmp_path / "run"
    out.mkdir()
    (out / "model.zip").write_bytes(b"PK weights of an hour of training")
    (out / "curve.csv").write_text("env_steps,minutes,ft,team_return\n")
    assert call(rl_ppo.main, ["--env-steps", "10", "--out", str(out)]) == 2
    assert "holds a trained model (model.zip), which is never overwritten" in one_error_line(capsys)
    assert (out / "model.zip").read_bytes() == b"PK weights of an hour of training"
    assert call(rl_ppo.main, ["--env-steps", "10", "--timesteps", "100", "--out", str(tmp_path / "new")]) == 2
    assert "--timesteps 100: conflicts with --env-steps 10" in one_error_line(capsys)
    assert not (tmp_path / "new").exists()


def test_conflicting_or_ignored_command_options_are_refused(champion_run, tmp_path, capsys):
    exp = write_tiny(tmp_path)
    assert call(evolve_main, [str(exp), "--out", str(tmp_path / "r"), "--ray-address", "auto"]) == 2
    assert "--ray-address auto: only used with --backend ray" in one_error_line(capsys)
    picture = tmp_path / "pic.png"
    assert call(replay_main, [str(champion_run / "champion.json"), "--out", str(tmp_path / "t.gif"), "--png",
                              str(picture), "--sensors-png", str(tmp_path / "." / "pic.png")]) == 2
    assert "--sensors-png" in one_error_line(capsys)
    assert not picture.exists() and not (tmp_path / "t.gif").exists()
    assert not (tmp_path / "r").exists()


def test_a_folder_given_as_the_experiment_is_a_folder_not_an_unknown_preset(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "myrun").mkdir()
    assert call(evolve_main, ["myrun", "--out", str(tmp_path / "r")]) == 2
    err = one_error_line(capsys)
    assert "myrun: is a folder; allowed: a TOML experiment file" in err and "unknown preset" not in err


@pytest.mark.parametrize("case", ["steps-negative", "frame-every-0", "out-foreign-gif", "png-foreign"])
def test_random_episode_refuses_bad_input_in_one_line_and_keeps_files(tmp_path, capsys, case):
    notes = tmp_path / "notes.gif"
    notes.write_text("my notes")
    picture = tmp_path / "mine.png"
    picture.write_text("not a png")
    out = ["--out", str(tmp_path / "new.gif")]
    args, needle = {
        "steps-negative": (["--steps", "-3", *out], "--steps: -3 is out of range"),
        "frame-every-0": (["--frame-every", "0", *out], "--frame-every: 0 is out of range"),
        "out-foreign-gif": (["--steps", "5", "--out", str(notes)], f"--out {notes}: exists and is not a .gif"),
        "png-foreign": (["--steps", "5", *out, "--png", str(picture)], f"--png {picture}: exists and is not a .png"),
    }[case]
    assert call(load_example("random_episode").main, args) == 2
    assert needle in one_error_line(capsys)
    assert notes.read_text() == "my notes" and picture.read_text() == "not a png"
    assert not (tmp_path / "new.gif").exists()


@pytest.mark.parametrize("case", ["out-is-a-file", "step-past-the-end", "pictures-exist", "champion-missing"])
def test_render_gallery_refuses_bad_input_in_one_line_and_keeps_files(champion_run, tmp_path, capsys, case):
    a_file = tmp_path / "gallery"
    a_file.write_text("mine")
    earlier = tmp_path / "earlier"
    earlier.mkdir()
    (earlier / "render-zone.png").write_text("my picture")
    champion = str(champion_run / "champion.json")
    short = ["--steps", "20", "--step", "10"]
    args, needle = {
        "out-is-a-file": ([champion, "--out", str(a_file), *short], f"--out {a_file}: is a file"),
        "step-past-the-end": ([champion, "--out", str(tmp_path / "new"), "--steps", "20", "--step", "21"],
                              "--step: 21 is outside the episode; allowed: 1..20"),
        "pictures-exist": ([champion, "--out", str(earlier), *short], "render-zone.png exists"),
        "champion-missing": ([str(tmp_path / "nope.json"), "--out", str(tmp_path / "new"), *short], "nope.json"),
    }[case]
    assert load_example("render_gallery").main(args) == 2
    assert needle in one_error_line(capsys)
    assert a_file.read_text() == "mine" and (earlier / "render-zone.png").read_text() == "my picture"
    assert not (tmp_path / "new").exists()
