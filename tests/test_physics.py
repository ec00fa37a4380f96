"""The pymunk world: cooperation requirement, drive kinematics, walls, attachments."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gathering_env.config import WorldConfig
from gathering_env.simulation import GatheringSimulation

pytestmark = pytest.mark.usefixtures("both_kernels")  # every test here runs on both kernels


def one_block_world(block_type: int, robots: int, **overrides) -> GatheringSimulation:
    counts = [0, 0, 0]
    counts[block_type] = 1
    cfg = WorldConfig.from_kwargs(environment=None, block_counts=counts, num_robots=max(robots, 1),
                                  max_cycles=100_000, **overrides)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=1)
    return sim


def push_block(block_type: int, pushers: int, steps: int = 300) -> tuple[int, float]:
    """Place ``pushers`` robots against the north side of a block at (20, 30), facing south
    (towards the zone), let the pickup heuristic attach them and drive. Returns
    (robots attached, block displacement)."""
    sim = one_block_world(block_type, pushers)
    w, cfg = sim.world, sim.config
    w.place_block(0, 20.0, 30.0, 0.0)
    half, r = w.block_half[0], cfg.robot_radius
    k = cfg.robots_needed[block_type]
    offsets = ((np.arange(k) + 0.5) / k * 2 - 1) * half      # the side's anchor points
    for i in range(pushers):
        w.place_robot(i, 20.0 + offsets[i], 30.0 + half + r + 0.01, -math.pi / 2)
    if pushers == 0:
        w.place_robot(0, 5.0, 35.0, 0.0)
    sim.step(np.zeros((cfg.num_robots, 2)))
    attached = int((w.robot_attached >= 0).sum())
    start = w.block_pos[0].copy()
    for _ in range(steps):
        sim.step(np.zeros((cfg.num_robots, 2)))
    return attached, float(np.hypot(*(w.block_pos[0] - start)))


@pytest.mark.parametrize("block_type", [0, 1, 2])
def test_k_minus_one_robots_cannot_move_a_block_that_needs_k(block_type):
    k = block_type + 1
    attached, moved = push_block(block_type, k - 1)
    assert attached == k - 1
    assert moved < 0.01


@pytest.mark.parametrize("block_type", [0, 1, 2])
def test_k_robots_move_the_block(block_type):
    k = block_type + 1
    attached, moved = push_block(block_type, k)
    assert attached == k
    assert moved > 5.0   # 300 steps x 0.1 s at up to 0.5 units/s = 15 units at most


def test_friction_follows_robots_needed():
    # Declaring large blocks as needing 2 robots sets their friction to (2 - 0.5) F: two move it.
    assert push_two_against_large_block(robots_needed=(1, 2, 2)) > 1.0
    assert push_two_against_large_block(robots_needed=(1, 2, 3)) < 0.01


def push_two_against_large_block(robots_needed) -> float:
    sim = one_block_world(2, 2, robots_needed=robots_needed)
    w, cfg = sim.world, sim.config
    w.place_block(0, 20.0, 30.0, 0.0)
    half, r = w.block_half[0], cfg.robot_radius
    for i, dx in enumerate((-half / 3, half / 3)):
        w.place_robot(i, 20.0 + dx, 30.0 + half + r + 0.01, -math.pi / 2)
    start = w.block_pos[0].copy()
    for _ in range(300):
        sim.step(np.zeros((2, 2)))
    return float(np.hypot(*(w.block_pos[0] - start)))


def test_free_robot_drives_forward_at_top_speed():
    sim = one_block_world(0, 1, pickup_heuristic=False)
    w = sim.world
    w.place_block(0, 5.0, 35.0, 0.0)
    w.place_robot(0, 20.0, 20.0, 0.3)
    for _ in range(20):
        sim.step(np.array([[1.0, 1.0]]))
    start = w.robot_pos[0].copy()
    for _ in range(50):                  # 5 s at 0.5 units/s = 2.5 units
        sim.step(np.array([[1.0, 1.0]]))
    moved = w.robot_pos[0] - start
    assert np.hypot(*moved) == pytest.approx(2.5, rel=0.02)
    assert math.atan2(moved[1], moved[0]) == pytest.approx(0.3, abs=0.01)   # along the heading


def test_spin_on_the_spot_and_no_side_slip():
    sim = one_block_world(0, 1, pickup_heuristic=False)
    w = sim.world
    w.place_block(0, 5.0, 35.0, 0.0)
    w.place_robot(0, 20.0, 20.0, 0.0)
    for _ in range(10):
        sim.step(np.array([[1.0, -1.0]]))  # left forward, right back: clockwise
    assert w.robot_angle[0] < -1.0         # omega = 2 * 0.5 / 0.3 = 3.33 rad/s, ramp-up included
    assert np.hypot(*(w.robot_pos[0] - [20.0, 20.0])) < 0.02
    # Driving an arc, the velocity stays along the heading: no side-slip.
    w.place_robot(0, 20.0, 20.0, 0.0)
    for step in range(60):
        before = w.robot_angle[0]
        sim.step(np.array([[1.0, 0.4]]))
        v = w.robot_bodies[0].velocity
        a = 0.5 * (before + w.robot_angle[0])         # the heading during the step
        lateral = -v.x * math.sin(a) + v.y * math.cos(a)
        if step >= 3:                                 # after the torque-limited ramp-up
            assert abs(lateral) < 0.02 * math.hypot(v.x, v.y) + 1e-6


@settings(max_examples=12, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(["forward", "random", "spin"]), st.sampled_from([1, 2]))
def test_robots_stay_inside_the_arena(seed, policy, substeps):
    cfg = WorldConfig.from_kwargs(environment=3, max_cycles=100_000, physics_substeps=substeps)
    # Discrete contacts: at most one sub-step's travel of overlap with a wall (plus the solver's slop).
    tolerance = cfg.robot_max_speed * cfg.dt / substeps + 0.005
    sim = GatheringSimulation(cfg)
    sim.reset(seed=seed)
    rng = np.random.default_rng(seed)
    r = cfg.robot_radius
    for _ in range(250):
        if policy == "forward":
            wheels = np.ones((20, 2))
        elif policy == "spin":
            wheels = np.tile([1.0, 0.3], (20, 1))
        else:
            wheels = rng.choice([-1.0, 1.0], size=(20, 2))
        obs, *_ = sim.step(wheels)
        pos = sim.world.robot_pos
        assert np.all(pos >= r - tolerance) and np.all(pos <= cfg.arena_width - r + tolerance)
        assert np.isfinite(obs).all()


def test_a_robot_driving_into_a_wall_is_pushed_back_out():
    sim = one_block_world(0, 1, pickup_heuristic=False)
    w = sim.world
    w.place_block(0, 5.0, 5.0, 0.0)
    w.place_robot(0, 20.0, 39.0, math.pi / 2)
    overlaps = []
    for _ in range(60):
        sim.step(np.array([[1.0, 1.0]]))
        overlaps.append(w.robot_pos[0, 1] - (40.0 - 0.15))
    assert max(overlaps) <= 0.05 + 1e-9          # one step of travel at most
    assert overlaps[-1] <= 0.005 + 1e-9          # and settled against the wall (slop)


def test_gathered_block_releases_its_robots():
    attached_before = None
    sim = one_block_world(1, 2)
    w, cfg = sim.world, sim.config
    w.place_block(0, 20.0, 10.5, 0.0)           # just north of the zone (y <= 8)
    half, r = w.block_half[0], cfg.robot_radius
    for i, dx in enumerate((-half / 2, half / 2)):
        w.place_robot(i, 20.0 + dx, 10.5 + half + r + 0.01, -math.pi / 2)
    total_reward = 0.0
    for step in range(400):
        _, reward, terminated, _ = sim.step(np.zeros((2, 2)))
        total_reward += reward
        if step == 0:
            attached_before = int((w.robot_attached >= 0).sum())
        if terminated:
            break
    assert attached_before == 2
    assert terminated and sim.gathered.all()
    assert (w.robot_attached < 0).all()           # released on gathering
    assert total_reward == pytest.approx(100.0)   # the only block: 100 * 2 / 2


@pytest.mark.slow
def test_long_run_has_no_nan():
    cfg = WorldConfig.from_kwargs(environment=2, max_cycles=10_000)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=0)
    rng = np.random.default_rng(0)
    done = False
    while not done:
        obs, _, terminated, truncated = sim.step(rng.uniform(-1, 1, (20, 2)))
        done = terminated or truncated
    assert sim.steps == 10_000 or terminated
    assert np.isfinite(obs).all() and np.isfinite(sim.world.robot_pos).all() and np.isfinite(sim.world.block_pos).all()
    assert np.all((sim.world.robot_pos > 0) & (sim.world.robot_pos < 40))


def test_collision_avoidance_turns_away_from_a_wall():
    def run(avoid: bool) -> tuple[float, float]:
        sim = one_block_world(0, 1, pickup_heuristic=False, collision_avoidance=avoid)
        w = sim.world
        w.place_block(0, 5.0, 5.0, 0.0)
        w.place_robot(0, 20.0, 39.5, math.pi / 2)        # facing the north wall, 0.35 away
        highest = 0.0
        for _ in range(12):
            sim.step(np.array([[1.0, 1.0]]))
            highest = max(highest, w.robot_pos[0, 1])
        return w.robot_angle[0], highest

    angle_off, y_off = run(False)
    angle_on, y_on = run(True)
    assert angle_off == pytest.approx(math.pi / 2, abs=1e-6) and y_off > 39.8   # drives into the wall
    assert abs(angle_on - math.pi / 2) > 0.5 and y_on < 39.8                     # turned away in time


def test_weld_seat_puts_the_robot_on_the_anchor():
    sim = one_block_world(0, 1)                       # the default: the weld seats the robot
    w, cfg = sim.world, sim.config
    assert cfg.weld_seat
    w.place_block(0, 20.0, 30.0, 0.0)
    # Slightly off-centre and skewed, touching the north face (y = 30.2).
    w.place_robot(0, 20.03, 30.2 + cfg.robot_radius + 0.01, -math.pi / 2 + 0.2)
    sim.step(np.zeros((1, 2)))
    assert w.robot_attached[0] == 0 and w.block_sticky_side[0] >= 0
    # Seated: facing south (onto the side's inward normal), its front on the single anchor (20, 30.2).
    assert w.robot_angle[0] == pytest.approx(-math.pi / 2, abs=0.05)
    front = w.robot_pos[0] + cfg.robot_radius * np.array([math.cos(w.robot_angle[0]), math.sin(w.robot_angle[0])])
    np.testing.assert_allclose(front, [20.0, 30.2], atol=0.02)


def test_weld_seat_puts_two_robots_on_their_own_anchors_facing_the_same_way():
    """A medium block (two anchors per side, at -1/2 and +1/2 of its half size): robots that
    grip skewed in different directions end up side by side, both facing the block square."""
    sim = one_block_world(1, 2)
    w, cfg = sim.world, sim.config
    w.place_block(0, 20.0, 30.0, 0.0)
    half = w.block_half[0]
    top = 30.0 + half
    w.place_robot(0, 19.85, top + cfg.robot_radius + 0.01, -math.pi / 2 + 0.35)
    w.place_robot(1, 20.15, top + cfg.robot_radius + 0.01, -math.pi / 2 - 0.3)
    sim.step(np.zeros((2, 2)))
    assert list(w.robot_attached) == [0, 0]
    for robot, x in ((0, 20.0 - half / 2), (1, 20.0 + half / 2)):
        assert w.robot_angle[robot] == pytest.approx(-math.pi / 2, abs=0.05)
        heading = np.array([math.cos(w.robot_angle[robot]), math.sin(w.robot_angle[robot])])
        np.testing.assert_allclose(w.robot_pos[robot] + cfg.robot_radius * heading, [x, top], atol=0.02)


def test_weld_in_place_keeps_the_robots_heading():
    sim = one_block_world(0, 1, weld_seat=False)
    w, cfg = sim.world, sim.config
    w.place_block(0, 20.0, 30.0, 0.0)
    w.place_robot(0, 20.03, 30.2 + cfg.robot_radius + 0.01, -math.pi / 2 + 0.2)
    sim.step(np.zeros((1, 2)))
    assert w.robot_attached[0] == 0
    assert w.robot_angle[0] == pytest.approx(-math.pi / 2 + 0.2, abs=0.02)   # welded skewed, where it stood

