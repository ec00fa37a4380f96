"""Held-out re-evaluation: seeds disjoint from training, replayed scores, cache, CLI."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
import small_runs

from evolution.analysis.fronts import analyse
from evolution.analysis.reevaluate import (
    CACHE_FILE,
    _run_setup,
    heldout_seeds,
    reevaluate_run,
    training_seeds,
)
from evolution.cli import analyze_main
from evolution.reproduction.pareto import non_dominated_fronts
from evolution.run.champion import genome_from_dict, load_champion
from evolution.run.evaluate import evaluate, trial_seed


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Copies of the shared small runs (re-evaluation writes its cache into them)."""
    _, so, _, mo = small_runs.build(tmp_path_factory)
    root = tmp_path_factory.mktemp("reeval")
    shutil.copytree(so, root / "so")
    shutil.copytree(mo, root / "mo")
    return root / "so", root / "mo"


def test_heldout_seeds_are_disjoint_from_training():
    train = training_seeds(7, 250, 5)
    held = heldout_seeds(7, 250, 5, 20)
    assert len(set(held)) == 20 and not set(held) & train
    # brute force: no (generation, trial) of the run gives a held-out seed
    assert all(trial_seed(7, g, t) not in set(held) for g in range(250) for t in range(5))


def test_replayed_champion_reproduces_its_stored_score(runs):
    so, _ = runs
    experiment, config, substrate = _run_setup(so)
    champion = load_champion(so / "champion.json")
    genome = genome_from_dict(champion.genome, config)
    ev = evaluate(genome, config, experiment.environment, trials=experiment.trials, seed=experiment.seed,
                  generation=champion.generation, method=experiment.method, substrate=substrate)
    assert ev.task == pytest.approx(champion.objectives["task"])
    assert ev.morphology == pytest.approx(champion.objectives["morphology"])
    # the mean ft over trials run on distinct seeds is the fitness
    seeds = {trial_seed(experiment.seed, champion.generation, t) for t in range(experiment.trials)}
    assert len(seeds) == experiment.trials and ev.task == pytest.approx(np.mean(ev.trial_ft))


def test_reevaluation_uses_heldout_seeds_and_is_cached(runs):
    so, mo = runs
    scores = reevaluate_run(mo, 3, workers=1, backend="serial")
    front_files = sorted(p.relative_to(mo).as_posix() for p in (mo / "front").glob("*.json"))
    assert set(front_files) <= set(scores) and "champion.json" in scores
    experiment, config, substrate = _run_setup(mo)
    expected_seeds = heldout_seeds(experiment.seed, experiment.generations, experiment.trials, 3)
    for name, entry in scores.items():
        assert entry["seeds"] == expected_seeds and len(entry["trial_ft"]) == 3
        doc = json.loads((mo / name).read_text())
        assert entry["morphology"] == pytest.approx(doc["objectives"]["morphology"])
    cache = json.loads((mo / CACHE_FILE).read_text())
    assert len(cache["entries"]) == len({json.dumps(json.loads((mo / n).read_text())["genome"]) for n in scores})
    mtime = (mo / CACHE_FILE).stat().st_mtime_ns
    assert reevaluate_run(mo, 3, workers=1, backend="serial") == scores     # served from the cache
    assert (mo / CACHE_FILE).stat().st_mtime_ns == mtime                   # not rewritten
    so_scores = reevaluate_run(so, 3, workers=1, backend="serial")
    champion = load_champion(so / "champion.json")
    held_out = so_scores["champion.json"]
    assert held_out["task"] != champion.objectives["task"]                # new worlds, another score
    reference = reference_ft(champion, held_out["seeds"])
    assert held_out["trial_ft"] == pytest.approx(reference)               # trial by trial, seed by seed
    assert held_out["task"] == pytest.approx(np.mean(reference))


def reference_ft(champion, seeds):
    """ft of the champion's stored team on each seed, by a plain loop over the environment."""
    from gathering_env import parallel_env

    env = parallel_env(**champion.environment)
    fts = []
    for seed in seeds:
        obs, _ = env.reset(seed=seed, options={"morphology": champion.morphology})
        obs = np.stack([obs[a] for a in env.possible_agents])
        while True:
            obs, _, terminated, truncated = env.step_batch(champion.controller.act(obs))
            if terminated or truncated:
                break
        fts.append(env.team_info()["task_performance"])
    return fts


def test_analysis_with_reevaluation_is_reproducible(runs, tmp_path):
    so, mo = runs
    a = analyse([so, mo], reevaluate=3, workers=1, backend="serial")
    b = analyse([so, mo], reevaluate=3, workers=1, backend="serial")
    assert a.scores.startswith("held-out") and b.scores == a.scores
    assert np.array_equal(a.so_points[1], b.so_points[1])
    assert all(np.array_equal(a.run_points[1][p], b.run_points[1][p]) for p in a.run_points[1])
    front = a.runs[1].front
    assert len(non_dominated_fronts(front)[0]) == len(front)              # still a front
    training = analyse([so, mo])
    assert training.scores.startswith("training")
    assert a.runs[0].champion_training == training.runs[0].champion
    out = tmp_path / "report"
    assert analyze_main([str(so), str(mo), "--out", str(out), "--reevaluate", "3", "--workers", "1"]) == 0
    assert "held-out" in (out / "report.md").read_text()


