"""Reward options: the shaping identity, local rewards that sum to the team reward, hand scenes, bad values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from evolution.policies.scripted import WanderTeam
from gathering_env import parallel_env
from gathering_env.config import WorldConfig
from gathering_env.simulation import GatheringSimulation
from gathering_env.vector import VectorSimulation

KERNELS = ("compiled", "numpy")


def hand_potential(cfg: WorldConfig, world) -> float:
    """Phi by the docs' formula, block by block and robot by robot:
    -100 * sum v * d / (total value * diagonal) + attach_reward * (robots attached)."""
    x0, y0, x1, y1 = cfg.zone_rect
    total = 0.0
    for (x, y), half, value in zip(world.block_pos.tolist(), world.block_half.tolist(), world.block_value.tolist()):
        dx = max(x0 + half - x, 0.0, x - (x1 - half))
        dy = max(y0 + half - y, 0.0, y - (y1 - half))
        total += value * math.sqrt(dx * dx + dy * dy)
    attached = sum(1 for block in world.robot_attached.tolist() if block >= 0)
    return -100.0 * total / (cfg.total_value * math.hypot(cfg.arena_width, cfg.arena_height)) \
        + cfg.attach_reward * attached


def mixed_actions(policy: WanderTeam, obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The explorer's wheels with random wheels for a third of the robots (moves blocks, varied)."""
    wheels = policy.act(obs)
    noisy = rng.random(len(wheels)) < 0.33
    wheels[noisy] = rng.uniform(-1.5, 1.5, (noisy.sum(), 2))
    return wheels


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("attach_reward", [0.0, 2.5])
def test_shaped_return_is_task_return_plus_potential_difference(kernel, attach_reward):
    """With gamma = 1: sum of shaped rewards = task return + Phi(end) - Phi(start)."""
    cfg = WorldConfig.from_kwargs(environment=1, num_robots=12, max_cycles=400, kernel=kernel,
                                  reward="shaped", attach_reward=attach_reward)
    moved = attachments_seen = released = 0
    for seed in (0, 14):            # seed 14: a robot carries a block into the zone and is released
        sim = GatheringSimulation(cfg)
        obs = sim.reset(seed=seed)
        rng, policy = np.random.default_rng(seed), WanderTeam(seed=seed)
        phi_start, value_start = hand_potential(cfg, sim.world), sim.gathered_value
        shaped = 0.0
        while not sim.done:
            before = sim.world.robot_attached.copy()
            obs, reward, _, _ = sim.step(mixed_actions(policy, obs, rng))
            shaped += reward
            attachments_seen += int(((before < 0) & (sim.world.robot_attached >= 0)).sum())
            released += int(((before >= 0) & (sim.world.robot_attached < 0)).sum())
        task_return = 100.0 * (sim.gathered_value - value_start) / cfg.total_value
        phi_end = hand_potential(cfg, sim.world)
        assert shaped == pytest.approx(task_return + phi_end - phi_start, abs=1e-9)
        moved += abs(phi_end - phi_start) > 1e-3
    assert moved and attachments_seen and released   # the episodes moved blocks, attached and released robots


def local_reference(cfg: WorldConfig, task: float, phi_before: np.ndarray, phi_after: np.ndarray,
                    attached_before: np.ndarray, attached_after: np.ndarray) -> np.ndarray:
    """Per-robot local rewards, robot by robot and block by block (the docs' rule)."""
    n = len(attached_before)
    rewards = [task / n] * n
    for b in range(len(phi_before)):
        change = phi_after[b] - phi_before[b] if cfg.reward == "shaped" else 0.0
        holders = [i for i in range(n) if attached_before[i] == b]
        for i in holders or range(n):
            rewards[i] += change / len(holders or range(n))
    for i in range(n):
        if cfg.reward == "shaped" and attached_before[i] < 0 <= attached_after[i]:
            rewards[i] += cfg.attach_reward       # attached: earns the bonus
        if cfg.reward == "shaped" and attached_after[i] < 0 <= attached_before[i]:
            rewards[i] -= cfg.attach_reward       # released: gives it back
    return np.array(rewards)


