"""The original protocol (``protocol = "original"``): each option against the original code's
behaviour or a hand value, the bundle's rules, its presets, and resuming a run under it."""

from __future__ import annotations

import argparse
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from evolution.cli import evolve_main
from evolution.encodings.substrate import Substrate
from evolution.run import backends
from evolution.run.evaluate import Evaluation, episode_seeds, trial_seed
from evolution.run.experiment import ExperimentError, experiment_from_run, load_experiment
from evolution.run.presets import preset_text, resolve_preset
from evolution.run.protocol import ORIGINAL, protocol_values
from evolution.run.recorder import convergence_target
from evolution.run.stats import read_stats, without_work
from gathering_env import Morphology, SensorSpec, morphological_complexity
from gathering_env.compiled import kernels, settle
from gathering_env.config import WorldConfig
from gathering_env.reference.heuristics import pickup_candidates
from gathering_env.simulation import GatheringSimulation

# A small world where blocks get gathered; its zone depth is left to the protocol (4).
WORLD = """
[environment]
environment = 1
arena_width = 10.0
arena_height = 10.0
zone_width = 10.0
block_counts = [8, 0, 0]
max_cycles = 80
num_robots = 10
"""


def experiment(tmp_path, name="orig", generations=3, population=8, body="protocol = \"original\""):
    path = tmp_path / f"{name}.toml"
    path.write_text(f"[experiment]\nname = \"{name}\"\ngenerations = {generations}\npopulation = {population}\n"
                    f"trials = 3\nseed = 5\n{body}\n" + WORLD)
    return path


def evolve(exp, out, *more):
    assert evolve_main([str(exp), "--out", str(out), "--workers", "1", "--no-progress", *more]) == 0


# ---------------------------------------------------------------------------- the bundle
def test_the_protocol_sets_every_original_option(tmp_path):
    exp = load_experiment(experiment(tmp_path))
    assert (exp.layout, exp.elitism, exp.complexity) == ("per_run", "ratchet", "original")
    world = exp.world_config()
    assert (world.zone_depth, world.pickup_box, world.pickup_box_width, world.pickup_box_depth) == (4.0, "centre",
                                                                                                    0.2, 0.1)
    assert exp.substrate["decode_window"] == 0.2
    assert exp.substrate["bias_threshold"] is True and exp.speciation == "original"
    # without the key every option keeps the paper's default ...
    plain = load_experiment(experiment(tmp_path, "plain", body=""))
    assert (plain.layout, plain.elitism, plain.complexity, plain.protocol, plain.speciation) == (
        "per_trial", "species", "paper", None, None)
    assert (plain.world_config().zone_depth, plain.world_config().pickup_box) == (8.0, "front")
    # ... "paper" names those defaults, and each option can be set on its own
    assert protocol_values("paper")["environment"]["zone_depth"] == 8.0
    alone = load_experiment(experiment(tmp_path, "alone", body='layout = "per_run"'))
    assert (alone.layout, alone.elitism) == ("per_run", "species")


@pytest.mark.parametrize("body,needle", [
    ('protocol = "orig"', "[experiment] protocol='orig'; allowed: ['paper', 'original']"),
    ('protocol = "original"\nlayout = "per_trial"',
     "[experiment] layout = 'per_trial' contradicts protocol = 'original'; allowed: 'per_run'"),
    ('protocol = "paper"\nelitism = "ratchet"',
     "[experiment] elitism = 'ratchet' contradicts protocol = 'paper'; allowed: 'species'"),
    ('layout = "everywhere"', "[experiment] layout='everywhere'; allowed: ['per_trial', 'per_run']"),
    ('truncation = "floor"', "[experiment] truncation='floor'; allowed: ['neat', 'encog']"),
    ("weights = 5", "[experiment] weights=5; allowed: ['neat', 'encog']"),
    ('protocol = "original"\nweights = "neat"',
     "[experiment] weights = 'neat' contradicts protocol = 'original'; allowed: 'encog'"),
    ('protocol = "original"\nprotocol_version = 4\ntruncation = "neat"',
     "[experiment] truncation = 'neat' contradicts protocol = 'original' (version 4); allowed: 'encog'"),
    ('protocol = "original"\n[substrate]\nbearings = "atan2"',
     "[substrate] bearings = 'atan2' contradicts protocol = 'original'; allowed: 'atan'"),
])
def test_unknown_or_contradicting_options_name_the_file_and_key(tmp_path, capsys, body, needle):
    path = experiment(tmp_path, body=body)
    with pytest.raises(ExperimentError, match=None) as err:
        load_experiment(path)
    assert str(err.value).startswith(str(path)) and needle in str(err.value)
    assert evolve_main([str(path), "--out", str(tmp_path / "run")]) == 2
    out = capsys.readouterr().err.strip()
    assert len(out.splitlines()) == 1 and needle in out
    assert not (tmp_path / "run").exists()


def test_a_world_key_contradicting_the_protocol_is_refused(tmp_path, capsys):
    path = experiment(tmp_path)
    path.write_text(path.read_text() + "zone_depth = 8\n")
    assert evolve_main([str(path), "--out", str(tmp_path / "run")]) == 2
    assert f"{path}: [environment] zone_depth = 8 contradicts protocol = 'original'; allowed: 4.0" in \
        capsys.readouterr().err
    # the command-line flag contradicts a file's own key in the same way
    plain = experiment(tmp_path, "plain", body='elitism = "species"')
    assert evolve_main([str(plain), "--protocol", "original", "--out", str(tmp_path / "run")]) == 2
    assert "[experiment] elitism = 'species' contradicts protocol = 'original'" in capsys.readouterr().err


def test_presets_under_the_original_protocol(capsys):
    path, overrides = resolve_preset("S1-original")
    assert path.name == "S1.toml" and overrides == {"protocol": "original", "name": "S1-original"}
    s1 = load_experiment(path)
    s1o = load_experiment(path, overrides)
    assert (s1o.name, s1o.protocol, s1o.population, s1o.generations, s1o.trials) == ("S1-original", "original",
                                                                                    150, 250, 5)
    assert s1o.world_config().max_cycles == s1.world_config().max_cycles == 10_000
    assert s1o.environment == s1.environment | ORIGINAL["environment"]
    # --dump prints a file that loads to the same experiment
    assert evolve_main(["--dump", "M2-original"]) == 0
    text = capsys.readouterr().out
    assert text == preset_text("M2-original") and 'protocol = "original"' in text
    assert evolve_main(["--list"]) == 0
    listed = capsys.readouterr().out.splitlines()
    names = [line.split()[0] for line in listed if not line.startswith("#")]
    assert {f"{e}-original" for e in ("S1", "S2", "S3", "M1", "M2", "M3")} <= set(names) and "S1" in names
    headers = [line for line in listed if line.startswith("# protocol")]
    assert len(headers) == 2 and "original" in headers[1]


def test_dumped_protocol_preset_loads_like_the_preset(tmp_path, capsys):
    assert evolve_main(["--dump", "S2-original"]) == 0
    mine = tmp_path / "mine.toml"
    mine.write_text(capsys.readouterr().out)
    dumped = load_experiment(mine)
    path, overrides = resolve_preset("S2-original")
    preset = load_experiment(path, overrides)
    assert {k: v for k, v in dumped.to_dict().items() if k != "source"} == \
        {k: v for k, v in preset.to_dict().items() if k != "source"}


# ---------------------------------------------------------------------------- versions
EVIDENCE = Path(__file__).resolve().parents[1] / "docs" / "evidence"


def settings(exp) -> dict:
    """What an experiment runs, without its name, source file and protocol label (a preset
    names the protocol, its record sets every key of it on its own)."""
    return {k: v for k, v in exp.to_dict().items() if k not in ("name", "source", "protocol", "protocol_version")}


