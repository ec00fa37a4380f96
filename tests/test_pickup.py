"""Pickup heuristic rules (docs/model.md §2) on hand-placed scenes: box, reach, sticky side, full blocks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gathering_env.config import WorldConfig
from gathering_env.simulation import GatheringSimulation

BLOCK = (20.0, 30.0)  # block centre, far from the zone and the walls


def world(block_type: int, robots: int) -> GatheringSimulation:
    counts = [0, 0, 0]
    counts[block_type] = 1
    cfg = WorldConfig.from_kwargs(environment=None, block_counts=counts, num_robots=robots, max_cycles=1000)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=1)
    sim.world.place_block(0, *BLOCK, 0.0)
    for i in range(robots):  # park every robot far away, facing west
        sim.world.place_robot(i, 3.0 + 0.5 * i, 36.0, math.pi)
    return sim


def north(sim: GatheringSimulation, robot: int, gap: float, dx: float = 0.0, angle: float = -math.pi / 2) -> None:
    """Put ``robot`` north of the block, ``gap`` between its rim and the block's north face."""
    half, r = sim.world.block_half[0], sim.config.robot_radius
    sim.world.place_robot(robot, BLOCK[0] + dx, BLOCK[1] + half + r + gap, angle)


def step(sim: GatheringSimulation) -> np.ndarray:
    sim.step(np.zeros((sim.config.num_robots, 2)))
    return sim.world.robot_attached.copy()


def test_pickup_box_depth_and_facing():
    cfg = WorldConfig()
    assert (cfg.pickup_box_width, cfg.pickup_box_depth) == (0.1, 0.2)   # docs/model.md §2: 0.1 wide x 0.2 deep
    near = world(0, 1)
    north(near, 0, gap=0.15)                  # face within the 0.2-deep box
    assert step(near)[0] == 0
    far = world(0, 1)
    north(far, 0, gap=0.3)                    # beyond the box
    assert step(far)[0] == -1
    back = world(0, 1)
    north(back, 0, gap=0.05, angle=math.pi / 2)  # touching, but facing away
    assert step(back)[0] == -1


def test_pickup_box_width():
    # Facing south beside the block: the box (0.05 either side of the heading line) misses it.
    half = world(0, 1).world.block_half[0]
    beside = world(0, 1)
    north(beside, 0, gap=0.05, dx=half + 0.08)
    assert step(beside)[0] == -1
    inside = world(0, 1)
    north(inside, 0, gap=0.05, dx=half + 0.02)
    assert step(inside)[0] == 0


def test_reach_to_an_anchor():
    # A large block (3 anchors per side at -2/3, 0, 2/3 of the half side); try_attach alone.
    sim = world(2, 1)
    w, r = sim.world, sim.config.robot_radius
    half = w.block_half[0]
    reach = sim.config.pickup_reach * r                     # 2.5 robot radii
    # The robot's front straight north of the north side's last anchor, just beyond / within reach.
    anchor = (BLOCK[0] + 2.0 / 3.0 * half, BLOCK[1] + half)
    w.place_robot(0, anchor[0], anchor[1] + reach + 0.02 + r, -math.pi / 2)
    assert not w.try_attach(0, 0)
    w.place_robot(0, anchor[0], anchor[1] + reach - 0.02 + r, -math.pi / 2)
    assert w.try_attach(0, 0)


def test_sticky_side():
    sim = world(2, 3)                          # a large block needs 3 robots
    north(sim, 0, gap=0.05)
    assert step(sim)[0] == 0
    assert sim.world.block_sticky_side[0] >= 0
    half, r = sim.world.block_half[0], sim.config.robot_radius
    # A robot touching the south face, facing north: its nearest anchor is on the south side,
    # more than the reach away from every north anchor -> refused.
    sim.world.place_robot(1, BLOCK[0], BLOCK[1] - half - r - 0.05, math.pi / 2)
    attached = step(sim)
    assert attached[1] == -1
    # A second robot on the sticky (north) side is accepted.
    north(sim, 2, gap=0.05, dx=2.0 / 3.0 * half)
    assert step(sim)[2] == 0


@pytest.mark.parametrize("block_type", [0, 1])
def test_a_full_block_refuses_more_robots(block_type):
    need = block_type + 1
    sim = world(block_type, need + 1)
    half = sim.world.block_half[0]
    offsets = ((np.arange(need) + 0.5) / need * 2 - 1) * half     # the side's anchor points
    for i in range(need):
        north(sim, i, gap=0.05, dx=float(offsets[i]))
    attached = step(sim)
    assert (attached[:need] == 0).all()
    north(sim, need, gap=0.05, dx=0.0)         # one more robot at the full block's sticky side
    assert step(sim)[need] == -1
    assert (sim.world.anchor_owner[0, :need] >= 0).all()


