"""The force drive (the original code's robot) against hand computations and the original's figures.

Hand figures: m = 0.7, dt = 0.1, a wheel pushes 2.5 at command 1, the robot's kinetic ground
friction removes 0.2 * 0.7 * 9.81 * 0.1 / 0.7 = 0.1962 units/s a step, the traction impulse
80 % of the forward velocity, and damping 0.1 keeps k = 1 / 1.01 of the velocity a step. So
a robot heading north at full drive goes v' = k (0.2 v + 0.7143) - 0.1962 a step.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gathering_env.config import WorldConfig
from gathering_env.drive import force_drive, wheel_force
from gathering_env.simulation import GatheringSimulation

FORCE = dict(drive_model="force", damping=0.1)
K = 1.0 / 1.01
FRICTION = 0.2 * 9.81 * 0.1          # the speed the robot's kinetic friction removes a step
PUSH = 2 * 2.5 * 0.1 / 0.7           # the speed both wheels at full drive and torque add a step


def lone_robot(heading: float, **overrides) -> GatheringSimulation:
    cfg = WorldConfig.from_kwargs(environment=None, block_counts=(1, 0, 0), num_robots=1,
                                  pickup_heuristic=False, max_cycles=100_000, **overrides)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=3)
    sim.world.place_block(0, 35.0, 35.0, 0.0)
    sim.world.place_robot(0, 5.0, 5.0, heading)
    return sim


def step_speeds(sim: GatheringSimulation, wheels, steps: int) -> list[float]:
    """Distance moved each step / dt."""
    w, out = sim.world, []
    for _ in range(steps):
        before = w.robot_pos[0].copy()
        sim.step(np.array([wheels], dtype=float))
        out.append(float(np.hypot(*(w.robot_pos[0] - before))) / sim.config.dt)
    return out


def test_wheel_force_fades_with_world_x_speed_and_is_full_against_the_motion():
    command = np.array([1.0, 1.0, 1.0, 1.0, -1.0, 0.5, 0.0])
    vx = np.array([0.0, 0.1, 0.35, 0.6, -0.35, -0.35, 0.3])
    np.testing.assert_allclose(wheel_force(command, vx), [2.5, 2.5, 1.25, 0.0, -1.25, 1.25, 0.0])


def test_force_drive_from_rest_and_in_motion_by_hand():
    cfg = WorldConfig.from_kwargs(1, drive_model="force")     # no damping: keep = 1
    heading = np.array([math.pi / 2, 0.0])
    vel = np.array([[0.0, 0.0, 0.0], [0.1, 0.3, 2.0]])
    got = force_drive(np.array([[1.0, 1.0], [0.2, 1.0]]), heading, vel, cfg)
    # robot 0: both wheels full, force 5 north, no torque
    np.testing.assert_allclose(got[0], [0.0, 5.0, 0.0], atol=1e-12)
    # robot 1 heading east at vx = 0.1 (full torque): wheels 0.5 and 2.5; forward momentum
    # 0.07, 80 % of it removed in the step; torque 0.1125 * 2 plus 8 % of the spin removed
    push = (0.1 * 3.0 - 0.8 * 0.07) / 0.1
    moment = 0.5 * 0.7 * 0.15 ** 2
    torque = moment * ((0.92 * 2.0 + 0.1 * 0.1125 * 2.0 / moment) - 2.0) / 0.1
    np.testing.assert_allclose(got[1], [push, 0.0, torque], rtol=1e-12)


@pytest.mark.usefixtures("both_kernels")
def test_free_robot_heading_north_reaches_the_hand_fixed_point_and_the_originals_speed():
    steady = (K * PUSH - FRICTION) / (1 - 0.2 * K)                # 0.6372; the original: 0.637
    assert step_speeds(lone_robot(math.pi / 2, **FORCE), (1, 1), 60)[-1] == pytest.approx(steady, rel=1e-3)
    half = (K * PUSH / 2 - FRICTION) / (1 - 0.2 * K)             # 0.1963; the original: 0.196
    assert step_speeds(lone_robot(math.pi / 2, **FORCE), (0.5, 0.5), 60)[-1] == pytest.approx(half, rel=1e-3)
    assert steady == pytest.approx(0.637, abs=1e-3) and half == pytest.approx(0.196, abs=1e-3)


@pytest.mark.usefixtures("both_kernels")
def test_heading_east_the_torque_fade_makes_the_robot_stop_and_go():
    # From rest: k * 0.7143 - 0.1962 = 0.511 > 0.5, so the next step the wheels push nothing
    # and friction stops it; the mean, 0.2555, is the original's 0.256.
    speeds = step_speeds(lone_robot(0.0, **FORCE), (1, 1), 40)
    go = K * PUSH - FRICTION
    np.testing.assert_allclose(speeds[-4:], [go, 0.0, go, 0.0] if speeds[-1] == 0.0 else [0.0, go, 0.0, go],
                               atol=1e-9)
    assert np.mean(speeds[-20:]) == pytest.approx(0.256, abs=1e-3)


@pytest.mark.usefixtures("both_kernels")
def test_sideways_only_friction_holds_the_robot_and_spin_is_capped():
    sim = lone_robot(math.pi / 2, **FORCE)
    sim.world.robot_bodies[0].velocity = (0.5, 0.0)            # sideways for a robot facing north
    sim.world.read_state()
    speeds = step_speeds(sim, (0, 0), 4)
    # the first step moves with the velocity set; then k v - 0.1962 a step, to rest
    second = K * 0.5 - FRICTION
    np.testing.assert_allclose(speeds, [0.5, second, K * second - FRICTION, 0.0], atol=1e-9)
    velocity = lone_robot(math.pi / 2)             # the velocity drive brakes with its drive force
    velocity.world.robot_bodies[0].velocity = (0.5, 0.0)
    velocity.world.read_state()
    brake = velocity.config.robot_drive_force / 0.7 * 0.1
    np.testing.assert_allclose(step_speeds(velocity, (0, 0), 3), [0.5, 0.5 - brake, 0.5 - 2 * brake],
                               atol=1e-9)
    spin = lone_robot(0.0, **FORCE)
    for _ in range(20):
        spin.step(np.array([[-1.0, 1.0]]))
    assert spin.world.raw[spin.world._robot_rows[0], 5] == pytest.approx(0.5 * math.pi / 0.1)  # the original: 15.7
    spin = lone_robot(0.0, **FORCE)
    for _ in range(20):
        spin.step(np.array([[0.0, 1.0]]))                        # torque 0.28 < friction 0.41: no turn
    assert abs(spin.world.raw[spin.world._robot_rows[0], 5]) < 1e-9


def test_the_velocity_drive_fields_cannot_be_mixed_with_the_force_drive():
    with pytest.raises(ValueError, match=r"drive_dead_band=0.28 with drive_model='force'.*allowed: 0"):
        WorldConfig.from_kwargs(1, drive_model="force", drive_dead_band=0.28)
    with pytest.raises(ValueError, match=r"drive_model='wheels'; allowed: 'velocity', 'force'"):
        WorldConfig.from_kwargs(1, drive_model="wheels")
    with pytest.raises(ValueError, match=r"damping=-1"):
        WorldConfig.from_kwargs(1, damping=-1)


@pytest.mark.usefixtures("both_kernels")
def test_damping_shrinks_a_sliding_blocks_speed_as_box2d_does():
    cfg = dict(ground_friction="threshold", robot_drive_force=1e-9, damping=0.1)   # no ground friction
    sim = lone_robot(0.0, **cfg)
    body = sim.world.block_bodies[0]
    body.velocity = (0.0, -0.5)
    sim.world.read_state()
    for _ in range(10):
        sim.step(np.zeros((1, 2)))
    assert body.velocity.length == pytest.approx(0.5 * K ** 10, rel=1e-6)


class _Keys:
    """A stand-in generator whose ``random(n)`` hands out fixed draws, in order."""

    def __init__(self, *draws):
        self.draws = [np.array(d, dtype=float) for d in draws]

    def random(self, n):
        out = self.draws.pop(0)
        assert out.shape == (n,)
        return out


def test_shuffled_times_count_the_actions_before_this_step_and_after_the_last_one():
    from gathering_env.drive import shuffled_times

    # three robots, the physics step's draw last: step 1 robots 0, 2 before it (0.1, 0.3 < 0.5)
    keys = _Keys([0.1, 0.9, 0.3, 0.5], [0.8, 0.2, 0.6, 0.7], [0.4, 0.45, 0.99, 0.0])
    after = np.zeros(3, dtype=bool)
    times, after = shuffled_times(keys, after)
    assert times.tolist() == [1, 0, 1] and after.tolist() == [False, True, False]
    times, after = shuffled_times(keys, after)      # robot 1 before (0.2 < 0.7), and after last time
    assert times.tolist() == [0, 2, 1] and after.tolist() == [True, False, False]
    times, after = shuffled_times(keys, after)      # the physics step first: nobody before it
    assert times.tolist() == [1, 0, 0] and after.tolist() == [True, True, True]


def test_shuffled_times_average_one_action_a_step():
    from gathering_env.drive import shuffled_times

    rng, after, total, seen = np.random.default_rng(5), np.zeros(20, dtype=bool), 0, set()
    for _ in range(2000):
        times, after = shuffled_times(rng, after)
        total += times.sum()
        seen.update(times.tolist())
    # every action reaches exactly one physics step: the mean is 1 up to the last after-action
    assert seen == {0, 1, 2} and abs(total - 2000 * 20) <= 20


def test_force_drive_acting_twice_reads_the_velocity_the_first_impulse_left():
    cfg = WorldConfig.from_kwargs(1, drive_model="force")     # no damping: keep = 1
    heading = np.full(3, math.pi / 2)
    vel = np.array([[0.0, 0.5, 1.0]] * 3)
    got = force_drive(np.ones((3, 2)), heading, vel, cfg, times=np.array([0, 1, 2]))
    moment = 0.5 * 0.7 * 0.15 ** 2
    # no action: no push; the torque only holds the spin where it is (below the cap)
    np.testing.assert_allclose(got[0], [0.0, 0.0, 0.0], atol=1e-12)
    # once: forward momentum 0.35, 0.28 of it removed; spin kept at 92 %
    np.testing.assert_allclose(got[1], [0.0, (0.1 * 5.0 - 0.28) / 0.1, moment * (0.92 - 1.0) / 0.1],
                               atol=1e-12)
    # twice: the second impulse finds 0.5 - 0.28 / 0.7 = 0.1 units/s, and removes 0.8 * 0.07
    np.testing.assert_allclose(got[2], [0.0, (0.1 * 10.0 - 0.28 - 0.056) / 0.1,
                                        moment * (0.92 ** 2 - 1.0) / 0.1], atol=1e-12)
    # the default is one action each, bit for bit
    assert np.array_equal(force_drive(np.ones((3, 2)), heading, vel, cfg), got[[1, 1, 1]])


def test_the_shuffled_schedule_is_refused_without_the_force_drive_and_unknown_names_too():
    with pytest.raises(ValueError, match="schedule='shuffled' with drive_model='velocity'"):
        WorldConfig.from_kwargs(1, schedule="shuffled")
    with pytest.raises(ValueError, match="schedule='mason'; allowed: 'fixed', 'shuffled'"):
        WorldConfig.from_kwargs(1, drive_model="force", schedule="mason")
    for bad in (-1, 2.5, True, "3"):
        with pytest.raises(ValueError, match="layout_seed="):
            WorldConfig.from_kwargs(1, layout_seed=bad)


@pytest.mark.usefixtures("both_kernels")
def test_a_shuffled_free_robot_runs_faster_as_the_originals_did_and_its_seed_repeats_it():
    # the original on its own classes under MASON's shuffle: 0.838 units/s (fixed order 0.637)
    speeds = [np.mean(step_speeds(lone_robot(math.pi / 2, schedule="shuffled", **FORCE), (1, 1), 300)[-100:])
              for _ in range(2)]
    assert speeds[0] == speeds[1]                      # one seed, one schedule
    assert 0.78 < speeds[0] < 0.9


def test_the_shuffled_schedule_leaves_the_layout_of_a_seed_alone():
    fixed, shuffled = (GatheringSimulation(WorldConfig.from_kwargs(2, schedule=s, **FORCE)) for s in ("fixed", "shuffled"))
    assert np.array_equal(fixed.reset(seed=11), shuffled.reset(seed=11))
    assert np.array_equal(fixed.world.raw, shuffled.world.raw)


def test_block_draws_are_the_generators_own_draws_in_order():
    """The world draws its schedule in blocks: across block boundaries the rows are exactly the
    successive ``rng.random(n)`` calls of the same generator."""
    from gathering_env.drive import BlockDraws

    direct = np.random.default_rng(11)
    blocks = BlockDraws(np.random.default_rng(11), 4, rows=3)
    for _ in range(10):                                  # 3 blocks and a part
        np.testing.assert_array_equal(blocks.random(4), direct.random(4))
    with pytest.raises(ValueError, match="n=5; allowed: 4"):
        blocks.random(5)
