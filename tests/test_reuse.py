"""Each distinct team is simulated once (``evolution.run.reuse``): a run gives the statistics
and champion it gives when every genome is simulated, ``steps`` aside, and it does reuse."""

from __future__ import annotations

import pytest
from small_runs import experiment_file

from evolution.cli import evolve_main
from evolution.run import reuse, trainer
from evolution.run.experiment import load_experiment
from evolution.run.stats import read_stats, without_work

CASES = {
    "hyperneat-so-fresh-layouts": ("hyperneat-m", '["task"]', ""),
    "neat-m-mo": ("neat-m", '["task", "morphology"]', ""),
    "ratchet-one-layout": ("hyperneat-m", '["task"]', 'layout = "per_run"\nelitism = "ratchet"\nspeciation = "original"'),
}


def _run(exp, out, capsys):
    assert evolve_main([str(exp), "--out", str(out), "--workers", "1", "--no-progress", "--population", "16"]) == 0
    return capsys.readouterr().out


@pytest.mark.parametrize("case", sorted(CASES))
def test_reuse_gives_the_run_of_simulating_every_genome(case, tmp_path, capsys):
    method, objectives, extra = CASES[case]
    exp = experiment_file(tmp_path, case, method, objectives, generations=4, extra=extra)
    said = _run(exp, tmp_path / "reuse", capsys)
    every_run = trainer.Trainer(load_experiment(exp, {"population": 16}), tmp_path / "all", workers=1,
                                progress=False, reuse=False).run()
    assert every_run.reused == 0
    with_reuse, every = read_stats(tmp_path / "reuse" / "stats.jsonl"), read_stats(tmp_path / "all" / "stats.jsonl")
    assert without_work(with_reuse) == without_work(every)
    assert (tmp_path / "reuse" / "champion.json").read_bytes() == (tmp_path / "all" / "champion.json").read_bytes()
    saved = sum(a["steps"] for a in every) - sum(r["steps"] for r in with_reuse)
    assert saved > 0, "no genome was reused: the test data cannot tell"
    assert "genomes decoded to a team already scored" in said


def test_equal_teams_have_equal_keys_and_a_changed_weight_another(tmp_path):
    import numpy as np

    from evolution.encodings.controller import TeamController
    from gathering_env import Morphology, SensorSpec

    weights = np.arange(20.0).reshape(2, 10) / 7.0
    sensors = Morphology([SensorSpec("infrared", bearing=0.1 * i, range=2.0, fov=1.0) for i in range(10)])
    a = TeamController.single_layer(weights, np.zeros(2))
    b = TeamController.single_layer(weights.copy(), np.zeros(2))
    nudged = weights.copy()
    nudged[1, 3] = np.nextafter(nudged[1, 3], 10.0)  # one bit of one weight
    c = TeamController.single_layer(nudged, np.zeros(2))
    assert reuse.team_key(a, sensors) == reuse.team_key(b, sensors)
    assert reuse.team_key(a, sensors) != reuse.team_key(c, sensors)
    other = Morphology([SensorSpec("infrared", bearing=0.1 * i, range=2.0 if i else 2.5, fov=1.0) for i in range(10)])
    assert reuse.team_key(a, sensors) != reuse.team_key(a, other)
