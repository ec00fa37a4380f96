"""Multi-agent RL tooling: the global state, TorchRL (wrapper and batched env), BenchMARL, policy files."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from evolution.cli import replay_main
from evolution.compare import compare, compare_main
from evolution.policies import make_policy
from gathering_env import parallel_env
from gathering_env.reference.sensing import SensorBank
from gathering_env.state import state_size

ROOT = Path(__file__).resolve().parents[1]


def decode_state(state: np.ndarray, config) -> dict[str, np.ndarray]:
    """The poses and flags of a state vector, read by the layout of docs/environment.md."""
    n, b = config.num_robots, config.num_blocks
    robots, blocks = state[:5 * n].reshape(n, 5), state[5 * n:5 * n + 5 * b].reshape(b, 5)
    scale = np.array([config.arena_width, config.arena_height])
    return {"robot_pos": robots[:, :2] * scale, "robot_angle": np.arctan2(robots[:, 3], robots[:, 2]),
            "attached": robots[:, 4], "block_pos": blocks[:, :2] * scale,
            "block_angle": np.arctan2(blocks[:, 3], blocks[:, 2]), "gathered": blocks[:, 4], "step": state[-1]}


# ---------------------------------------------------------------------- the global state
def test_state_before_reset_is_a_clear_error():
    env = parallel_env(environment=1, max_cycles=20)
    with pytest.raises(ValueError, match=r"state\(\) called before reset\(\)"):
        env.state()


@pytest.mark.parametrize("kernel", ["compiled", "numpy"])
def test_state_is_consistent_with_observations_and_infos(kernel):
    """Readings recomputed by the numpy reference sensors from the decoded state equal the env's
    observations; gathered flags weighted by block values give the info's gathered value."""
    from evolution.policies.scripted import WanderTeam

    env = parallel_env(environment=1, max_cycles=2000, kernel=kernel)
    cfg = env.config
    assert env.state_space.shape == (state_size(cfg),) == (5 * 20 + 5 * 15 + 1,)
    obs, infos = env.reset(seed=3)
    team = WanderTeam(env.morphology, seed=0)
    attached_seen = gathered_seen = False
    for _ in range(2000):
        state = env.state()
        assert env.state_space.contains(state)
        s = decode_state(state, cfg)
        w = env.sim.world
        bank = SensorBank(env.morphology, cfg, w.block_half, w.block_need)
        readings = bank.read(s["robot_pos"], s["robot_angle"], s["block_pos"], s["block_angle"])
        observed = np.stack([obs[a] for a in env.possible_agents])
        assert np.mean(np.abs(readings - observed) < 1e-3) > 0.99      # float32 poses: a rare reading may flip
        info = infos["robot_0"]
        assert s["step"] == pytest.approx(info["steps"] / cfg.max_cycles)
        assert float(w.block_value @ s["gathered"]) == pytest.approx(info["gathered_value"])
        attached_seen |= s["attached"].any()
        gathered_seen |= s["gathered"].any()
        if not env.agents or (attached_seen and gathered_seen):
            break
        obs, _, _, _, infos = env.step(dict(zip(env.agents, team.act(observed))))
    assert attached_seen and gathered_seen, "the episode should show attachments and gathered blocks"


def test_vector_states_equal_the_env_states():
    from gathering_env.vector import VectorSimulation

    sims = VectorSimulation(2, environment=1, max_cycles=50)
    sims.reset([5, 6])
    envs = [parallel_env(environment=1, max_cycles=50) for _ in range(2)]
    for env, seed in zip(envs, (5, 6)):
        env.reset(seed=seed)
    wheels = np.random.default_rng(1).uniform(-1, 1, (30, 2, 20, 2))
    for t in range(30):
        sims.step(wheels[t])
        for w, env in enumerate(envs):
            env.step_batch(wheels[t, w])
    np.testing.assert_array_equal(sims.states(), np.stack([env.state() for env in envs]))


# ---------------------------------------------------------------------- TorchRL
torchrl = pytest.importorskip("torchrl")
torch = pytest.importorskip("torch")


def test_pettingzoo_wrapper_passes_check_env_specs():
    from torchrl.envs import PettingZooWrapper
    from torchrl.envs.utils import check_env_specs

    env = PettingZooWrapper(parallel_env(environment=1, num_robots=5, max_cycles=15), return_state=True,
                            categorical_actions=False, seed=0)
    assert list(env.group_map) == ["robot"] and len(env.group_map["robot"]) == 5
    check_env_specs(env, seed=0)
    rollout = env.rollout(40, break_when_any_done=False)       # crosses two episode ends
    assert rollout["next", "done"].sum() == 2
    assert rollout["next", "state"].shape == (40, 5 * 5 + 5 * 15 + 1)


