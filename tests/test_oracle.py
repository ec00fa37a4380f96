"""The privileged team (``evolution.policies.oracle``): its assignment, targets and steering
worked by hand on a stand-in world, and whole episodes in real ones."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from evolution.compare import compare
from evolution.policies import make_policy
from evolution.policies.oracle import OracleTeam, steer
from evolution.run.protocol import protocol_values
from gathering_env.config import WorldConfig


def stand_in(robots, blocks, gathered=None):
    """A sim-like record over the default 40 x 40 arena (zone x 10-30, y 0-8, middle line y = 4).
    robots: [(x, y, angle)]; blocks: [(x, y, half, need)]."""
    world = SimpleNamespace(
        robot_pos=np.array([r[:2] for r in robots], dtype=float),
        robot_angle=np.array([r[2] for r in robots], dtype=float),
        block_pos=np.array([b[:2] for b in blocks], dtype=float),
        block_half=np.array([b[2] for b in blocks], dtype=float),
        block_need=np.array([b[3] for b in blocks]),
    )
    gathered = np.zeros(len(blocks), bool) if gathered is None else np.asarray(gathered)
    return SimpleNamespace(world=world, config=WorldConfig.from_kwargs(environment=1), gathered=gathered)


SOUTH = -math.pi / 2


def test_slots_go_to_the_nearest_robots_and_spares_to_the_block_needing_most():
    # block 0 small at (20, 20), block 1 medium at (5, 30); robot 0 1 north of block 0, robot 2
    # 1.41 from block 1, robot 1 3 from it, robot 3 far from both: 3 slots (0; -0.21 and +0.21
    # on block 1) and a spare slot on block 1 (needs most) at offset 0, taken by robot 3
    sim = stand_in([(20, 21, SOUTH), (5, 33, 0.0), (6, 31, 0.0), (30, 30, 0.0)],
                   [(20, 20, 0.2, 1), (5, 30, 0.3, 2)])
    team = OracleTeam()
    team.bind(sim)
    team.act(None)
    assert team.slot_block.tolist() == [0, 1, 1, 1]
    np.testing.assert_allclose(team.slot_offset, [0.0, 0.21, -0.21, 0.0])


def test_a_gathered_block_offers_no_slot_and_robots_without_one_head_for_the_centre():
    # block 0 gathered: both robots on block 1 (one slot, one spare at offset 0)
    sim = stand_in([(20, 21, SOUTH), (5, 33, 0.0)], [(20, 20, 0.2, 1), (5, 30, 0.2, 1)], gathered=[True, False])
    team = OracleTeam()
    team.bind(sim)
    team.act(None)
    assert team.slot_block.tolist() == [1, 1]
    # every block gathered: no slots, both robots head for the arena's centre
    sim.gathered = np.array([True, True])
    team.act(None)
    assert team.slot_block.tolist() == [-1, -1]
    np.testing.assert_allclose(team.targets(), [(20, 20), (20, 20)])


def test_targets_push_round_and_to_the_slot_by_hand():
    # block at (20, 20), goal (20, 4): u = (0, -1), n = (1, 0), h + r = 0.35
    robots = [(20, 21, SOUTH),     # behind it on its line: through the block, c + 2u = (20, 18)
              (20, 19, SOUTH),     # between it and the goal: round it, c + 0.85 n - 0.85 u
              (22, 23, SOUTH),     # behind but 2 off the line: to the slot, c - 0.45 u
              (18.5, 19.9, SOUTH)]  # level with its rear face, on the left: round the other side
    sim = stand_in(robots, [(20, 20, 0.2, 1)])
    team = OracleTeam()
    team.bind(sim)
    team.slot_block, team.slot_offset = np.zeros(4, int), np.zeros(4)
    np.testing.assert_allclose(team.targets(), [(20, 18), (20.85, 20.85), (20, 20.45), (19.15, 20.85)])


def test_a_goal_is_kept_inside_the_zone_and_a_target_inside_the_walls():
    # a block in the south-west corner at (0.3, 0.25): its goal's x is clipped to 10 + 0.2 + 1 =
    # 11.2 (y = 4), so u = (10.9, 3.75) / 11.527 = (0.94560, 0.32532), n = (-0.32532, 0.94560);
    # a robot at (0.25, 3) is ahead of its rear face (a = 0.847) on its left (l = 2.62): round
    # it at c + 0.85 n - 0.85 u = (-0.7803, 0.7772), which the west wall clips to x = 0.2
    sim = stand_in([(0.25, 3.0, 0.0)], [(0.3, 0.25, 0.2, 1)])
    team = OracleTeam()
    team.bind(sim)
    team.slot_block, team.slot_offset = np.zeros(1, int), np.zeros(1)
    np.testing.assert_allclose(team.targets()[0], (0.2, 0.77724), atol=1e-5)


def test_steering_by_hand():
    pos = np.zeros((4, 2))
    target = np.array([(1, 0), (1, 0), (0, 1), (-1, 0.01)], dtype=float)
    angle = np.array([0.0, 0.1, 0.0, 0.0])
    wheels = steer(pos, angle, target)
    # straight ahead: full speed; 0.1 rad to the left of it: the left wheel faster (turn right)
    np.testing.assert_allclose(wheels[:2], [(1, 1), (1, 0.8)])
    # 90 degrees to the left: on the spot, left wheel back; behind, slightly left: the same way
    np.testing.assert_allclose(wheels[2:], [(-1, 1), (-1, 1)])


def test_act_before_bind_names_the_missing_step():
    with pytest.raises(RuntimeError, match=r"bind\(sim\) after each reset"):
        OracleTeam().act(np.zeros((20, 6)))


def test_the_oracle_gathers_every_block_of_a_small_world_and_repeats_itself():
    """A real world (4 robots, 2 small and 1 medium block, compiled kernel) through
    gathering-compare's runner, which binds the policy: every block gathered on each seed, and
    the same seeds give the same episodes."""
    world = dict(environment=None, block_counts=(2, 1, 0), num_robots=4, max_cycles=4000)
    rows = compare([make_policy("oracle")], world, [0, 1, 2])
    again = compare([make_policy("oracle")], world, [0, 1, 2])
    assert rows[0]["finished"] == 3
    assert (rows[0]["small"], rows[0]["medium"]) == (2.0, 1.0)
    assert rows[0]["per_episode"] == again[0]["per_episode"]


def test_the_original_world_lets_a_team_gather_environment_1_within_half_the_steps():
    """The S1 milestone is within the original protocol's physics (docs/evidence.md, "What the
    world allows"): in the newest bundle's world the oracle gathers every block of environment 1
    in under 5 000 of the 10 000 steps (2 layouts; about 3 500 each)."""
    world = {**protocol_values("original")["environment"], "environment": 1}
    row = compare([make_policy("oracle")], world, [0, 1])[0]
    assert row["finished"] == 2
    assert max(e["steps"] for e in row["per_episode"]) < 5000