def record_settings(folder: str) -> dict:
    """``settings`` of a committed evidence run's experiment file."""
    return settings(load_experiment(EVIDENCE / folder / "experiment.toml"))


def test_the_versions_of_the_original_bundle():
    v1, v2, v3 = (protocol_values("original", v)["environment"] for v in (1, 2, 3))
    assert v1 == {"zone_depth": 4.0, "pickup_box": "centre", "pickup_box_width": 0.2, "pickup_box_depth": 0.1,
                  "ir_response": "gamma"}
    assert v2 == v1 | {"ground_friction": "mass", "robot_restitution": 1.0, "block_restitution": 0.4,
                       "wall_restitution": 1.0, "robot_drive_force": 3.63, "robot_max_speed": 0.637,
                       "drive_dead_band": 0.28}
    assert v3 == {k: v for k, v in v2.items() if k not in ("robot_drive_force", "robot_max_speed", "drive_dead_band")} \
        | {"drive_model": "force", "damping": 0.1, "schedule": "shuffled"}
    v4 = protocol_values("original", 4)
    assert v4["environment"] == v3 and v4["substrate"] == protocol_values("original", 3)["substrate"]
    assert v4["experiment"] == protocol_values("original", 3)["experiment"] | {"truncation": "encog", "weights": "encog"}
    v5 = protocol_values("original", 5)
    assert v5["environment"] == v3 and v5["experiment"] == v4["experiment"]
    assert v5["substrate"] == v4["substrate"] | {"bearings": "atan"}
    v6 = protocol_values("original", 6)
    assert v6["experiment"] == v5["experiment"] and v6["substrate"] == v5["substrate"]
    assert v6["environment"] == v3 | {"colour_response": "farther"}
    v7 = protocol_values("original", 7)
    assert v7["experiment"] == v6["experiment"] and v7["substrate"] == v6["substrate"]
    assert v7["environment"] == v6["environment"] | {"block_sighting": "rays"}
    v8 = protocol_values("original", 8)
    assert v8["experiment"] == v7["experiment"] and v8["substrate"] == v7["substrate"]
    assert v8["environment"] == v7["environment"] | {"ir_response": "khepera", "bottom_response": "khepera"}
    assert v7["environment"]["ir_response"] == "gamma"
    v9 = protocol_values("original", 9)
    assert v9["experiment"] == v8["experiment"] and v9["substrate"] == v8["substrate"]
    assert v9["environment"] == v8["environment"] | {"wall_distance": "original"}
    v10 = protocol_values("original", 10)
    assert v10["environment"] == v9["environment"] and v10["substrate"] == v9["substrate"]
    assert v10["experiment"] == v9["experiment"] | {"species_bookkeeping": "encog"}
    v11 = protocol_values("original", 11)
    assert v11["experiment"] == v10["experiment"] and v11["substrate"] == v10["substrate"]
    assert v11["environment"] == v10["environment"] | {"attached_steering": "original", "weld_spin": "free"}
    assert protocol_values("original") == v11 and ORIGINAL["environment"] == v11["environment"]
    # "paper" names the defaults of every key any version sets
    paper = protocol_values("paper")["environment"]
    assert (paper["drive_model"], paper["damping"], paper["schedule"], paper["drive_dead_band"],
            paper["robot_max_speed"], paper["ground_friction"]) == ("velocity", 0.0, "fixed", 0.0, 0.5, "threshold")
    assert (protocol_values("paper")["experiment"]["truncation"], protocol_values("paper")["experiment"]["weights"]) \
        == ("neat", "neat")
    assert protocol_values("paper")["substrate"]["bearings"] == "atan2"
    assert protocol_values("paper")["environment"]["colour_response"] == "nearer"
    assert protocol_values("paper")["environment"]["block_sighting"] == "cone"
    assert protocol_values("paper")["environment"]["bottom_response"] == "linear"
    assert protocol_values("paper")["environment"]["wall_distance"] == "nearest"
    assert (protocol_values("paper")["environment"]["attached_steering"],
            protocol_values("paper")["environment"]["weld_spin"]) == ("sharp", "held")


@pytest.mark.parametrize("version", [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11])
def test_a_run_saved_before_versions_keeps_the_bundle_it_was_run_under(tmp_path, version):
    exp = load_experiment(experiment(tmp_path, body=f'protocol = "original"\nprotocol_version = {version}'))
    saved = exp.to_dict()
    assert saved["protocol_version"] == version
    del saved["protocol_version"]                   # experiment.json as it was written before versions
    again = experiment_from_run(saved, "experiment.json")
    assert again.protocol_version == version and again.environment == exp.environment
    assert again.truncation == exp.truncation == again.weights == ("encog" if version >= 4 else "neat")
    assert again.world_config() == exp.world_config()
    assert again.substrate.get("bearings", "atan2") == exp.substrate.get("bearings", "atan2") == \
        ("atan" if version >= 5 else "atan2")
    assert again.world_config().colour_response == ("farther" if version >= 6 else "nearer")
    assert again.world_config().block_sighting == ("rays" if version >= 7 else "cone")
    assert (again.world_config().ir_response, again.world_config().bottom_response) == \
        (("khepera", "khepera") if version >= 8 else ("gamma", "linear"))
    assert again.world_config().wall_distance == ("original" if version >= 9 else "nearest")
    assert again.species_bookkeeping == exp.species_bookkeeping == ("encog" if version >= 10 else "membership")
    assert (again.world_config().attached_steering, again.world_config().weld_spin) == \
        (("original", "free") if version >= 11 else ("sharp", "held"))


@pytest.mark.parametrize("folder, version", [("original-S1-2018", 1), ("original-S1-elite02", 1),
                                             ("original-S1", 2), ("original-S1-continued", 2), ("original-M1", 2)])
def test_the_committed_records_rebuild_in_the_world_they_were_run_in(folder, version):
    saved = json.loads((EVIDENCE / folder / "experiment.json").read_text())
    assert "protocol_version" not in saved and saved["protocol"] == "original"
    exp = experiment_from_run(saved, folder)
    assert exp.protocol_version == version and exp.environment == saved["environment"]
    assert (exp.world_config().drive_model, exp.world_config().schedule) == ("velocity", "fixed")


def test_the_five_schedule_record_is_the_s1_original_preset():
    """... as the preset was at version 3, under which it ran (version 4 adds Encog's truncation)."""
    record = load_experiment(EVIDENCE / "original-S1-five" / "experiment.toml")
    path, overrides = resolve_preset("S1-original")
    preset = load_experiment(path, {**(overrides or {}), "protocol_version": 3})
    assert (record.protocol, preset.protocol_version, record.truncation, record.weights) == (None, 3, "neat", "neat")
    assert (load_experiment(path, overrides).truncation, load_experiment(path, overrides).weights) == ("encog", "encog")
    mine, theirs = settings(record), settings(preset)
    assert mine == theirs