def test_batched_env_passes_check_env_specs_and_matches_the_pettingzoo_env():
    from torchrl.envs.utils import check_env_specs

    from gathering_env.rl.seeds import SEED_LIMIT
    from gathering_env.rl.torchrl_env import GatheringTorchEnv

    world = {"environment": 1, "num_robots": 20, "max_cycles": 60, "reward": "shaped", "reward_scope": "local"}
    tenv = GatheringTorchEnv(3, seed=7, **world)
    check_env_specs(tenv, seed=7)
    tenv.set_seed(7)
    gen = torch.Generator().manual_seed(0)

    def forward(td):                          # full speed ahead with noise: robots reach blocks
        td.set(("robot", "action"), (0.9 + 0.2 * torch.randn((3, 20, 2), generator=gen)).clamp(-1, 1))
        return td

    rollout = tenv.rollout(70, forward, break_when_any_done=False, auto_reset=True)   # worlds end at step 60
    actions = rollout["robot", "action"].numpy()
    seeds = np.random.default_rng(7).integers(0, SEED_LIMIT, 6)      # 3 first episodes, then 3 resets
    rewards_seen = []
    for w in range(3):
        env = parallel_env(**world)
        obs, _ = env.reset(seed=int(seeds[w]))
        for t in range(70):
            if t == 60:
                obs, _ = env.reset(seed=int(seeds[3 + w]))
                np.testing.assert_array_equal(rollout[w, t]["robot", "observation"].numpy(),
                                              np.stack([obs[a] for a in env.possible_agents]))
            obs, rewards, term, trunc, _ = env.step(dict(zip(env.possible_agents, actions[w, t])))
            nxt = rollout[w, t]["next"]
            np.testing.assert_array_equal(nxt["robot", "observation"].numpy(),
                                          np.stack([obs[a] for a in env.possible_agents]))
            rewards_seen.append([rewards[a] for a in env.possible_agents])
            np.testing.assert_allclose(nxt["robot", "reward"].numpy()[:, 0], rewards_seen[-1], rtol=1e-5, atol=1e-9)
            np.testing.assert_array_equal(nxt["state"].numpy(), env.state())
            assert bool(nxt["done"]) == bool(nxt["truncated"]) == (t == 59)
    rewards_seen = np.array(rewards_seen)
    assert (rewards_seen.std(axis=1) > 0).sum() >= 5          # local credit: robots' rewards differ


# ---------------------------------------------------------------------- BenchMARL
benchmarl = pytest.importorskip("benchmarl")


def run_example(tmp_path: Path, algorithm: str, *extra: str) -> Path:
    out = tmp_path / algorithm
    args = ["--algorithm", algorithm, "--robots", "4", "--steps", "20", "--worlds", "2", "--env-steps", "160",
            "--frames-per-batch", "80", "--epochs", "1", "--minibatch", "40", "--eval-episodes", "1",
            "--out", str(out), *extra]
    sys.path.insert(0, str(ROOT / "examples"))
    try:
        import benchmarl_run
    finally:
        sys.path.pop(0)
    assert benchmarl_run.main(args) == 0
    return out


@pytest.mark.parametrize("algorithm, extra", [("ippo", ()), ("mappo", ("--tanh-normal",))])
def test_benchmarl_runs_exports_a_policy_that_replays_and_compares(tmp_path, algorithm, extra, capsys):
    out = run_example(tmp_path, algorithm, *extra)
    run = json.loads((out / "run.json").read_text())
    assert run["env_steps"] == 160 and run["training_episodes"] == 8   # 2 worlds x 80 steps / 20-step episodes
    rows = (out / "curve.csv").read_text().splitlines()
    assert rows[0] == "env_steps,minutes,ft"
    assert [int(r.split(",")[0]) for r in rows[1:]] == [40, 40, 80, 80, 120, 120, 160, 160]
    policy = make_policy(f"benchmarl:{out / 'policy.pt'}")
    assert policy.environment == {"environment": 1, "num_robots": 4, "max_cycles": 20}
    again = compare([policy, make_policy(f"benchmarl:{out / 'policy.pt'}")], dict(policy.environment), [10_000])
    assert again[0]["ft_mean"] == again[1]["ft_mean"] == run["evaluation"]["deterministic"]["ft_mean"]
    sampled = make_policy(f"benchmarl-sample:{out / 'policy.pt'}")
    obs = np.random.default_rng(0).uniform(0, 1, (4, 6))
    sampled.reset(3)
    first = sampled.act(obs)
    sampled.reset(3)
    np.testing.assert_array_equal(first, sampled.act(obs))                   # seeded
    assert np.isfinite(first).all() and not np.array_equal(first, policy.act(obs))
    if "--tanh-normal" in extra:
        assert np.all(np.abs(first) <= 1)            # squashed; Gaussian samples are clipped by the env
    gif = tmp_path / f"{algorithm}.gif"
    assert replay_main([f"benchmarl-sample:{out / 'policy.pt'}", "--steps", "10", "--out", str(gif)]) == 0
    assert gif.stat().st_size > 0 and "environment 1" in capsys.readouterr().out


