"""Whole runs against hand values: fitness = mean ft on distinct seeds, the SO convergence
stop at the paper's threshold, non-dominated front files, NEAT-M / MO resume."""

from __future__ import annotations

import itertools
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import small_runs
from small_runs import evolve, experiment_file

from evolution.run import trainer as trainer_module
from evolution.run.evaluate import Evaluation, evaluate, sensor_statistics, trial_seed
from evolution.run.experiment import load_experiment
from evolution.run.stats import read_stats, without_timing
from gathering_env import Morphology, parallel_env


@pytest.fixture(scope="module")
def mo_run(tmp_path_factory):
    _, _, exp, run = small_runs.build(tmp_path_factory)
    return exp, run


def team_ft(controller, morphology, env_config, seed):
    """ft of one episode by a plain loop over the public environment API."""
    env = parallel_env(**env_config)
    obs, _ = env.reset(seed=seed, options={"morphology": morphology})
    obs = np.stack([obs[a] for a in env.possible_agents])
    while True:
        obs, _, terminated, truncated = env.step_batch(controller.act(obs))
        if terminated or truncated:
            return env.team_info()["task_performance"]


HAND_WORLD = dict(environment=1, arena_width=6.0, arena_height=6.0, zone_width=6.0, zone_depth=2.0,
                  block_counts=[12, 0, 0], max_cycles=150, num_robots=10)


def hand_cppn():
    """(config, genome): a hand-built CPPN, both wheels forward, the right one faster (x2 link)."""
    from test_substrate import BIAS, X2, cppn, cppn_config

    config = cppn_config()
    return config, cppn(config, {(X2, BIAS): 1.0}, biases={BIAS: 0.3})


def test_fitness_is_the_mean_ft_over_distinct_trial_seeds():
    """On a hand-built CPPN whose trial scores differ, the fitness is their mean, each trial
    on its own seed."""
    from evolution.encodings.substrate import Substrate, decode

    config, genome = hand_cppn()
    world = HAND_WORLD
    seeds = [trial_seed(3, 3, t) for t in range(5)]
    assert len(set(seeds)) == 5
    controller, morphology = decode(genome, config, Substrate())
    reference = [team_ft(controller, morphology, world, s) for s in seeds]
    assert len(set(reference)) >= 3                   # the trials' scores differ (else mean = max = any)
    ev = evaluate(genome, config, world, trials=5, seed=3, generation=3, method="hyperneat-m")
    assert ev.trial_ft == pytest.approx(reference)    # trial t ran on seed t, in order
    assert ev.task == pytest.approx(sum(reference) / 5)
    assert all(ev.task != pytest.approx(ft) for ft in reference)   # no single trial, nor the max, is the mean


def test_front_files_are_non_dominated(mo_run):
    _, run = mo_run
    points = [json.loads(f.read_text())["objectives"] for f in sorted((run / "front").glob("*.json"))]
    assert points
    for a, b in itertools.permutations(points, 2):            # brute force, both objectives maximised
        dominates = (a["task"] >= b["task"] and a["morphology"] >= b["morphology"]
                     and (a["task"] > b["task"] or a["morphology"] > b["morphology"]))
        assert not dominates, (a, b)


def front_files(run: Path) -> dict[str, dict]:
    return {f.name: json.loads(f.read_text()) for f in sorted((run / "front").glob("*.json"))}


def test_neat_m_mo_run_resumes_to_the_uninterrupted_result(mo_run, tmp_path):
    exp, run = mo_run
    copy = tmp_path / "copy"
    shutil.copytree(run, copy)
    shutil.rmtree(copy / "front")
    evolve(exp, copy, "--resume-from", str(copy / "checkpoints" / "gen-0001.ckpt"))
    assert without_timing(read_stats(copy / "stats.jsonl")) == without_timing(read_stats(run / "stats.jsonl"))
    assert front_files(copy) == front_files(run)
    assert json.loads((copy / "champion.json").read_text()) == json.loads((run / "champion.json").read_text())


def test_a_run_directory_moves_between_machines(mo_run, tmp_path):
    from evolution.cli import evolve_main

    exp, run = mo_run
    recorded = json.loads((run / "experiment.json").read_text())
    assert recorded["neat_config"] == "neat_m.neat.cfg"          # a preset's name, no folder
    assert len(recorded["neat_config_sha256"]) == 64
    for path in run.rglob("*"):                                   # no text file names a folder of this machine
        if path.suffix in {".json", ".jsonl", ".csv", ".cfg"}:
            assert str(run.parent) not in path.read_text(), path
    here, moved = tmp_path / "here", tmp_path / "elsewhere" / "deeper" / "run"
    shutil.copytree(run, here)
    shutil.copytree(run, moved)
    for target in (here, moved):  # the run's own experiment, one generation more
        assert evolve_main(["--resume", str(target), "--generations", "3", "--workers", "1", "--no-progress"]) == 0
    assert without_timing(read_stats(moved / "stats.jsonl")) == without_timing(read_stats(here / "stats.jsonl"))
    assert len(read_stats(moved / "stats.jsonl")) == 3


