"""PettingZoo conformance (pettingzoo.test), registry, spaces, seeding and infos."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pettingzoo
import pettingzoo.utils.conversions
import pytest
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test, render_test, seed_test

import gathering_env
from gathering_env import ENV_ID, Morphology, SensorSpec, env, parallel_env

# pettingzoo.test passes a made-up reset option; the env warns that it ignores it.
pytestmark = pytest.mark.filterwarnings("ignore:ignoring unknown reset option")


def test_parallel_api():
    parallel_api_test(parallel_env(max_cycles=150), num_cycles=200)


def test_aec_api():
    api_test(env(max_cycles=80), num_cycles=100)


def test_seeds():
    parallel_seed_test(lambda: parallel_env(max_cycles=60), num_cycles=80)
    seed_test(lambda: env(max_cycles=60), num_cycles=80)


def test_render_rgb_array():
    render_test(lambda render_mode=None: env(render_mode=render_mode or "rgb_array", max_cycles=30))


def test_registry_make_parallel_and_aec():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no deprecation warning on the registry path
        p = pettingzoo.make("parallel", ENV_ID, environment=3, max_cycles=5)
        a = pettingzoo.make("aec", ENV_ID, environment=1, max_cycles=5)
    assert isinstance(p, gathering_env.GatheringEnv)
    assert p.config.block_counts == (0, 5, 10)
    a.reset(seed=0)
    assert a.agent_selection == "robot_0"
    assert a.unwrapped.config.block_counts == (10, 5, 0)
    assert isinstance(a.env, pettingzoo.utils.conversions.parallel_to_aec_wrapper)  # wrapped once


def test_spaces_follow_the_morphology():
    e = parallel_env(max_cycles=5)
    e.reset(seed=0)
    assert e.observation_space("robot_3").shape == (6,)
    assert e.action_space("robot_3") == e.action_space("robot_0")
    assert e.action_space("robot_0").shape == (2,) and e.action_space("robot_0").dtype == np.float32
    two = [SensorSpec("camera", 0.5, 0.0, 12.0, 1.0), {"type": "bottom"}]
    obs, _ = e.reset(seed=0, options={"morphology": two})
    assert e.observation_space("robot_0").shape == (2,)
    assert obs["robot_0"].shape == (2,) and obs["robot_0"].dtype == np.float32
    obs, _ = e.reset(seed=0, options={"morphology": Morphology.khepera_iii().to_dict()})
    assert obs["robot_0"].shape == (6,)
    obs, _ = e.reset(seed=0, options={"morphology": []})
    assert obs["robot_0"].shape == (0,)


def test_same_seed_same_trajectory_and_different_seeds_differ():
    def trajectory(seed):
        e = parallel_env(environment=2, max_cycles=200)
        obs, _ = e.reset(seed=seed)
        rng = np.random.default_rng(42)
        out = [np.stack(list(obs.values()))]
        while e.agents:
            obs, *_ = e.step({a: rng.uniform(-1, 1, 2) for a in e.agents})
            if obs:
                out.append(np.stack(list(obs.values())))
        return np.array(out), e.sim.world.robot_pos.copy()

    a, pos_a = trajectory(5)
    b, pos_b = trajectory(5)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(pos_a, pos_b)
    _, pos_c = trajectory(6)
    assert not np.allclose(pos_a, pos_c)


def test_reset_without_seed_continues_the_seeded_stream():
    e1, e2 = parallel_env(max_cycles=5), parallel_env(max_cycles=5)
    e1.reset(seed=9)
    e2.reset(seed=9)
    e1.reset()
    e2.reset()
    np.testing.assert_array_equal(e1.sim.world.robot_pos, e2.sim.world.robot_pos)


def test_infos_rewards_and_truncation():
    e = parallel_env(environment=1, max_cycles=30)
    _, infos = e.reset(seed=1)
    assert set(infos["robot_0"]) == {"gathered_value", "total_value", "blocks_gathered",
                                     "blocks_gathered_by_type", "steps", "task_performance"}
    assert infos["robot_0"]["task_performance"] == 0.0  # present at every step (TorchRL's wrapper needs it)
    assert infos["robot_0"]["total_value"] == 10 * 1 + 5 * 2
    steps = 0
    while e.agents:
        _, rewards, terms, truncs, infos = e.step({a: np.zeros(2) for a in e.agents})
        steps += 1
        assert len(set(rewards.values())) == 1          # one team reward
    assert steps == 30 and all(truncs.values()) and not any(terms.values())
    assert infos["robot_0"]["task_performance"] == 0.0  # nothing gathered, no bonus
    assert e.agents == []
    with pytest.raises(RuntimeError, match="ended"):
        e.step({})


def test_step_batch_equals_step():
    e1, e2 = parallel_env(max_cycles=100), parallel_env(max_cycles=100)
    o1, _ = e1.reset(seed=3)
    e2.reset(seed=3)
    rng = np.random.default_rng(0)
    for _ in range(50):
        wheels = rng.uniform(-1, 1, (20, 2))
        o1, r1, *_ = e1.step({f"robot_{i}": wheels[i] for i in range(20)})
        o2, r2, *_ = e2.step_batch(wheels)
        np.testing.assert_array_equal(np.stack([o1[a] for a in e1.possible_agents]), o2)
        assert r1["robot_0"] == r2
    assert e1.team_info() == e2.team_info()


def test_observations_are_bounded_for_a_rich_morphology():
    morph = [SensorSpec(t, b, 0.3, r, f) for t, b, r, f in (
        ("infrared", 0.0, 5.0, 1.0), ("ultrasonic", math.pi / 2, 25.0, math.pi),
        ("colour", -math.pi / 2, 10.0, 2.0), ("camera", math.pi, 20.0, 2.5))] + [SensorSpec("bottom")]
    e = parallel_env(environment=3, max_cycles=100)
    e.reset(seed=0, options={"morphology": morph})
    space = e.observation_space("robot_0")
    rng = np.random.default_rng(1)
    for _ in range(100):
        obs, *_ = e.step({a: rng.uniform(-1, 1, 2) for a in e.agents})
        for o in obs.values():
            assert space.contains(o)