# Heading error e (the zone centre's bearing from the robot's heading) -> (left, right) wheels, worked
# by hand: 'original' from the 2018 code's Heuristic.wheelDriveForTargetAngle quadrant by quadrant
# (outer wheel +-1, inner (pi/2 - |e|) / (pi/2) forwards, backwards from +90 degrees, forwards at
# -90), 'sharp' from t = clip(4 e' / pi) and (d - t, d + t) scaled to a largest wheel of 1.
STEERING = [
    (math.pi / 6, (2 / 3, 1.0), (0.2, 1.0)),                 # ahead, to the left
    (-math.pi / 3, (1.0, 1 / 3), (1.0, 0.0)),                # ahead, to the right
    (2 * math.pi / 3, (-1 / 3, -1.0), (0.0, -1.0)),          # behind, to the left: backwards
    (-5 * math.pi / 6, (-1.0, -2 / 3), (-1.0, -0.2)),        # behind, to the right
    (math.pi / 2, (0.0, -1.0), (0.0, 1.0)),                  # +90 degrees: the original reverses
    (-math.pi / 2, (1.0, 0.0), (1.0, 0.0)),                  # -90 degrees: both go forwards
    (0.0, (1.0, 1.0), (1.0, 1.0)),
]


@pytest.mark.parametrize("steering", ["original", "sharp"])
@pytest.mark.parametrize("error, original, sharp", STEERING)
def test_attached_steering_by_hand(steering, error, original, sharp):
    """A welded robot's wheels (``WorldConfig.attached_steering``) at hand-picked heading errors
    (the numpy reference; tests/test_kernels.py holds the compiled kernel to it over episodes)."""
    from gathering_env.reference.heuristics import attached_wheels

    cfg = WorldConfig.from_kwargs(environment=None, block_counts=(1, 0, 0), num_robots=1,
                                  attached_steering=steering)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=1)
    cx, cy = cfg.zone_centre
    # 10 units north of the zone centre, its bearing is -pi/2; heading -pi/2 - e makes the error e
    sim.world.place_robot(0, cx, cy + 10.0, -math.pi / 2 - error)
    want = original if steering == "original" else sharp
    got = attached_wheels(sim.world, np.array([0]))[0]
    np.testing.assert_allclose(got, want, atol=1e-12)


ORIGINAL_ROBOT = dict(environment=None, num_robots=1, block_counts=(1, 0, 0), zone_depth=4.0, ground_friction="mass",
                      robot_restitution=1.0, block_restitution=0.4, wall_restitution=1.0, drive_model="force",
                      damping=0.1, attached_steering="original")


def carry(kernel: str, weld_spin: str, block: tuple[float, float] = (5.0, 10.0), steps: int = 1500):
    """One robot welded to the west side of a small block, steered by the heuristic: (steps until
    the block lies in the zone or the limit, block x, block y, robot heading at the end)."""
    cfg = WorldConfig.from_kwargs(**ORIGINAL_ROBOT, kernel=kernel, weld_spin=weld_spin, max_cycles=steps + 10)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=1)
    w = sim.world
    w.place_block(0, *block, 0.0)
    w.place_robot(0, block[0] - w.block_half[0] - cfg.robot_radius - 0.02, block[1], 0.0)
    assert w.try_attach(0, 0)
    taken = 0
    while taken < steps and sim.task_performance() == 0:
        sim.step(np.zeros((1, 2)))
        taken += 1
    return taken, float(w.block_pos[0, 0]), float(w.block_pos[0, 1]), float(w.robot_angle[0])


@pytest.mark.parametrize("kernel", ["numpy", "compiled"])
def test_a_welded_pair_turns_only_with_weld_spin_free(kernel):
    """The zone centre lies 27.5 degrees to the right of a welded robot's heading. The original's
    own classes (measured with its RobotObject, ResourceObject and Box2D world, fixed order)
    arc the block into the zone in 943 steps (its friction joint takes only a share of the robot's spin). Held by that
    torque, ours drives straight on east, never turning; with weld_spin = "free" it arcs right and
    gathers the block (in 766 steps), the same on both kernels."""
    steps, x, y, heading = carry(kernel, "held")
    assert steps == 1500 and y == pytest.approx(10.0, abs=1e-6) and abs(heading) < 1e-6 and x > 15
    steps, x, y, heading = carry(kernel, "free")
    assert steps < 1000 and y < 4.0 and heading < -0.5
    assert (steps, x, y) == carry("compiled" if kernel == "numpy" else "numpy", "free")[:3]


def test_weld_spin_free_lets_go_of_the_friction_torque_only_while_welded():
    from gathering_env.drive import control_limits

    cfg = WorldConfig.from_kwargs(**ORIGINAL_ROBOT, weld_spin="free")
    sim = GatheringSimulation(cfg)
    sim.reset(seed=1)
    w = sim.world
    torque = control_limits(cfg)[1]
    assert torque > 0 and w.control_gears[0].max_force == torque
    w.place_block(0, 5.0, 10.0, 0.0)
    w.place_robot(0, 5.0 - w.block_half[0] - cfg.robot_radius - 0.02, 10.0, 0.0)
    assert w.try_attach(0, 0) and w.control_gears[0].max_force == 0.0
    w.detach_block(0)
    assert w.robot_attached[0] == -1 and w.control_gears[0].max_force == torque
