"""``gathering-replay`` pictures: film strips, sensor layouts, render options and their errors."""

from __future__ import annotations

import json
import math
from pathlib import Path

import imageio.v2 as imageio
import numpy as np
import pytest

from evolution.cli import replay_main
from evolution.encodings.controller import TeamController
from evolution.run.champion import FORMAT, VERSION
from gathering_env import Morphology, SensorSpec
from gathering_env.render import PAGE, WALL, cone_colour_on


@pytest.fixture
def champion(tmp_path):
    """A hand-made champion: ten long cameras, a random single-layer controller, 8 robots."""
    sensors = [SensorSpec("camera", bearing=b, orientation=0.0, range=20.0, fov=math.pi / 2)
               for b in np.linspace(-math.pi, math.pi, 10, endpoint=False)]
    rng = np.random.default_rng(0)
    controller = TeamController.single_layer(rng.normal(size=(2, 10)), rng.normal(size=2))
    doc = {"format": FORMAT, "version": VERSION, "method": "hyperneat-m", "experiment": "handmade",
           "objectives": {"task": 0.0}, "environment": {"environment": 1, "max_cycles": 40, "num_robots": 8},
           "morphology": Morphology(sensors).to_dict(), "controller": controller.to_dict()}
    path = tmp_path / "champion.json"
    path.write_text(json.dumps(doc))
    return path


def wall_runs(row: np.ndarray) -> int:
    is_wall = (row == np.array(WALL)).all(axis=1).astype(int)
    return int(np.sum(np.diff(np.concatenate([[0], is_wall])) == 1))


def test_film_strip_sensor_layout_and_options(champion, tmp_path, capsys):
    out, strip, sensors = tmp_path / "team.gif", tmp_path / "strip.png", tmp_path / "sensors.png"
    assert replay_main([str(champion), "--out", str(out), "--frame-every", "20", "--png", str(strip),
                        "--strip", "0,10,20,40", "--sensors-png", str(sensors), "--no-panel",
                        "--size", "200", "--cones", "0,3", "--view", "zone", "--trail", "5"]) == 0
    printed = capsys.readouterr().out
    assert str(strip) in printed and str(sensors) in printed
    frames = imageio.mimread(out)
    assert len(frames) == 3 and frames[0].shape[:2] == (200, 200)           # --size, --no-panel
    picture = imageio.imread(strip)[..., :3]
    assert picture.shape[1] == 4 * 200 + 3 * 8                              # four panels side by side
    layout = imageio.imread(sensors)[..., :3]
    tint = np.array(cone_colour_on(PAGE, "camera"))
    assert (np.abs(layout.astype(int) - tint).max(axis=2) <= 1).mean() > 0.05   # cones drawn


def test_film_strip_panels_full_view(champion, tmp_path):
    strip = tmp_path / "strip.png"
    assert replay_main([str(champion), "--out", str(tmp_path / "t.gif"), "--png", str(strip),
                        "--strip", "0,40", "--size", "160"]) == 0
    picture = imageio.imread(strip)[..., :3]
    assert wall_runs(picture[80]) == 2 * 2                                  # two arenas, two walls each