def block_terms(cfg: WorldConfig, world) -> np.ndarray:
    x0, y0, x1, y1 = cfg.zone_rect
    terms = []
    for (x, y), half, value in zip(world.block_pos.tolist(), world.block_half.tolist(), world.block_value.tolist()):
        dx = max(x0 + half - x, 0.0, x - (x1 - half))
        dy = max(y0 + half - y, 0.0, y - (y1 - half))
        terms.append(-100.0 * value * math.hypot(dx, dy) / (cfg.total_value * math.hypot(cfg.arena_width, cfg.arena_height)))
    return np.array(terms)


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("reward", ["shaped", "task"])
def test_local_rewards_sum_to_team_reward_and_follow_the_rule(kernel, reward):
    local = WorldConfig.from_kwargs(environment=1, num_robots=10, max_cycles=300, kernel=kernel,
                                    reward=reward, reward_scope="local")
    team = WorldConfig.from_kwargs(environment=1, num_robots=10, max_cycles=300, kernel=kernel, reward=reward)
    sims = [GatheringSimulation(local), GatheringSimulation(team)]
    obs = [s.reset(seed=9) for s in sims][0]
    rng, policy = np.random.default_rng(9), WanderTeam(seed=9)
    held = gathered = 0
    while not sims[0].done:
        wheels = mixed_actions(policy, obs, rng)
        phi_before, attached_before = block_terms(local, sims[0].world), sims[0].world.robot_attached.copy()
        gathered_before = sims[0].gathered_value
        obs, local_team, _, _ = sims[0].step(wheels.copy())
        _, team_reward, _, _ = sims[1].step(wheels.copy())
        robot = sims[0].robot_reward
        assert local_team == team_reward                              # the scope does not change the team reward
        assert robot.sum() == pytest.approx(team_reward, abs=1e-9)    # local rewards sum to it
        np.testing.assert_array_equal(sims[1].robot_reward, np.full(10, team_reward))   # team: everyone gets it
        task = 100.0 * (sims[0].gathered_value - gathered_before) / local.total_value
        expected = local_reference(local, task, phi_before, block_terms(local, sims[0].world), attached_before,
                                   sims[0].world.robot_attached)
        np.testing.assert_allclose(robot, expected, atol=1e-9)
        held += int((attached_before >= 0).any())
        gathered += task > 0
    assert held and gathered   # some steps had robots holding blocks, one gathered a block


@pytest.mark.parametrize("kernel", KERNELS)
def test_hand_scene_two_robots_push_a_medium_block(kernel):
    """Two robots attach to a medium block: each gets the bonus, then half the block's shaping term."""
    cfg = WorldConfig.from_kwargs(environment=None, block_counts=(0, 1, 0), num_robots=3, max_cycles=100,
                                  kernel=kernel, reward="shaped", reward_scope="local", attach_reward=0.5)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=1)
    world = sim.world
    world.place_block(0, 20.0, 20.0, 0.0)
    half, r = world.block_half[0], cfg.robot_radius
    for robot, dx in ((0, -0.15), (1, 0.15)):          # north of the block, facing south, within the box
        world.place_robot(robot, 20.0 + dx, 20.0 + half + r + 0.05, -math.pi / 2)
    world.place_robot(2, 5.0, 35.0, math.pi)           # far away
    phi0 = hand_potential(cfg, world)
    sim.step(np.zeros((3, 2)))
    assert world.robot_attached.tolist() == [0, 0, -1]
    first = sim.robot_reward
    change = hand_potential(cfg, world) - phi0 - 2 * 0.5      # the block's distance term
    np.testing.assert_allclose(first, [0.5 + change / 3, 0.5 + change / 3, change / 3], atol=1e-12)
    for _ in range(20):                                # attached robots drive the block to the zone
        phi = hand_potential(cfg, world)
        sim.step(np.zeros((3, 2)))
        change = hand_potential(cfg, world) - phi
        np.testing.assert_allclose(sim.robot_reward, [change / 2, change / 2, 0.0], atol=1e-12)
    assert hand_potential(cfg, world) > phi0 + 1.0 + 1e-3    # the block came nearer the zone
    # Phi's scale: value 2 at distance d from the zone, total value 2, 40 x 40 arena, nobody attached
    assert phi0 == pytest.approx(-100 * 2 * (20.0 - (8.0 - half)) / (2 * math.hypot(40, 40)))


@pytest.mark.parametrize("kernel", KERNELS)
def test_reward_options_leave_the_episode_unchanged(kernel):
    """Same seed and actions: identical observations and ft with every reward option."""
    finals = []
    for options in ({}, {"reward": "shaped"}, {"reward": "shaped", "reward_scope": "local", "attach_reward": 3.0}):
        sims = VectorSimulation(2, environment=1, num_robots=8, max_cycles=150, kernel=kernel, **options)
        obs = sims.reset([5, 6])
        policy, trace = WanderTeam(seed=5), []
        while sims.active.any():
            obs, *_ = sims.step(policy.act(obs.reshape(-1, 6)).reshape(2, 8, 2))
            trace.append(obs)
        finals.append((np.stack(trace), sims.task_performance()))
    for trace, ft in finals[1:]:
        np.testing.assert_array_equal(trace, finals[0][0])
        np.testing.assert_array_equal(ft, finals[0][1])


def test_vector_robot_rewards_match_single_world_runs():
    options = dict(environment=1, num_robots=6, max_cycles=120, reward="shaped", reward_scope="local")
    sims = VectorSimulation(2, **options)
    obs = sims.reset([7, 8])
    single = [GatheringSimulation(WorldConfig.from_kwargs(**options)) for _ in range(2)]
    single_obs = [s.reset(seed=k) for s, k in zip(single, (7, 8))]
    rng = np.random.default_rng(0)
    while sims.active.any():
        wheels = rng.uniform(-1, 1, (2, 6, 2))
        obs, reward, _, _ = sims.step(wheels)
        for w in range(2):
            single_obs[w], r, _, _ = single[w].step(wheels[w])
            assert reward[w] == r
            np.testing.assert_array_equal(sims.robot_rewards()[w], single[w].robot_reward)