def test_benchmarl_trains_over_torchrls_pettingzoo_wrapper_too(tmp_path):
    sys.path.insert(0, str(ROOT / "examples"))
    try:
        import benchmarl_run
    finally:
        sys.path.pop(0)
    args = benchmarl_run.parse_args(["--algorithm", "mappo", "--robots", "3", "--steps", "10", "--worlds", "2",
                                     "--env-steps", "40", "--frames-per-batch", "20", "--epochs", "1",
                                     "--minibatch", "10", "--out", str(tmp_path)])
    (tmp_path / "benchmarl").mkdir()
    log = benchmarl_run.EpisodeLog()
    experiment = benchmarl_run.build_experiment(args, [log], route="wrapper")
    assert type(experiment.test_env.base_env).__name__ == "PettingZooWrapper"
    experiment.run()
    assert experiment.total_frames == 40
    assert [r["env_steps"] for r in log.rows] == [20, 20, 40, 40]    # 2 worlds x 2 episodes of 10 steps
    assert "state" in experiment.state_spec.keys()


def test_policy_files_of_the_wrong_kind_are_refused(tmp_path, capsys):
    with pytest.raises(ValueError, match="policy file not found"):
        make_policy(f"benchmarl:{tmp_path / 'missing.pt'}")
    (tmp_path / "notes.pt").write_text("hello")
    with pytest.raises(ValueError, match="not a readable torch file"):
        make_policy(f"benchmarl:{tmp_path / 'notes.pt'}")
    torch.save({"collector": {}, "loss_robot": {}}, tmp_path / "checkpoint_1.pt")
    with pytest.raises(ValueError, match="BenchMARL experiment checkpoint"):
        make_policy(f"benchmarl:{tmp_path / 'checkpoint_1.pt'}")
    assert compare_main(["--policy", f"ppo:{tmp_path / 'checkpoint_1.pt'}", "--out", str(tmp_path / "c")]) == 2
    assert "not a readable Stable-Baselines3 PPO model" in capsys.readouterr().err
    assert compare_main(["--policy", "mappo:x.pt"]) == 2
    assert "allowed: random, heuristic, wander" in capsys.readouterr().err
    assert replay_main(["wandr", "--out", str(tmp_path / "t.gif")]) == 2
    err = capsys.readouterr().err
    assert "neither a champion file nor a policy name" in err and "benchmarl:PATH" in err and len(err.splitlines()) == 1


def test_task_config_and_continuous_actions_only():
    from gathering_env.rl.benchmarl_task import GatheringTask, check_task_config

    task = GatheringTask.ENV2.get_from_yaml()
    assert task.config["environment"] == 2 and task.supports_continuous_actions()
    assert not task.supports_discrete_actions()
    with pytest.raises(ValueError, match="reward_scale"):
        check_task_config({"environment": 1, "reward_scale": 0})
    with pytest.raises(ValueError, match="reward"):
        check_task_config({"environment": 1, "reward": "dense"})
    with pytest.raises(ValueError, match="continuous wheel commands only"):
        task.get_env_fun(2, continuous_actions=False, seed=0, device="cpu")


@pytest.mark.slow
def test_benchmarl_hydra_config_system_runs_the_task(tmp_path):
    cmd = [sys.executable, "-m", "gathering_env.rl.benchmarl_hydra", "algorithm=mappo", "task=gathering/env1",
           "task.num_robots=3", "task.max_cycles=10", "experiment.max_n_frames=40",
           "experiment.on_policy_collected_frames_per_batch=20", "experiment.on_policy_n_envs_per_worker=2",
           "experiment.on_policy_n_minibatch_iters=1", "experiment.on_policy_minibatch_size=10",
           "experiment.loggers=[csv]", "experiment.render=False", "experiment.evaluation=False",
           f"experiment.save_folder={tmp_path}", f"hydra.run.dir={tmp_path / 'hydra'}"]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    done = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp_path, timeout=300, env=env)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "task: gathering/env1" in done.stdout.replace("Task: ", "task: ")
    assert list(tmp_path.glob("mappo_env1_*/*/scalars/ft_mean.csv"))