@pytest.mark.parametrize("args,message", [
    (["--cones", "3,x"], "error: --cones: '3,x' is not a choice nor a list of robot indices; allowed: "
                         "'auto', 'all', 'none' or robot indices in 0..7"),
    (["--cones", "9"], "error: --cones: robot index 9 does not exist (8 robots); allowed:"),
    (["--view", "top"], "error: --view: 'top' is not a view; allowed: 'full', 'zone' or 'follow:K' with K in 0..7"),
    (["--view", "follow:8"], "error: --view: robot 8 does not exist"),
    (["--size", "20"], "error: --size: 20 is not an integer in 64..4096; allowed: an integer in 64..4096 (pixels)"),
    (["--size", "100000"], "error: --size: 100000 is not an integer in 64..4096"),
    (["--trail", "-2"], "error: --trail: -2 is not an integer >= 0; allowed:"),
    (["--min-robot-px", "0"], "error: --min-robot-px: 0 is not an integer >= 1; allowed:"),
    (["--strip", "0,50", "--png", "s.png"], "error: --strip: step 50 is outside the episode; allowed: "
                                            "comma-separated steps in 0..40"),
    (["--strip", "0,a", "--png", "s.png"], "error: --strip: '0,a' is not a list of steps; allowed:"),
    (["--strip", "0,10"], "error: --strip: a film strip needs a picture file; allowed: --png FILE.png"),
    (["--png", "s.jpg"], "error: --png s.jpg: suffix '.jpg'; allowed: .png"),
    (["--sensors-png", "s.gif"], "error: --sensors-png s.gif: suffix '.gif'; allowed: .png"),
    (["--world", "max_cycles=5"], "error: --world max_cycles: the command's option --steps sets it; allowed: that option"),
    (["--world", "weld_spin=loose"], "error: --world weld_spin='loose': weld_spin='loose'; allowed: 'held', 'free'"),
    (["--world", "zone_width=-1"], "error: --world zone_width=-1: "),
])
def test_bad_replay_options_exit_2_with_one_line(champion, tmp_path, capsys, monkeypatch, args, message):
    monkeypatch.chdir(tmp_path)
    assert replay_main([str(champion), "--out", "team.gif", *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith(message) and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["champion.json"]  # nothing written


def test_replay_says_its_episode_is_unseen_and_quotes_the_training_ft(champion, tmp_path, capsys):
    doc = json.loads(champion.read_text())
    doc["objectives"]["task"] = 12.5  # trained score; the replayed episode scores 0 here
    champion.write_text(json.dumps(doc))
    assert replay_main([str(champion), "--seed", "4", "--out", str(tmp_path / "t.gif")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "ft = 0.00" in lines[0]
    assert lines[1] == ("an unseen episode (seed 4): the training ft 12.50 is the mean over the run's own trial "
                        "episodes; one new episode can score far from it")
    assert replay_main([str(champion), "--steps", "20", "--out", str(tmp_path / "u.gif")]) == 0
    assert "an unseen episode (seed 0) in a changed world (max_cycles): " in capsys.readouterr().out


def test_replay_in_a_world_changed_by_world_settings(champion, tmp_path, capsys):
    """--world KEY=VALUE replays the team in its world with that key changed (here fewer robots:
    the panel-less frames then hold fewer robot pixels) and the note names the changed key."""
    out = tmp_path / "a.gif"
    assert replay_main([str(champion), "--out", str(out), "--no-panel", "--frame-every", "40"]) == 0
    capsys.readouterr()
    fewer = tmp_path / "b.gif"
    assert replay_main([str(champion), "--out", str(fewer), "--no-panel", "--frame-every", "40",
                        "--world", "num_robots=2", "--world", "zone_depth=6"]) == 0
    assert "in a changed world (num_robots, zone_depth)" in capsys.readouterr().out
    first, changed = imageio.mimread(out)[0], imageio.mimread(fewer)[0]
    assert first.shape == changed.shape and not np.array_equal(first, changed)


def test_a_per_run_champion_replayed_on_its_layout_scores_its_training_ft(tmp_path, capsys):
    """The champion records its training episodes (``trial_seeds``): replayed on the run's one
    layout it scores exactly its training ft (the simulation is deterministic), and the note
    says which episode it is; any other seed is unseen and the note names the training layout."""
    from small_runs import evolve, experiment_file

    from evolution.run.champion import load_champion
    from evolution.run.evaluate import trial_seed

    exp = experiment_file(tmp_path, "perrun", "hyperneat-m", '["task"]', generations=2,
                          extra='layout = "per_run"\nelitism = "ratchet"')
    evolve(exp, tmp_path / "run")
    champ = load_champion(tmp_path / "run" / "champion.json")
    layout = trial_seed(3, 0, 0)
    assert champ.trial_seeds == (layout,)
    assert champ.objectives["task"] > 0  # a score a wrong episode would not reproduce by chance
    capsys.readouterr()
    assert replay_main([str(tmp_path / "run" / "champion.json"), "--seed", str(layout),
                        "--out", str(tmp_path / "own.gif")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert f"ft = {champ.objectives['task']:.2f}" in lines[0]
    assert lines[1].startswith(f"its training episode (seed {layout}, the run's one layout)")
    assert replay_main([str(tmp_path / "run" / "champion.json"), "--out", str(tmp_path / "new.gif")]) == 0
    assert f"(its training layout is --seed {layout})" in capsys.readouterr().out


def test_a_replay_that_does_not_reproduce_its_training_ft_says_so(tmp_path, capsys):
    """The converged S1 champion of docs/evidence/original-S1-shuffled was scored 110.44 on a
    machine whose team controllers took its BLAS kernel and numpy's SIMD code; replayed with
    the compiled controller its training episode scores 105.73 (whatever the BLAS kernel and
    numpy's SIMD code), and the note says that it is not the training ft instead of claiming it is."""
    from evolution.replay import unseen_note
    from evolution.run.champion import load_champion

    path = Path(__file__).resolve().parents[1] / "docs" / "evidence" / "original-S1-shuffled" / "champion.json"
    champion = load_champion(path)
    seed = champion.trial_seeds[0]
    env_config = dict(champion.environment)
    assert champion.trial_ft == ()                       # a file from before 2026-12: the training ft stands in
    assert unseen_note(champion, env_config, seed, 110.436).endswith("so ft equals the training ft 110.44")
    assert "but ft 90.00 is not the ft 110.44 it scored in training" in unseen_note(champion, env_config, seed, 90.0)
    capsys.readouterr()
    assert replay_main([str(path), "--seed", str(seed), "--frame-every", "100000",
                        "--out", str(tmp_path / "own.gif")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "ft = 105.73, gathered 20/20 in 7135 steps" in lines[0]
    assert lines[1].startswith(f"its training episode (seed {seed}, the run's one layout), but ft 105.73 is not "
                               "the ft 110.44 it scored in training")


@pytest.mark.parametrize("value, shown", [([1.0, 2.0], "[1.0, 2.0]"), (["85"], "['85']"), ([True], "[True]")])
def test_a_champion_with_a_bad_trial_ft_is_refused_naming_the_field(tmp_path, capsys, value, shown):
    source = Path(__file__).resolve().parents[1] / "docs" / "evidence" / "original-S1-shuffled" / "champion.json"
    doc = json.loads(source.read_text())
    doc["trial_ft"] = value                              # one trial seed, so one finite ft is allowed
    bad = tmp_path / "champion.json"
    bad.write_text(json.dumps(doc))
    assert replay_main([str(bad), "--out", str(tmp_path / "x.gif")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"error: {bad}: field 'trial_ft' is {shown}; allowed: a finite ft for each of the 1 trial_seeds")
    assert not (tmp_path / "x.gif").exists()