def test_pettingzoo_local_rewards_per_agent():
    env = parallel_env(environment=1, num_robots=10, max_cycles=300, reward="shaped", reward_scope="local")
    observations, _ = env.reset(seed=9)
    rng, policy, total = np.random.default_rng(9), WanderTeam(seed=9), dict.fromkeys(env.possible_agents, 0.0)
    while env.agents:
        wheels = mixed_actions(policy, np.stack([observations[a] for a in env.possible_agents]), rng)
        observations, rewards, *_ = env.step({a: wheels[i] for i, a in enumerate(env.possible_agents)})
        assert sum(rewards.values()) == pytest.approx(env.sim.reward, abs=1e-9)
        np.testing.assert_array_equal(list(rewards.values()), env.sim.robot_reward)
        for a, r in rewards.items():
            total[a] += r
    assert len(set(np.round(list(total.values()), 9))) > 1     # robots were credited differently


@pytest.mark.parametrize(("option", "value", "message"), [
    ("reward", "dense", r"reward='dense'; allowed: 'task', 'shaped'"),
    ("reward_scope", "global", r"reward_scope='global'; allowed: 'team', 'local'"),
    ("attach_reward", -1.0, r"attach_reward=-1.0 out of range; allowed: \[0.0, inf\]"),
    ("attach_reward", "big", r"attach_reward='big' must be a number"),
])
def test_bad_reward_options_are_value_errors(option, value, message):
    with pytest.raises(ValueError, match=message):
        WorldConfig.from_kwargs(**{option: value})
    with pytest.raises(ValueError, match=message):
        parallel_env(**{option: value})
    with pytest.raises(ValueError, match=message):
        VectorSimulation(2, **{option: value})


def test_pettingzoo_api_test_with_local_shaped_rewards():
    from pettingzoo.test import parallel_api_test

    parallel_api_test(parallel_env(environment=1, num_robots=4, max_cycles=60, reward="shaped",
                                   reward_scope="local"), num_cycles=80)


def test_local_credit_of_blocks_nobody_holds_is_shared_by_everyone():
    """RewardShaper by hand, two worlds of four robots and three blocks. World 0: robots 0 and
    1 hold block 0, robot 3 holds block 2 and lets go, robot 2 attaches to block 1, which nobody
    held at the start of the step. Each block moves 0.5, 0.3 or
    0.1 towards the zone. The documented split: a held block's potential change to its holders
    at the start of the step (equally), a free block's change to all four robots equally, the
    attachment term to the robot that attached or let go, the task reward to all equally.
    World 1: robot 1 holds block 2 throughout, blocks 0 and 1 are free."""
    from gathering_env.rewards import RewardShaper

    cfg = WorldConfig.from_kwargs(environment=None, block_counts=(3, 0, 0), num_robots=4, reward="shaped",
                                  reward_scope="local", attach_reward=0.5)
    half, value = np.full(3, 0.25), np.ones(3)
    x0, y0, x1, y1 = cfg.zone_rect
    start = np.array([[x0 + 2.0, y1 + 3.0], [x0 + 4.0, y1 + 2.0], [x0 + 6.0, y1 + 1.0]])
    step = np.array([0.5, 0.3, 0.1])
    end = start - np.stack([np.zeros(3), step], axis=1)              # straight south, towards the zone
    before = np.array([[0, 0, -1, 2], [-1, 2, -1, -1]])
    after = np.array([[0, 0, 1, -1], [-1, 2, -1, -1]])
    shaper = RewardShaper(cfg, half, value)
    shaper.before(np.stack([start, start]), before)
    task = np.array([4.0, 0.0])
    team, robot = shaper.after(task, np.stack([end, end]), after)

    # Phi's distance term of a block above the zone: -100 * value * (y - (y1 - half)) / (V * diagonal)
    scale = 100.0 / (cfg.total_value * math.hypot(cfg.arena_width, cfg.arena_height))
    change = scale * step                                             # each block's gain in potential
    expected = np.full((2, 4), 0.0)
    expected[:, :] += task[:, None] / 4
    expected[0, [0, 1]] += change[0] / 2                              # block 0: its two holders
    expected[0, 3] += change[2]                                       # block 2: robot 3 held it at the start
    expected[0, :] += change[1] / 4                                   # block 1: nobody held it -> everyone
    expected[0, 2] += 0.5                                             # robot 2 attached
    expected[0, 3] -= 0.5                                             # robot 3 let go
    expected[1, 1] += change[2]                                       # world 1: robot 1 holds block 2,
    expected[1, :] += (change[0] + change[1]) / 4                     # blocks 0 and 1 are free
    np.testing.assert_allclose(robot, expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(team, task + change.sum(), rtol=0, atol=1e-12)
    np.testing.assert_allclose(robot.sum(axis=1), team, rtol=0, atol=1e-12)