def test_reevaluation_never_overwrites_a_foreign_file(runs, tmp_path, capsys):
    so, _ = runs
    copy = tmp_path / "copy"
    shutil.copytree(so, copy)
    (copy / CACHE_FILE).write_text("my notes\n")
    assert analyze_main([str(copy), "--out", str(tmp_path / "r"), "--reevaluate", "2", "--workers", "1"]) == 2
    assert "not a re-evaluation cache" in capsys.readouterr().err
    assert (copy / CACHE_FILE).read_text() == "my notes\n"


@pytest.mark.parametrize("args, needle", [(["--reevaluate", "-1"], "--reevaluate"),
                                          (["--workers", "0"], "--workers"),
                                          (["--backend", "gpu"], "--backend")])
def test_bad_reevaluation_options(runs, tmp_path, capsys, args, needle):
    so, _ = runs
    with pytest.raises(SystemExit) as exit_status:     # argparse's error, one line (evolution.guard)
        analyze_main([str(so), "--out", str(tmp_path / "r"), *args])
    assert exit_status.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and needle in err and "allowed" in err and err.count("\n") == 1
    assert not (tmp_path / "r").exists()


# ---------------------------------------------------------------------------- worlds actually stepped
def spy_on_resets(monkeypatch) -> list[list[int]]:
    """Record the seeds of every batch of worlds the evaluation resets."""
    from gathering_env.vector import VectorSimulation

    seen: list[list[int]] = []
    original = VectorSimulation.reset

    def reset(self, seeds, morphology=None):
        seen.append([int(s) for s in seeds])
        return original(self, seeds, morphology)

    monkeypatch.setattr(VectorSimulation, "reset", reset)
    return seen


def fresh_copy(run, tmp_path):
    copy = tmp_path / run.name
    shutil.copytree(run, copy)
    (copy / CACHE_FILE).unlink(missing_ok=True)
    return copy


def test_reevaluation_steps_the_heldout_worlds(runs, tmp_path, monkeypatch):
    so = fresh_copy(runs[0], tmp_path)
    experiment, _, _ = _run_setup(so)
    seen = spy_on_resets(monkeypatch)
    scores = reevaluate_run(so, 3, workers=1, backend="serial")
    # By hand: SeedSequence([run seed, 2**32 - 1, t]), the tag no training generation reaches.
    held = [int(np.random.SeedSequence([experiment.seed, 2**32 - 1, t]).generate_state(1)[0]) for t in range(3)]
    assert not set(held) & training_seeds(experiment.seed, experiment.generations, experiment.trials)
    assert seen == [held] * len(scores)                  # every genome stepped exactly the held-out worlds
    assert all(entry["seeds"] == held for entry in scores.values())
    champion = load_champion(so / "champion.json")
    assert scores["champion.json"]["trial_ft"] == pytest.approx(reference_ft(champion, held))


def test_reevaluation_cache_is_keyed_by_what_changes_the_score(runs, tmp_path, monkeypatch):
    so = fresh_copy(runs[0], tmp_path)
    seen = spy_on_resets(monkeypatch)
    first = reevaluate_run(so, 3, workers=1, backend="serial")
    assert len(seen) == 1
    assert reevaluate_run(so, 3, workers=1, backend="serial") == first and len(seen) == 1   # cached
    # Fewer trials: the two seeds are the first two of the three, but the score is another mean.
    two = reevaluate_run(so, 2, workers=1, backend="serial")
    assert len(seen) == 2 and seen[-1] == first["champion.json"]["seeds"][:2]
    assert two["champion.json"]["trial_ft"] == first["champion.json"]["trial_ft"][:2]
    # Another world (the run's experiment edited): evaluated again, in that world.
    doc = json.loads((so / "experiment.json").read_text())
    doc["environment"]["max_cycles"] = 40
    (so / "experiment.json").write_text(json.dumps(doc))
    shorter = reevaluate_run(so, 3, workers=1, backend="serial")
    assert len(seen) == 3 and seen[-1] == first["champion.json"]["seeds"]
    champion = load_champion(so / "champion.json")
    champion.environment["max_cycles"] = 40
    assert shorter["champion.json"]["trial_ft"] == pytest.approx(reference_ft(champion, seen[-1]))


def test_cache_key_covers_genome_method_world_substrate_and_seeds():
    from types import SimpleNamespace

    from evolution.analysis.reevaluate import _entry_key

    base = dict(method="hyperneat-m", environment={"environment": 1, "max_cycles": 80}, substrate={},
                complexity="paper")
    genome = {"key": 1, "nodes": [[0, 0.5]]}
    key = _entry_key(genome, SimpleNamespace(**base), [1, 2, 3])
    assert _entry_key(dict(genome), SimpleNamespace(**base), [1, 2, 3]) == key            # same inputs
    variants = [
        (dict(genome, nodes=[[0, 0.6]]), base, [1, 2, 3]),                                  # genome
        (genome, dict(base, method="neat-m"), [1, 2, 3]),                                    # method
        (genome, dict(base, environment={"environment": 1, "max_cycles": 81}), [1, 2, 3]),  # world
        (genome, dict(base, substrate={"hidden_nodes": 2}), [1, 2, 3]),                     # substrate
        (genome, dict(base, complexity="original"), [1, 2, 3]),                              # eq. 2 variant
        (genome, base, [1, 2]),                                                              # trials
        (genome, base, [1, 2, 4]),                                                           # seeds
    ]
    keys = {_entry_key(g, SimpleNamespace(**e), seeds) for g, e, seeds in variants}
    assert len(keys) == len(variants) and key not in keys