class ScriptedEvaluator:
    """Gives genome 0 of generation g the task score ``scores[g]`` and every other genome 0."""

    name = "scripted"

    def __init__(self, scores):
        self.scores = scores
        self.failures = []

    def map(self, genomes, generation):
        empty = sensor_statistics(Morphology())
        return [Evaluation(task=self.scores[generation] if i == 0 else 0.0, morphology=50.0, controller=50.0,
                           sensors=empty) for i in range(len(genomes))]

    def close(self):
        pass


@pytest.mark.parametrize("bonus, threshold", [(20.0, 110.0), (10.0, 105.0)])  # 100 + bonus / 2, by hand
def test_so_convergence_stop_fires_exactly_at_the_threshold(tmp_path, monkeypatch, bonus, threshold):
    exp = experiment_file(tmp_path, "so", "hyperneat-m", '["task"]', generations=6,
                          extra="convergence_stop = true")
    text = exp.read_text().replace("num_robots = 10", f"num_robots = 10\ntime_bonus = {bonus}")
    exp.write_text(text)
    scores = [threshold - 1e-9, threshold - 1e-6, threshold, threshold + 5, 0.0, 0.0]
    monkeypatch.setattr(trainer_module, "make_evaluator", lambda *a, **k: ScriptedEvaluator(scores))
    result = trainer_module.Trainer(load_experiment(exp), tmp_path / "run", workers=1, progress=False).run()
    assert result.converged and result.generations == 3        # stopped right after generation 2
    # the MO arm never stops early
    mo = experiment_file(tmp_path, "mo", "hyperneat-m", '["task", "morphology"]', generations=4,
                         extra="convergence_stop = true")
    mo.write_text(mo.read_text().replace("num_robots = 10", f"num_robots = 10\ntime_bonus = {bonus}"))
    result = trainer_module.Trainer(load_experiment(mo), tmp_path / "mo-run", workers=1, progress=False).run()
    assert not result.converged and result.generations == 4


def test_per_process_worlds_are_keyed_by_the_whole_world_configuration():
    """The evaluation's cached batch of worlds is rebuilt whenever any world option or the
    number of trials changes: every result equals one from a fresh process."""
    from evolution.run import evaluate as evaluation
    from gathering_env.config import WorldConfig

    base = dict(environment=1, arena_width=6.0, arena_height=6.0, zone_width=6.0, zone_depth=2.0,
                block_counts=[8, 0, 0], max_cycles=60, num_robots=10)
    variants = [dict(base, max_cycles=50), dict(base, block_counts=[7, 1, 0]), dict(base, zone_depth=1.5),
                dict(base, arena_width=7.0), dict(base, collision_avoidance=True), dict(base, ir_response="gamma"),
                dict(base, kernel="numpy"), dict(base, reward="shaped"), dict(base, physics_substeps=2)]
    for variant in variants:
        evaluation._worlds_for(base, 2)                                  # a warm cache of another world
        sims = evaluation._worlds_for(variant, 2)
        assert sims.config == WorldConfig.from_kwargs(**variant), variant
        assert sims.config != WorldConfig.from_kwargs(**base)
    assert evaluation._worlds_for(base, 3).num_worlds == 3 and evaluation._worlds_for(base, 2).num_worlds == 2
    # and the scores: a short world evaluated after a long one scores as in a fresh process
    config, genome = hand_cppn()
    evaluate(genome, config, HAND_WORLD, trials=5, seed=3, generation=1)
    warm = evaluate(genome, config, dict(HAND_WORLD, max_cycles=60), trials=5, seed=3, generation=1)
    evaluation._SIM_CACHE.clear()
    cold = evaluate(genome, config, dict(HAND_WORLD, max_cycles=60), trials=5, seed=3, generation=1)
    assert warm.trial_ft == cold.trial_ft and warm.steps == cold.steps == 5 * 60


def test_a_failed_evaluation_has_the_worst_objectives_and_keeps_its_error():
    ev = Evaluation.failure("worker died")
    assert ev.objectives(("task", "morphology", "controller")) == (0.0, 0.0, 0.0)   # every minimum
    assert ev.failed and ev.error == "worker died" and ev.trial_ft == [] and ev.steps == 0
    np.testing.assert_equal(ev.sensors, sensor_statistics(Morphology()))            # NaN means: no sensor
    assert ev.sensors["num_sensors"] == 0.0
    np.testing.assert_equal(Evaluation(**ev.to_dict()).to_dict(), ev.to_dict())
    assert not Evaluation(task=1.0, morphology=2.0, controller=3.0).failed