@pytest.mark.parametrize("body, needle", [
    ('protocol = "original"\nprotocol_version = 12', "[experiment] protocol_version=12; allowed for protocol = "
                                                     "'original': [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11]"),
    ('protocol = "original"\nprotocol_version = true', "protocol_version=True; allowed for protocol = 'original'"),
    ('protocol = "paper"\nprotocol_version = 2', "[experiment] protocol_version=2; allowed for protocol = 'paper': [1]"),
    ("protocol_version = 2", "[experiment] protocol_version=2 without a protocol; allowed: with protocol"),
    ('protocol = "original"\nprotocol_version = 2\n[environment]\nzone_depth = 8',
     "[environment] zone_depth = 8 contradicts protocol = 'original' (version 2); allowed: 4.0"),
])
def test_a_bad_protocol_version_names_the_file_and_key(tmp_path, capsys, body, needle):
    path = tmp_path / "bad.toml"
    path.write_text(f"[experiment]\n{body}\n")
    assert evolve_main([str(path), "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(path) in err and needle in err, err
    assert not (tmp_path / "run").exists()


# ---------------------------------------------------------------------------- one layout per run
def test_one_layout_for_every_trial_and_generation():
    once = [trial_seed(7, 0, 0)]
    for generation in (0, 1, 9, 200):
        assert episode_seeds(7, generation, 5, "per_run") == once   # run once: the trials would be equal
    per_trial = {s for g in range(3) for s in episode_seeds(7, g, 5)}
    assert len(per_trial) == 15
    # the same seed gives the same layout (every robot and block pose)
    layouts = []
    for _ in range(2):
        sim = GatheringSimulation(WorldConfig.from_kwargs(environment=1))
        sim.reset(seed=once[0])
        layouts.append(np.concatenate([sim.world.robot_pos.ravel(), sim.world.robot_angle,
                                       sim.world.block_pos.ravel(), sim.world.block_angle]))
    np.testing.assert_array_equal(*layouts)


@pytest.mark.parametrize("version, runs", [
    (2, [trial_seed(5, 0, 0)]),                             # fixed order: the 3 trials are one episode, run once
    (3, [trial_seed(5, 0, t) for t in range(3)]),           # shuffled: 3 schedules of the one layout
])
def test_a_genome_meets_the_same_episodes_in_every_generation(tmp_path, monkeypatch, version, runs):
    """Every evaluation of a per_run experiment runs the same episodes, those of generation 0:
    once under version 2's fixed order, once per trial under version 3's shuffled schedule."""
    seen = []
    real = backends.evaluate

    def spy(*args, **kwargs):
        ev = real(*args, **kwargs)
        seen.append((kwargs["generation"], episode_seeds(kwargs["seed"], kwargs["generation"], kwargs["trials"],
                                                         kwargs["layout"], args[2]), len(ev.trial_ft), ev.steps))
        return ev

    monkeypatch.setattr(backends, "evaluate", spy)
    body = f'protocol = "original"\nprotocol_version = {version}'
    evolve(experiment(tmp_path, generations=2, population=6, body=body), tmp_path / "run")
    assert {g for g, *_ in seen} == {0, 1}
    assert all(seeds == runs and n == len(runs) and 0 < steps <= 80 * len(runs) for _, seeds, n, steps in seen)


# ---------------------------------------------------------------------------- the ratchet
def _fake_scores(monkeypatch, calls):
    """Evaluations that depend on the genome only: ft from its key (no simulation)."""

    def fake(genome, config, env_config, trials=5, seed=0, generation=0, method="hyperneat-m", substrate=None,
             layout="per_trial", complexity="paper"):
        calls.append((generation, genome.key))
        task = float((genome.key * 37) % 101)
        return Evaluation(task=task, morphology=50.0, controller=90.0, trial_ft=[task],
                          sensors={"num_sensors": 0.0, **{f"count_{t}": 0.0 for t in
                                                          ("infrared", "ultrasonic", "colour", "camera", "bottom")},
                                   **{f"{p}_{t}": float("nan") for p in ("range", "fov")
                                      for t in ("infrared", "ultrasonic", "colour", "camera")}},
                          steps=1)

    monkeypatch.setattr(backends, "evaluate", fake)


def test_the_best_genome_is_carried_over_without_being_scored_again(tmp_path, monkeypatch):
    calls: list[tuple[int, int]] = []
    _fake_scores(monkeypatch, calls)
    # the fake scores follow the genome id, not its team: every genome must be asked for
    monkeypatch.setattr("evolution.run.trainer.ReusingEvaluator", lambda inner, context: inner)
    exp = experiment(tmp_path, generations=5, population=10, body='elitism = "ratchet"\nconvergence_stop = false')
    evolve(exp, tmp_path / "run")
    records = read_stats(tmp_path / "run" / "stats.jsonl")
    by_gen: dict[int, list[int]] = {}
    for g, key in calls:
        by_gen.setdefault(g, []).append(key)
    scored = set()
    best_ever = (-1.0, None)
    for g in range(5):
        keys = by_gen[g]
        assert not scored & set(keys)                        # nothing is ever scored twice
        scored |= set(keys)
        if g > 0:
            assert len(keys) == 9                            # 10 genomes: the carried best + 9 offspring
            assert records[g]["genomes"] == 10
        for key in keys:
            task = float((key * 37) % 101)
            if task > best_ever[0]:
                best_ever = (task, key)
        # the record's best is the best-ever score (the carried genome's stored one)
        assert records[g]["task_best"] == best_ever[0]
        assert records[g]["best_genome"] == best_ever[1]
    assert records[-1]["steps"] == 9                          # the carried genome adds no steps


def test_without_the_ratchet_the_elites_are_scored_again(tmp_path, monkeypatch):
    calls: list[tuple[int, int]] = []
    _fake_scores(monkeypatch, calls)
    evolve(experiment(tmp_path, generations=3, population=10, body="convergence_stop = false"), tmp_path / "run")
    keys = [k for _, k in calls]
    assert len(keys) > len(set(keys))                         # species elites meet a new evaluation


def test_the_stop_compares_the_best_ever_score_with_110(tmp_path, monkeypatch):
    calls: list[tuple[int, int]] = []
    _fake_scores(monkeypatch, calls)
    exp = load_experiment(experiment(tmp_path))
    assert convergence_target(exp) == 110.0 == 100 + exp.world_config().time_bonus / 2

    def scores(genome, config, env_config, **kwargs):  # genome 13 is the first to reach 110
        calls.append((kwargs["generation"], genome.key))
        task = 110.0 if genome.key == 13 else 50.0 + genome.key / 100
        return Evaluation(task=task, morphology=50.0, controller=90.0, trial_ft=[task],
                          sensors=Evaluation.failure("").sensors, steps=1)

    monkeypatch.setattr(backends, "evaluate", scores)
    evolve(experiment(tmp_path, generations=20), tmp_path / "run")
    records = read_stats(tmp_path / "run" / "stats.jsonl")
    stop = next(g for g, key in calls if key == 13)
    assert len(records) == stop + 1 and records[-1]["task_best"] == 110.0
    assert all(r["task_best"] < 110 for r in records[:-1])


def test_a_run_under_the_original_protocol_resumes_to_the_same_statistics(tmp_path):
    exp = experiment(tmp_path, generations=4, population=8, body='protocol = "original"\nconvergence_stop = false')
    evolve(exp, tmp_path / "whole")
    evolve(exp, tmp_path / "part", "--generations", "2")
    evolve(exp, tmp_path / "part", "--resume")
    # steps aside: the resumed run simulates again the teams the whole run reused from the
    # generations before the resume (one layout: evolution.run.reuse keeps them in memory only)
    whole = without_work(read_stats(tmp_path / "whole" / "stats.jsonl"))
    part = without_work(read_stats(tmp_path / "part" / "stats.jsonl"))
    assert len(whole) == 4 and part == whole
    saved = json.loads((tmp_path / "part" / "experiment.json").read_text())
    assert saved["protocol"] == "original" and saved["environment"]["zone_depth"] == 4.0
    assert saved["protocol_version"] == 11 and saved["truncation"] == saved["weights"] == "encog"
    assert saved["species_bookkeeping"] == "encog"
    assert saved["environment"]["schedule"] == "shuffled" and saved["substrate"]["bearings"] == "atan"
    assert saved["environment"]["colour_response"] == "farther" and saved["environment"]["block_sighting"] == "rays"
    assert saved["environment"]["ir_response"] == saved["environment"]["bottom_response"] == "khepera"
    assert saved["environment"]["wall_distance"] == "original"
    assert (saved["environment"]["attached_steering"], saved["environment"]["weld_spin"]) == ("original", "free")
    shutil.rmtree(tmp_path / "part")


# ---------------------------------------------------------------------------- zone 20 x 4
def test_zone_of_the_original_is_20_by_4():
    exp = load_experiment(*resolve_preset("S1-original"))
    cfg = exp.world_config()
    assert cfg.zone_rect == (10.0, 0.0, 30.0, 4.0)            # x in [10, 30], y in [0, 4] (hand value)
    gathered = {}
    for depth, y in ((4.0, 3.7), (4.0, 3.85), (8.0, 3.85)):   # a small block: half side 0.2
        world = WorldConfig.from_kwargs(environment=None, block_counts=(1, 0, 0), num_robots=1, zone_depth=depth)
        sim = GatheringSimulation(world)
        sim.reset(seed=0)
        sim.world.place_block(0, 20.0, y, 0.0)
        sim.world.place_robot(0, 5.0, 30.0, 0.0)
        sim.step(np.zeros((1, 2)))
        gathered[(depth, y)] = bool(sim.gathered[0])
    assert gathered == {(4.0, 3.7): True, (4.0, 3.85): False, (8.0, 3.85): True}


# ---------------------------------------------------------------------------- the pickup box
BLOCK = (20.0, 20.0)
ORIGINAL_BOX = dict(pickup_box="centre", pickup_box_width=0.2, pickup_box_depth=0.1)


def _scene(gap, **box):
    """One small block; one robot north of it facing it, ``gap`` from its rim to the block's face
    (negative: the block overlaps the robot's body)."""
    cfg = WorldConfig.from_kwargs(environment=None, block_counts=(1, 0, 0), num_robots=1, **box)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=0)
    sim.world.place_block(0, *BLOCK, 0.0)
    half, r = sim.world.block_half[0], cfg.robot_radius
    sim.world.place_robot(0, BLOCK[0], BLOCK[1] + half + r + gap, -math.pi / 2)
    return sim


def _compiled_box(sim):
    params, _ = kernels.world_params(sim.config)
    w = sim.world
    return settle._in_pickup_box(w.robot_pos[0, 0], w.robot_pos[0, 1], w.robot_angle[0], w.block_pos[0, 0],
                                  w.block_pos[0, 1], w.block_angle[0], w.block_half[0], params)


@pytest.mark.parametrize("gap,front,centre", [
    (0.01, True, False),     # touching the front rim, not the body: grips only with the paper's box
    (0.15, True, False),     # inside the paper's 0.2-deep box ahead of the rim
    (-0.08, True, False),    # overlapping the body by 0.08: the face 0.07 ahead of the centre, box reaches 0.05
    (-0.11, True, True),     # overlapping by 0.11: the face 0.04 ahead of the centre, inside the centre box
])
def test_centre_pickup_box_needs_the_block_on_the_body(gap, front, centre):
    for box, want in ((dict(), front), (ORIGINAL_BOX, centre)):
        sim = _scene(gap, **box)
        assert (pickup_candidates(sim.world, np.zeros(1, bool)) == [(0, 0)]) is want, (gap, box)
        assert bool(_compiled_box(sim)) is want, (gap, box)


def test_a_block_at_the_rim_is_not_gripped_with_the_centre_box():
    for kernel in ("numpy", "compiled"):
        paper, original = _scene(0.01, kernel=kernel), _scene(0.01, kernel=kernel, **ORIGINAL_BOX)
        for sim in (paper, original):
            sim.step(np.zeros((1, 2)))
        assert paper.world.robot_attached[0] == 0 and original.world.robot_attached[0] == -1
    assert WorldConfig(**ORIGINAL_BOX).pickup_box_offset == 0.0
    assert WorldConfig().pickup_box_offset == pytest.approx(0.15 + 0.1)
    with pytest.raises(ValueError, match="pickup_box='middle'; allowed: 'front', 'centre'"):
        WorldConfig(pickup_box="middle")


# ---------------------------------------------------------------------------- decoding window, eq. 2
def test_decoded_range_fov_and_orientation_reach_the_middle_20_percent():
    """Hand values of the original (NormalizedField over [-5, 5] fed with [-1, 1])."""
    sub = Substrate(decode_window=0.2, sensor_types=("infrared", "ultrasonic", "camera", "colour"))
    out = np.zeros(6)
    reach = {}
    for v in (-1.0, 1.0):
        out[1] = out[2] = out[3] = v                           # fov, orientation, range
        for kind, t in (("infrared", -0.9), ("ultrasonic", -0.2), ("camera", 0.2), ("colour", 0.9)):
            out[4] = t
            s = sub.sensor_from_outputs(out, 0.0)
            assert s.type == kind                               # the original's type order
            reach.setdefault(kind, []).append((s.range, s.fov, s.orientation))
    (r0, f0, o0), (r1, f1, o1) = reach["infrared"]
    assert (r0, r1) == pytest.approx((4.006, 6.004)) and (f0, f1) == pytest.approx((1.3614, 1.7802), abs=1e-4)
    assert (o0, o1) == pytest.approx((-math.pi / 10, math.pi / 10))
    (r0, f0, _), (r1, f1, _) = reach["camera"]
    assert (r0, r1) == pytest.approx((8.012, 12.008), abs=1e-3) and (f0, f1) == pytest.approx((1.3265, 1.8151),
                                                                                              abs=1e-4)
    (r0, f0, _), (r1, f1, _) = reach["ultrasonic"]
    assert (r0, r1) == pytest.approx((10.015, 15.01), abs=1e-3) and (f0, f1) == pytest.approx((1.3166, 1.9250),
                                                                                              abs=1e-4)
    # the default reaches the whole interval, as before
    full = Substrate().sensor_from_outputs(np.array([0, 1.0, 1.0, 1.0, -0.9, 0]), 0.0)
    assert (full.range, full.fov, full.orientation) == (10.0, 5 * math.pi / 6, math.pi / 2)
    with pytest.raises(ValueError, match=r"decode_window=0; allowed: \(0, 1\]"):
        Substrate(decode_window=0)


def test_original_eq_2_counts_range_twice_no_fov_and_infrared_flat():
    morph = Morphology([
        SensorSpec("bottom"),
        SensorSpec("infrared", 0.5, 0.0, 5.0, 2.0),             # original: flat 10
        SensorSpec("ultrasonic", 1.0, 0.0, 12.5, 3.0),          # range 0.5 of 25 -> 10 * 0.5 = 5
        SensorSpec("camera", -1.0, 0.0, 4.0, 1.0),              # 4/20 = 0.2 -> 2
        SensorSpec("colour", 2.0, 0.0, 10.0, math.pi / 6),      # 1.0 -> 10, whatever the FOV
    ])
    assert morphological_complexity(morph, "original") == pytest.approx(100 - 10 - 10 - 5 - 2 - 10)
    # the paper's: bottom 10, then 5 * (FOV fraction + range fraction) for every configurable sensor
    fov = lambda f, lo, hi: (f - lo) / (hi - lo)  # noqa: E731
    paper = 100 - 10 - 5 * (fov(2.0, math.pi / 6, 5 * math.pi / 6) + 0.5) - 5 * (fov(3.0, 0.1, math.pi) + 0.5) \
        - 5 * (fov(1.0, math.pi / 9, 8 * math.pi / 9) + 0.2) - 5 * (0.0 + 1.0)
    assert morphological_complexity(morph) == pytest.approx(paper)
    # its C falls only by dropping or retyping sensors: FOV changes nothing
    wider = Morphology([SensorSpec("ultrasonic", 1.0, 0.0, 12.5, 0.2)])
    assert morphological_complexity(wider, "original") == morphological_complexity(
        Morphology([SensorSpec("ultrasonic", 1.0, 0.0, 12.5, 3.0)]), "original") == 95.0
    with pytest.raises(ValueError, match="formula='2018'; allowed: 'paper', 'original'"):
        morphological_complexity(morph, "2018")


def test_a_run_records_the_original_complexity(tmp_path):
    evolve(experiment(tmp_path, generations=1, population=6), tmp_path / "run")
    champion = json.loads((tmp_path / "run" / "champion.json").read_text())
    morph = Morphology.from_dict({"sensors": champion["morphology"]} if isinstance(champion["morphology"], list)
                                 else champion["morphology"])
    assert champion["objectives"]["morphology"] == pytest.approx(morphological_complexity(morph, "original"))


def test_spawn_counts_reach_the_offspring_places_exactly():
    """With the ratchet N - 1 places are left; neat-python's adjustment alone gives up on this one."""
    import neat

    from evolution.reproduction.breeding import NEATReproduction

    with pytest.raises(RuntimeError, match="could not match"):
        neat.DefaultReproduction._adjust_spawn_exact(None, [3, 2, 1, 1, 1, 1, 1], 7, 1)
    repro = NEATReproduction.__new__(NEATReproduction)
    assert repro._exact_spawn([3, 2, 1, 1, 1, 1, 1], 7, 1) == [1] * 7
    assert repro._exact_spawn([1, 1, 1], 6, 1) == [2, 2, 2]


def _population_of_one_species(size, body):
    import neat

    from evolution.run.neat_setup import make_neat_config

    exp = load_experiment(None, {"population": size, **body})
    config = make_neat_config(exp)
    population = neat.Population(config, seed=3)
    scores = {key: float((key * 37) % 101) for key in population.population}   # distinct
    for key, g in population.population.items():
        g.fitness = scores[key]
    return config, population, scores


def test_encogs_selection_of_2018_keeps_only_the_ratchets_best():
    """Encog's SO selection (speciation = "original") with the 2018 code's elite rate 0: generation
    0 is one species of 20; the ratchet carries the best genome, unscored, and no other genome of
    generation 0 survives: 19 offspring fill the population; the leader is the species' best."""
    config, population, scores = _population_of_one_species(20, {"speciation": "original", "elitism": "ratchet"})
    assert len(population.species.species) == 1
    assert config.reproduction_config.original_elite_rate == 0.0
    repro = population.reproduction
    new = repro.reproduce(config, population.species, 20, 0)
    ranked = sorted(scores, key=lambda k: (scores[k], k), reverse=True)
    assert len(new) == 20
    assert repro.carried == {ranked[0]}
    assert set(new) & set(scores) == {ranked[0]}        # only the best-ever survives
    (species,) = population.species.species.values()
    assert species.representative.key == ranked[0]      # the leader of the next speciation
    assert config.stagnation_config.max_stagnation == 16


def _with_elite_rate(config, rate):
    config.reproduction_config.original_elite_rate = rate
    return config


def test_encogs_selection_with_an_elite_rate_keeps_the_best_of_a_species_unscored():
    """original_elite_rate = 0.2 (the code from 2018-12-03 on): the species' best 20 % (4 of 20,
    the best among them) survive too, none of them re-scored, and 16 offspring fill the population."""
    config, population, scores = _population_of_one_species(20, {"speciation": "original", "elitism": "ratchet"})
    repro = population.reproduction
    new = repro.reproduce(_with_elite_rate(config, 0.2), population.species, 20, 0)
    ranked = sorted(scores, key=lambda k: (scores[k], k), reverse=True)
    assert len(new) == 20
    assert repro.carried == set(ranked[:4])             # the best + the next three of the top 4
    assert set(new) & set(scores) == set(ranked[:4])    # no other genome of generation 0 survives


def test_encogs_selection_without_the_ratchet_keeps_elites_that_are_scored_again():
    config, population, scores = _population_of_one_species(20, {"speciation": "original"})
    repro = population.reproduction
    new = repro.reproduce(_with_elite_rate(config, 0.2), population.species, 20, 0)
    ranked = sorted(scores, key=lambda k: (scores[k], k), reverse=True)
    assert len(new) == 20 and not repro.carried
    assert set(new) & set(scores) == set(ranked[:4])    # 20 % of 20 survive as they are


def test_an_elite_rate_outside_0_1_is_refused(tmp_path, capsys):
    cfg = tmp_path / "bad.neat.cfg"
    shipped = (Path(__file__).parents[1] / "configs" / "hyperneat_m.neat.cfg").read_text()
    cfg.write_text(shipped.replace("[NEATReproduction]\n", "[NEATReproduction]\noriginal_elite_rate = 1.5\n"))
    exp = experiment(tmp_path, body=f'protocol = "original"\nneat_config = "{cfg}"')
    assert evolve_main([str(exp), "--out", str(tmp_path / "r"), "--workers", "1", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.neat.cfg" in err[0] and "original_elite_rate = 1.5" in err[0] and "[0, 1]" in err[0]


def test_the_paper_protocols_species_keep_neat_pythons_selection():
    config, population, _ = _population_of_one_species(20, {})
    assert not config.species_set_config.leaders
    assert config.stagnation_config.max_stagnation == 20


def _recording_compare(seen: list):
    """A stand-in for ``evolution.compare.compare`` that records the world it is asked for."""

    def fake_compare(policies, env_config, seeds):
        seen.append(env_config)
        return [{"policy": p.name, "sensors": 1, "episodes": len(seeds), "ft_mean": 0.0, "ft_std": 0.0,
                 "ft_se": None, "small": 0.0, "medium": 0.0, "large": 0.0, "finished": 0,
                 "steps_to_finish": None} for p in policies]

    return fake_compare


def test_compare_runs_in_the_protocols_world(tmp_path, monkeypatch, capsys):
    """gathering-compare --protocol original compares in the original world (zone 4 deep, centre
    box, the Khepera curve), the default in the paper's; a champion made in another world is named."""
    from evolution import compare as compare_module
    from evolution.policies.base import Policy

    seen = []

    monkeypatch.setattr(compare_module, "compare", _recording_compare(seen))
    for protocol, out in (("original", "o"), ("paper", "p")):
        assert compare_module.compare_main(["--policy", "wander", "--episodes", "1", "--protocol", protocol,
                                            "--out", str(tmp_path / out)]) == 0
    original, paper = seen
    assert (original["zone_depth"], original["pickup_box"], original["ir_response"]) == (4.0, "centre", "khepera")
    assert (paper["zone_depth"], paper["pickup_box"], paper["ir_response"]) == (8.0, "front", "linear")
    assert "original protocol" in (tmp_path / "o" / "compare.md").read_text()

    evolved_there = Policy("champion:x", Morphology.khepera_iii(), None, environment={"environment": 1, **ORIGINAL["environment"]})
    assert compare_module.world_notes([evolved_there], original) == []
    note, = compare_module.world_notes([evolved_there], paper)
    assert "zone_depth = 4.0 (here 8.0)" in note and "pickup_box = 'centre' (here 'front')" in note
    assert compare_module.world_notes([Policy("wander", Morphology.khepera_iii(), None)], paper) == []


def test_compare_runs_in_the_world_a_champion_was_evolved_in(tmp_path, monkeypatch, capsys):
    """gathering-compare --world-from CHAMPION takes the champion's world keys (here the force
    drive and the shuffled schedule) and, unless given, its preset, steps and team size; with
    --protocol as well it is refused in one line, exit 2, nothing written."""
    from evolution import compare as compare_module

    champion = json.loads((Path(__file__).resolve().parents[1] / "docs" / "evidence" / "original-S1-force"
                           / "champion.json").read_text())
    champion["environment"].update(schedule="shuffled", max_cycles=3000)
    path = tmp_path / "champion.json"
    path.write_text(json.dumps(champion))
    seen = []

    monkeypatch.setattr(compare_module, "compare", _recording_compare(seen))
    args = ["--policy", "wander", "--policy", f"champion:{path}", "--episodes", "1", "--world-from", str(path)]
    assert compare_module.compare_main(args + ["--out", str(tmp_path / "a")]) == 0
    assert compare_module.compare_main(args + ["--robots", "5", "--out", str(tmp_path / "b")]) == 0
    own, fewer = seen
    assert own == champion["environment"]
    assert (own["drive_model"], own["schedule"], own["environment"], own["max_cycles"]) == ("force", "shuffled", 1, 3000)
    assert fewer == {**champion["environment"], "num_robots": 5}
    out = capsys.readouterr().out
    assert "was made in another world" not in out and f"the world of {path}" in out
    assert compare_module.compare_main(args + ["--own-layout", "--out", str(tmp_path / "g")]) == 2
    assert "has no layout_seed" in capsys.readouterr().err and not (tmp_path / "g").exists()
    # a one-layout champion: compared on fresh layouts, or with --own-layout on its own
    champion["environment"]["layout_seed"] = 99
    path.write_text(json.dumps(champion))
    assert compare_module.compare_main(args + ["--out", str(tmp_path / "d")]) == 0
    assert compare_module.compare_main(args + ["--own-layout", "--out", str(tmp_path / "e")]) == 0
    fresh, own_layout = seen[2:]
    assert "layout_seed" not in fresh and own_layout["layout_seed"] == 99
    assert "on its own layout" in (tmp_path / "e" / "compare.md").read_text()
    assert compare_module.compare_main(["--own-layout", "--policy", "wander", "--out", str(tmp_path / "f")]) == 2
    assert "allowed: with --world-from" in capsys.readouterr().err
    assert compare_module.compare_main(args + ["--protocol", "original", "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--world-from and --protocol" in err[0] and not (tmp_path / "c").exists()


def test_compare_sets_one_world_key_and_names_a_champion_made_without_it(tmp_path, monkeypatch, capsys):
    """gathering-compare --world KEY=VALUE changes one world parameter over the chosen world (VALUE
    read as TOML, else as a bare string) and says so in the title; a champion whose record lacks the
    key (so was made with its default) is named in a note; an unknown key, a bad value or a key that
    has its own option is refused in one line, exit 2, nothing written."""
    from evolution import compare as compare_module
    from evolution.policies.base import Policy

    assert compare_module.world_setting("weld_spin=free") == ("weld_spin", "free")
    assert compare_module.world_setting("zone_depth = 4") == ("zone_depth", 4)
    assert compare_module.world_setting("block_counts=[3, 2, 1]") == ("block_counts", [3, 2, 1])
    assert compare_module.world_setting('schedule="shuffled"') == ("schedule", "shuffled")
    with pytest.raises(argparse.ArgumentTypeError, match="on one line"):  # a second TOML key smuggled in
        compare_module.world_setting("zone_depth=4\nweld_spin = 'free'")
    seen = []
    monkeypatch.setattr(compare_module, "compare", _recording_compare(seen))
    args = ["--policy", "wander", "--episodes", "1", "--protocol", "original"]
    assert compare_module.compare_main(args + ["--world", "weld_spin=held", "--world", "zone_depth=6",
                                               "--out", str(tmp_path / "a")]) == 0
    changed, = seen
    assert changed == {**ORIGINAL["environment"], "environment": 2, "max_cycles": 10_000, "num_robots": 20,
                       "weld_spin": "held", "zone_depth": 6}
    assert "with weld_spin = 'held', zone_depth = 6" in (tmp_path / "a" / "compare.md").read_text()
    # a version-10 record has no weld_spin: it was made with "held", and the compared world says "free"
    v10 = {k: v for k, v in ORIGINAL["environment"].items() if k not in ("weld_spin", "attached_steering")}
    note, = compare_module.world_notes([Policy("champion:v10", Morphology.khepera_iii(), None, environment=v10)],
                                       {**ORIGINAL["environment"], "weld_spin": "free"})
    assert "weld_spin = 'held' (here 'free')" in note and "attached_steering = 'sharp' (here 'original')" in note
    capsys.readouterr()
    for bad, says in ((["--world", "no_such_key=1"], "--world no_such_key=1: unknown world parameter"),
                      (["--world", "weld_spin=spinning"], "--world weld_spin='spinning': weld_spin='spinning'; allowed"),
                      (["--world", "max_cycles=5"], "--world max_cycles: the command's option --steps sets it"),
                      (["--world", "weld_spin"], "'weld_spin' is not KEY=VALUE")):
        out = tmp_path / "bad"
        try:
            status = compare_module.compare_main(args + bad + ["--out", str(out)])
        except SystemExit as e:   # argparse's own refusal
            status = e.code
        assert status == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and says in err[0] and not out.exists(), err


def test_a_second_compare_into_the_same_folder_is_refused(tmp_path, capsys):
    """One writer per gathering-compare --out: while another holds it, one line, exit 2, no file."""
    from evolution.compare import compare_main
    from evolution.run.lock import RunLock

    out = tmp_path / "cmp"
    with RunLock(out, what="output folder", by="another gathering-compare"):
        assert compare_main(["--policy", "random", "--steps", "5", "--episodes", "1", "--out", str(out)]) == 2
        assert sorted(p.name for p in out.iterdir()) == [".lock"]
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "in use by process" in err[0] and str(out) in err[0]
    assert compare_main(["--policy", "random", "--steps", "5", "--episodes", "1", "--out", str(out)]) == 0


@pytest.mark.parametrize("case", ["incumbent ties", "two members beat it"])
def test_encogs_leader_keeps_its_place_on_a_tie(case):
    """Encog's leader (``addSpeciesMember``): a member replaces the leader only when it scores
    strictly higher. On a tie the incumbent stays the leader (so with elite rate 0 the species of
    the ratchet's best survives: its leader is carried); of two members that beat it with the same
    score, the one with the lower key (the first to join) leads."""
    config, population, scores = _population_of_one_species(20, {"speciation": "original", "elitism": "ratchet"})
    (species,) = population.species.species.values()
    keys = sorted(species.members)
    incumbent = keys[10]                    # the leader the species was speciated against
    species.representative = species.members[incumbent]
    others = [k for k in keys if k != incumbent]
    for g in species.members.values():
        g.fitness = 1.0
    species.members[incumbent].fitness = 50.0
    if case == "incumbent ties":
        for k in (keys[0], keys[-1]):      # an older and a younger genome, same score
            species.members[k].fitness = 50.0
        expected = incumbent
    else:
        species.members[others[3]].fitness = species.members[others[7]].fitness = 60.0
        expected = others[3]
    population.reproduction.reproduce(config, population.species, 20, 0)
    (species,) = population.species.species.values()
    assert species.representative.key == expected


def test_the_ratchets_species_survives_a_tie_with_a_younger_genome():
    """The symptom the tie rule cured: with elite rate 0 only the ratchet's best is carried, so
    its species lives on only if that genome stays its leader. A younger genome scoring the same
    must not take the place: after the next speciation the species still exists, led by the
    carried genome (ranking by score alone let the young genome lead, the species was disbanded
    and the population lumped into a new one)."""
    config, population, scores = _population_of_one_species(20, {"speciation": "original", "elitism": "ratchet"})
    species_set = population.species
    (sid,) = species_set.species
    founder = species_set.species[sid].representative.key
    youngest = max(species_set.species[sid].members)
    for g in species_set.species[sid].members.values():
        g.fitness = 1.0
    species_set.species[sid].members[founder].fitness = species_set.species[sid].members[youngest].fitness = 40.0
    new = population.reproduction.reproduce(config, species_set, 20, 0)
    assert population.reproduction.carried == {founder} and youngest not in new
    species_set.speciate(config, new, 1)
    assert sid in species_set.species
    assert species_set.species[sid].representative.key == founder


def _two_stagnant_species(top_in_second: float):
    """Generation 30 of Encog's selection with the ratchet: species A (the older) holds the best
    genome (50, the first to score it), species B's best scores ``top_in_second``; neither
    improved since generation 0."""
    import neat

    config, population, _ = _population_of_one_species(20, {"speciation": "original", "elitism": "ratchet"})
    species_set = population.species
    (old,) = species_set.species.values()
    keys = sorted(old.members)
    members = {k: old.members[k] for k in keys}
    for g in members.values():
        g.fitness = 1.0
    members[keys[3]].fitness = 50.0
    members[keys[15]].fitness = top_in_second
    a, b = neat.species.Species(1, 0), neat.species.Species(2, 0)
    a.update(members[keys[3]], {k: members[k] for k in keys[:10]})
    b.update(members[keys[15]], {k: members[k] for k in keys[10:]})
    for s in (a, b):
        s.fitness_history, s.last_improved = [max(s.get_fitnesses())] * 30, 0
    species_set.species = {1: a, 2: b}
    return config, population, keys[3]


def test_encogs_stagnation_spares_the_best_genomes_species_only():
    """Encog removes a species after 15 generations without improvement, except the species of
    the best genome (``removeSpecies``): with the ratchet's best in the older species A and species
    B tying it, A lives on and B is removed. (neat-python's ``species_elitism = 1`` spares the
    fittest species, and of two that tie the one with the later id: B, and A died.)"""
    config, population, best = _two_stagnant_species(50.0)
    assert config.stagnation_config.species_elitism == 0
    new = population.reproduction.reproduce(config, population.species, 20, 30)
    assert population.reproduction.best.key == best
    assert set(population.species.species) == {1}
    assert len(new) == 20 and best in new


# ---------------------------------------------------------------------------- shuffled trials
def test_under_the_shuffled_schedule_a_one_layout_runs_trials_share_the_layout_not_the_schedule():
    from evolution.run.evaluate import training_environment, varied_episodes

    shuffled = {"environment": 1, "drive_model": "force", "schedule": "shuffled"}
    assert varied_episodes(shuffled) and not varied_episodes({"drive_model": "force"})
    for generation in (0, 3):
        assert episode_seeds(7, generation, 5, "per_run", shuffled) == [trial_seed(7, 0, t) for t in range(5)]
        assert episode_seeds(7, generation, 5, "per_run", {"environment": 1}) == [trial_seed(7, 0, 0)]
        assert episode_seeds(7, generation, 5, "per_trial", shuffled) == [trial_seed(7, generation, t) for t in range(5)]
    assert training_environment(shuffled, 7, "per_run") == {**shuffled, "layout_seed": trial_seed(7, 0, 0)}
    assert training_environment(shuffled, 7, "per_trial") == shuffled
    assert training_environment({"environment": 1}, 7, "per_run") == {"environment": 1}
    # the worlds: one layout (bodies where they start), episodes apart after a few steps
    from gathering_env.vector import VectorSimulation

    world = {**training_environment(shuffled, 7, "per_run"), "num_robots": 6, "max_cycles": 50}
    sims = VectorSimulation(3, **world)
    sims.reset(episode_seeds(7, 0, 3, "per_run", world))
    start = [w.raw.copy() for w in sims._engine.worlds]
    assert all(np.array_equal(start[0], s) for s in start[1:])
    for _ in range(30):
        sims.step(np.ones((3, 6, 2)))
    moved = [w.robot_pos.copy() for w in sims._engine.worlds]
    assert not np.array_equal(moved[0], moved[1]) and not np.array_equal(moved[1], moved[2])


def test_a_shuffled_one_layout_champion_replays_each_training_trial_exactly(tmp_path, capsys):
    """The champion of a per_run run under the shuffled schedule keeps the run's layout_seed and
    its trials' seeds: replayed with each, it scores that trial's ft, whose mean is its training
    ft; the trials differ (the record's trial_ft); a resumed run equals an unbroken one."""
    from small_runs import evolve, experiment_file

    from evolution.cli import replay_main
    from evolution.run.champion import load_champion

    exp = experiment_file(tmp_path, "shuffled", "hyperneat-m", '["task"]', generations=3,
                          extra='layout = "per_run"\nelitism = "ratchet"\nconvergence_stop = false')
    exp.write_text(exp.read_text().replace("max_cycles = 80", "max_cycles = 300")
                   + 'drive_model = "force"\ndamping = 0.1\nschedule = "shuffled"\n')
    evolve(exp, tmp_path / "run")
    champ = load_champion(tmp_path / "run" / "champion.json")
    seeds = (trial_seed(3, 0, 0), trial_seed(3, 0, 1))
    assert champ.trial_seeds == seeds and champ.environment["layout_seed"] == seeds[0]
    records = read_stats(tmp_path / "run" / "stats.jsonl")
    trial_fts = [fts for r in records for fts in r["trial_ft"].values()]
    assert all(len(fts) == 2 for fts in trial_fts) and any(a != b for a, b in trial_fts)
    replayed = []
    for seed in seeds:
        capsys.readouterr()
        assert replay_main([str(tmp_path / "run" / "champion.json"), "--seed", str(seed),
                            "--out", str(tmp_path / f"t{seed}.gif")]) == 0
        lines = capsys.readouterr().out.splitlines()
        replayed.append(float(lines[0].split("ft = ")[1].split()[0].rstrip(",")))
        trial = seeds.index(seed)
        assert lines[1].startswith(f"training episode {trial + 1} of its 2 (seed {seed}): ft equals the ft it "
                                   f"scored in training, {champ.trial_ft[trial]:.2f}")
    assert replayed == pytest.approx(list(champ.trial_ft), abs=0.005)     # each trial, as the champion recorded it
    assert np.mean(replayed) == pytest.approx(champ.objectives["task"], abs=0.01)
    evolve(exp, tmp_path / "part", "--generations", "2")
    evolve(exp, tmp_path / "part", "--resume")
    assert without_work(read_stats(tmp_path / "part" / "stats.jsonl")) == without_work(records)


def test_a_one_layout_run_says_how_its_trials_are_run():
    from dataclasses import replace

    from evolution.run.trainer import protocol_notes

    path, overrides = resolve_preset("S1-original")
    exp = load_experiment(path, overrides)                                   # the newest bundle: shuffled
    fixed = load_experiment(path, {**overrides, "protocol_version": 2})      # the velocity drive, fixed order
    lines = {name: next(n for n in protocol_notes(e) if "one layout" in n) for name, e in (
        ("fixed", fixed), ("shuffled", exp), ("one", replace(exp, trials=1)))}
    assert "would be the same episode" in lines["fixed"] and "runs it once" in lines["fixed"]
    assert "S1-original: protocol 'original', version 2 (evolution.run.protocol)" in protocol_notes(fixed)
    assert "its 5 trials share it and differ by their shuffled schedules" in lines["shuffled"]
    assert "one trial on it with one shuffled schedule" in lines["one"]


def test_the_encog_weights_note_gives_each_methods_own_deviations():
    """The run's start note reads the range and the small and large deviations of the method it runs
    (HyperNEAT-M 0.02 or 1, NEAT-M 0.004 or 0.2, by hand from the 2018 HyperNEATMUtil/NEATMUtil), in order."""
    from dataclasses import replace

    from evolution.run.trainer import protocol_notes

    path, overrides = resolve_preset("S1-original")
    exp = load_experiment(path, overrides)
    note = {m: next(n for n in protocol_notes(replace(exp, method=m)) if "weights = encog" in n)
            for m in ("hyperneat-m", "neat-m")}
    assert "uniform in +-5, perturbed by a deviation of 0.02 or 1, or reset" in note["hyperneat-m"]
    assert "uniform in +-5, perturbed by a deviation of 0.004 or 0.2, or reset" in note["neat-m"]
    assert not any("weights = encog" in n for n in protocol_notes(replace(exp, weights="neat")))


def test_the_bearings_note_and_the_bearings_run_are_version_5():
    """The newest bundle's HyperNEAT-M runs say at their start that their sensors sit on the front
    half; the committed bearings run is the S1-original preset at version 5 key for key, and
    version 4's own record differs from it by the bearings alone."""
    from dataclasses import replace

    from evolution.run.trainer import protocol_notes

    path, overrides = resolve_preset("S1-original")
    exp = load_experiment(path, {**(overrides or {}), "protocol_version": 5})
    assert any("bearings = atan" in n for n in protocol_notes(exp))
    assert not any("bearings = atan" in n for n in protocol_notes(load_experiment(path, {**(overrides or {}),
                                                                                       "protocol_version": 4})))
    assert not any("bearings = atan" in n for n in protocol_notes(replace(exp, method="neat-m")))
    record = load_experiment(EVIDENCE / "original-S1-v4-atan-bearings" / "experiment.toml")
    mine = settings(record)
    assert mine == settings(exp)
    v4 = experiment_from_run(json.loads((EVIDENCE / "original-S1-v4" / "experiment.json").read_text()), "v4")
    theirs = settings(v4)
    assert {k for k in mine if mine[k] != theirs[k]} == {"substrate"}
    assert mine["substrate"] == theirs["substrate"] | {"bearings": "atan"}


@pytest.mark.parametrize("version, folder, before, added, note", [
    (6, "original-S1-v6", "original-S1-v4-atan-bearings", {"colour_response": "farther"}, "colour_response = farther"),
    (7, "original-S1-v7", "original-S1-v6", {"block_sighting": "rays"}, "block_sighting = rays"),
    (8, "original-S1-v8", "original-S1-v7", {"ir_response": "khepera", "bottom_response": "khepera"},
     "ir_response = khepera, bottom_response = khepera"),
    (9, "original-S1-v9", "original-S1-v8", {"wall_distance": "original"}, "wall_distance = original"),
])
def test_each_sensing_version_says_so_and_its_run_is_the_preset(version, folder, before, added, note):
    """A run under version 6-9 says at its start what the version reads as the original did (with
    either method); the version before does not; the committed run of the version is the
    S1-original preset at that version key for key, and differs from the run of the version
    before by the version's world keys alone."""
    from dataclasses import replace

    from evolution.run.trainer import protocol_notes

    path, overrides = resolve_preset("S1-original")
    exp = load_experiment(path, {**(overrides or {}), "protocol_version": version})
    assert {k: exp.environment[k] for k in added} == added
    assert sum(note in n for n in protocol_notes(exp)) == 1
    assert any(note in n for n in protocol_notes(replace(exp, method="neat-m")))
    previous = load_experiment(path, {**(overrides or {}), "protocol_version": version - 1})
    assert not any(note in n for n in protocol_notes(previous))
    mine = record_settings(folder)
    assert mine == settings(exp)
    theirs = record_settings(before)
    assert {k for k in mine if mine[k] != theirs[k]} == {"environment"}
    assert mine["environment"] == theirs["environment"] | added


def test_the_newest_bundle_is_version_11():
    path, overrides = resolve_preset("S1-original")
    assert load_experiment(path, overrides).protocol_version == 11


def test_the_welded_robot_version_says_so_and_its_run_is_the_preset():
    """A run under version 11 says at its start that a welded robot steers and turns as the
    original's did (either method); one under version 10 does not; the committed version-11 run
    is the S1-original preset key for key and differs from the version-10 run by those two keys."""
    from dataclasses import replace

    from evolution.run.trainer import protocol_notes

    path, overrides = resolve_preset("S1-original")
    exp = load_experiment(path, overrides)
    added = {"attached_steering": "original", "weld_spin": "free"}
    assert {k: exp.environment[k] for k in added} == added
    for key in added:
        assert sum(f"{key} = {added[key]}" in n for n in protocol_notes(exp)) == 1
        assert any(f"{key} = {added[key]}" in n for n in protocol_notes(replace(exp, method="neat-m")))
    previous = load_experiment(path, {**(overrides or {}), "protocol_version": 10})
    assert (previous.world_config().attached_steering, previous.world_config().weld_spin) == ("sharp", "held")
    assert not any("attached_steering" in n or "weld_spin" in n for n in protocol_notes(previous))
    mine = record_settings("original-S1-v11")
    assert mine == settings(exp)
    theirs = record_settings("original-S1-v10")
    assert {k for k in mine if mine[k] != theirs[k]} == {"environment"}
    assert mine["environment"] == theirs["environment"] | added


def test_the_bookkeeping_version_says_so_and_its_run_is_the_preset():
    """A single-objective run under version 10 says at its start that it keeps Encog's species
    books, one under version 9 or an MO one does not; the committed version-10 run is the
    S1-original preset key for key and differs from the version-9 run by the books alone."""
    from dataclasses import replace

    from evolution.run.trainer import protocol_notes

    path, overrides = resolve_preset("S1-original")
    exp = load_experiment(path, {**(overrides or {}), "protocol_version": 10})
    assert exp.species_bookkeeping == "encog"
    assert sum("species_bookkeeping = encog" in n for n in protocol_notes(exp)) == 1
    assert not any("species_bookkeeping" in n for n in protocol_notes(replace(exp, objectives=("task", "morphology"))))
    previous = load_experiment(path, {**(overrides or {}), "protocol_version": 9})
    assert previous.species_bookkeeping == "membership"
    assert not any("species_bookkeeping" in n for n in protocol_notes(previous))
    mine = record_settings("original-S1-v10")
    assert mine == settings(exp)
    theirs = record_settings("original-S1-v9")
    assert {k for k in mine if mine[k] != theirs[k]} == {"species_bookkeeping"}


def test_a_one_layout_run_refuses_a_layout_seed_of_its_own(tmp_path):
    path = experiment(tmp_path, body='layout = "per_run"')
    path.write_text(path.read_text() + "layout_seed = 4\n")
    with pytest.raises(ExperimentError, match=r"layout_seed with \[experiment\] layout = 'per_run'"):
        load_experiment(path)
    path = experiment(tmp_path, name="fresh", body="")
    path.write_text(path.read_text() + "layout_seed = 4\n")
    assert load_experiment(path).world_config().layout_seed == 4


def test_the_front_box_experiment_differs_from_the_newest_bundle_by_the_box_alone():
    front = load_experiment(EVIDENCE / "original-S1-front" / "experiment.toml")
    preset = load_experiment(*resolve_preset("S1-original"))
    differ = {k for k in set(front.environment) | set(preset.environment)
              if front.environment.get(k) != preset.environment.get(k)}
    assert differ == {"pickup_box"} and front.environment["pickup_box"] == "front"
    assert (front.layout, front.elitism, front.complexity, front.speciation, front.truncation, front.weights,
            front.substrate) == (preset.layout, preset.elitism, preset.complexity, preset.speciation,
                                 preset.truncation, preset.weights, preset.substrate)


def test_a_paper_protocol_run_saved_before_the_bundle_grew_resumes_in_the_same_world(tmp_path):
    """protocol = "paper" names the defaults of every key of every version, so it gained
    drive_model, damping and schedule with version 3 of the original; a run saved before holds
    the keys it had, and its experiment must come back the same (resume compares it)."""
    exp = load_experiment(experiment(tmp_path, body='protocol = "paper"'))
    saved = exp.to_dict()
    for key in ("drive_model", "damping", "schedule"):
        del saved["environment"][key]
    del saved["protocol_version"]
    again = experiment_from_run(saved, "experiment.json")
    assert again.environment == saved["environment"] and again.world_config() == exp.world_config()
    assert again.to_dict()["environment"] == saved["environment"]

