"""Standard RL tooling on the unchanged env: SuperSuit + SB3 PPO, Gymnasium's checker, comparisons."""

from __future__ import annotations

import json

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import gathering_env  # noqa: F401 - registers the envs
from evolution.compare import compare_main
from gathering_env import TEAM_ENV_ID, Morphology, parallel_env

ss = pytest.importorskip("supersuit")
sb3 = pytest.importorskip("stable_baselines3")


def test_supersuit_vector_env_trains_ppo_and_reloads(tmp_path):
    env = parallel_env(environment=1, num_robots=6, max_cycles=60)
    env.reset(seed=0)                       # seeded before wrapping (SuperSuit cannot forward seeds)
    vec = ss.pettingzoo_env_to_vec_env_v1(env)
    vec = ss.concat_vec_envs_v1(vec, 1, num_cpus=0, base_class="stable_baselines3")
    assert vec.num_envs == 6 and vec.observation_space.shape == (6,)
    model = sb3.PPO("MlpPolicy", vec, n_steps=32, batch_size=96, n_epochs=1, device="cpu")
    model.learn(total_timesteps=384)
    model.save(tmp_path / "model.zip")
    again = sb3.PPO.load(tmp_path / "model.zip", device="cpu")
    obs = np.random.default_rng(0).uniform(0, 1, (6, 6)).astype(np.float32)
    np.testing.assert_array_equal(model.predict(obs, deterministic=True)[0], again.predict(obs, deterministic=True)[0])


def test_gymnasium_team_env_passes_checker_and_trains():
    env = gymnasium.make(TEAM_ENV_ID, environment=1, num_robots=4, max_cycles=40)
    check_env(env.unwrapped)
    assert env.observation_space.shape == (4 * 6,) and env.action_space.shape == (8,)
    model = sb3.PPO("MlpPolicy", env, n_steps=64, batch_size=64, n_epochs=1, device="cpu")
    model.learn(total_timesteps=128)
    obs, info = env.reset(seed=1, options={"morphology": [{"type": "bottom"}]})
    assert obs.shape == (4,) and env.observation_space.shape == (4,)
    with pytest.raises(ValueError, match=r"expected \(8,\)"):
        env.step(np.zeros(5))


def test_compare_two_policies_writes_table_and_figure(tmp_path, capsys):
    assert compare_main(["--policy", "random", "--policy", "heuristic", "--environment", "1", "--steps", "60",
                         "--robots", "5", "--episodes", "2", "--out", str(tmp_path)]) == 0
    header = (tmp_path / "compare.csv").read_text().splitlines()[0].split(",")
    assert header == ["policy", "sensors", "episodes", "ft_mean", "ft_std", "small", "medium", "large",
                      "finished", "steps_to_finish"]
    assert (tmp_path / "compare.png").read_bytes()[:4] == b"\x89PNG"
    table = (tmp_path / "compare.md").read_text()
    assert "| random |" in table and "| heuristic |" in table


def test_compare_keeps_policies_of_the_same_name_apart(tmp_path, capsys):
    assert compare_main(["--policy", "random", "--policy", "random", "--environment", "1", "--steps", "20",
                         "--robots", "3", "--episodes", "1", "--out", str(tmp_path)]) == 0
    names = [line.split(",")[0] for line in (tmp_path / "compare.csv").read_text().splitlines()[1:]]
    assert names == ["random", "random#2"]


def test_policy_of_wrong_observation_size_is_refused(tmp_path, capsys):
    env = parallel_env(environment=1, num_robots=3, max_cycles=20, morphology=[{"type": "bottom"}])
    env.reset(seed=0)
    vec = ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(env), 1, num_cpus=0, base_class="stable_baselines3")
    model = sb3.PPO("MlpPolicy", vec, n_steps=16, batch_size=48, device="cpu")
    model.save(tmp_path / "tiny.zip")           # trained on 1 sensor; no morphology file -> Khepera III (6)
    assert compare_main(["--policy", f"ppo:{tmp_path / 'tiny.zip'}", "--steps", "20", "--episodes", "1",
                         "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "expects observations of shape (1,)" in err and "6 sensors" in err
    (tmp_path / "tiny.morphology.json").write_text(json.dumps(Morphology([{"type": "bottom"}]).to_dict()))
    assert compare_main(["--policy", f"ppo:{tmp_path / 'tiny.zip'}", "--steps", "20", "--robots", "3",
                         "--episodes", "1", "--out", str(tmp_path / "out")]) == 0


def test_unknown_policy_spec(capsys):
    assert compare_main(["--policy", "genius"]) == 2
    assert "allowed: random, heuristic" in capsys.readouterr().err
