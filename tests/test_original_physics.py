"""The original code's physics as world options: mass ground friction and Box2D restitution."""

from __future__ import annotations

import importlib.util
import itertools
import math
import re
from pathlib import Path

import numpy as np
import pytest

from evolution.run.protocol import ORIGINAL_PHYSICS, protocol_values
from gathering_env.config import WorldConfig
from gathering_env.contacts import mixing
from gathering_env.simulation import GatheringSimulation

ORIGINAL_RESTITUTION = {"robot_restitution": 1.0, "block_restitution": 0.4, "wall_restitution": 1.0}
FRICTIONLESS = {"ground_friction": "threshold", "robot_drive_force": 1e-9}
"""Blocks slide freely (threshold friction scales with the drive force)."""


def world(counts, robots=1, **overrides) -> GatheringSimulation:
    cfg = WorldConfig.from_kwargs(environment=None, block_counts=counts, num_robots=robots,
                                  pickup_heuristic=False, max_cycles=100_000, **overrides)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=3)
    return sim


def test_mass_friction_is_the_originals_kinetic_coulomb_friction():
    cfg = WorldConfig.from_kwargs(1, ground_friction="mass", robots_needed=(3, 3, 1))
    for t, mass in enumerate(cfg.block_masses):               # 1, 3, 6 by default
        force, torque = cfg.block_ground_friction(t)
        assert force == pytest.approx(0.1 * mass * 9.81)
        assert torque == pytest.approx(0.01 * mass * 9.81)    # the same for every shape
    default = WorldConfig.from_kwargs(1)                        # threshold: (k - 0.5) F, arm 0.38 side
    assert default.block_ground_friction(1) == pytest.approx((1.5, 1.5 * 0.38 * 0.6))


def push(block_type: int, steps: int = 300, **overrides) -> float:
    """One robot against the north side of a lone block at (20, 30), driving south without
    gripping; returns the block's displacement."""
    counts = [0, 0, 0]
    counts[block_type] = 1
    sim = world(counts, **overrides)
    w, cfg = sim.world, sim.config
    w.place_block(0, 20.0, 30.0, 0.0)
    w.place_robot(0, 20.0, 30.0 + w.block_half[0] + cfg.robot_radius + 0.01, -math.pi / 2)
    start = w.block_pos[0].copy()
    for _ in range(steps):
        sim.step(np.ones((1, 2)))
    return float(np.hypot(*(w.block_pos[0] - start)))


@pytest.mark.usefixtures("both_kernels")
def test_under_mass_friction_one_robot_pushes_what_its_force_beats_whatever_the_robots_needed():
    # Drive force 3.6: above a medium block's 0.1 * 3 * 9.81 = 2.94, below a large one's 5.89.
    assert push(1, ground_friction="mass", robot_drive_force=3.6) > 5.0
    assert push(2, ground_friction="mass", robot_drive_force=3.6) < 0.05
    # The threshold model asks for two robots however strong one is: (2 - 0.5) * 3.6 > 3.6.
    assert push(1, ground_friction="threshold", robot_drive_force=3.6) < 0.05


def slide_into(target: str, **overrides) -> tuple[float, float]:
    """A small block sent east at 1 unit/s into a resting small block or the east wall, with
    no ground friction; returns the (mover's, target block's) x velocity once they part."""
    two = target == "block"
    sim = world((2 if two else 1, 0, 0), **FRICTIONLESS, **overrides)
    w = sim.world
    w.place_robot(0, 5.0, 5.0, 0.0)
    x0 = 30.0 if two else w.config.arena_width - 1.0
    w.place_block(0, x0, 20.0, 0.0)
    if two:
        w.place_block(1, x0 + 1.0, 20.0, 0.0)
    w.block_bodies[0].velocity = (1.0, 0.0)
    w.read_state()
    for _ in range(20):                                         # 2 s: contact after ~0.6 s
        sim.step(np.zeros((1, 2)))
    vel = [w.block_bodies[i].velocity.x for i in range(len(w.block_bodies))]
    return vel[0], (vel[1] if two else 0.0)


@pytest.mark.usefixtures("both_kernels")
def test_restitution_is_the_larger_of_the_two_shapes_as_in_box2d():
    # Block on wall: max(0.4, 1) = 1, so the block comes back at full speed (pymunk's product: 0.4).
    mover, _ = slide_into("wall", **ORIGINAL_RESTITUTION)
    assert mover == pytest.approx(-1.0, abs=0.02)
    # Block on block: 0.4; equal masses part at (1 - e) / 2 and (1 + e) / 2 (here 0.3 and 0.7).
    mover, target = slide_into("block", **ORIGINAL_RESTITUTION)
    assert (mover, target) == (pytest.approx(0.3, abs=0.02), pytest.approx(0.7, abs=0.02))
    # The default (0 everywhere): a perfectly inelastic contact, both at 0.5.
    mover, target = slide_into("block")
    assert (mover, target) == (pytest.approx(0.5, abs=0.02), pytest.approx(0.5, abs=0.02))


@pytest.mark.parametrize("values", list(itertools.product((0.0, 0.4, 1.0), repeat=3)))
def test_mixing_gives_every_kind_of_contact_the_larger_restitution(values):
    cfg = WorldConfig.from_kwargs(1, **dict(zip(ORIGINAL_RESTITUTION, values)))
    e = dict(zip(("robot", "block", "wall"), values))
    elasticity, handled = mixing(cfg)
    by_pair = {(a, b): value for a, b, value in handled}
    for a, b in [("robot", "robot"), ("robot", "block"), ("robot", "wall"), ("block", "block"), ("block", "wall")]:
        got = by_pair.get((a, b), elasticity[a] * elasticity[b])
        assert got == max(e[a], e[b]), (a, b)
    if values == (1.0, 0.4, 1.0):                               # the original: one handler, the rare one
        assert list(by_pair) == [("block", "block")]


@pytest.mark.parametrize("key, value, allowed", [
    ("ground_friction", "Mass", "'threshold', 'mass'"),
    ("robot_restitution", 1.5, "[0.0, 1.0]"),
    ("wall_restitution", -0.1, "[0.0, 1.0]"),
])
def test_bad_physics_options_name_the_key_and_what_is_allowed(key, value, allowed):
    with pytest.raises(ValueError, match=rf"{key}=.*allowed: {re.escape(allowed)}"):
        WorldConfig.from_kwargs(1, **{key: value})


@pytest.mark.usefixtures("both_kernels")
def test_under_the_original_protocols_physics_one_robot_moves_a_medium_block_as_in_the_original():
    # Measured on the original's own classes: 7.3 (fixed order) to 17.1 (its shuffled
    # schedule) units in 500 steps; under the paper's world one robot cannot move it at all.
    env = protocol_values("original", 2)["environment"]  # version 2: the velocity drive's model
    moved = push(1, steps=500, **{key: env[key] for key in ORIGINAL_PHYSICS})
    assert 5.0 < moved < 25.0
    assert push(1, steps=500) < 0.05


def free_speed(drive: float, **overrides) -> float:
    """Speed (units/s) of a lone robot after 30 steps at wheel drive (drive, drive)."""
    sim = world((1, 0, 0), **overrides)
    w = sim.world
    w.place_block(0, 35.0, 35.0, 0.0)
    w.place_robot(0, 5.0, 5.0, math.pi / 2)
    for _ in range(30):
        sim.step(np.full((1, 2), drive))
    before = w.robot_pos[0].copy()
    sim.step(np.full((1, 2), drive))
    return float(np.hypot(*(w.robot_pos[0] - before)) / sim.config.dt)


@pytest.mark.usefixtures("both_kernels")
def test_dead_band_stops_weak_commands_and_scales_the_rest_to_top_speed():
    band = dict(drive_dead_band=0.28, robot_max_speed=0.637)
    assert free_speed(0.25, **band) == 0.0
    assert free_speed(0.5, **band) == pytest.approx(0.637 * (0.5 - 0.28) / 0.72, rel=1e-3)  # original: 0.196
    assert free_speed(-0.5, **band) == pytest.approx(0.637 * (0.5 - 0.28) / 0.72, rel=1e-3)
    assert free_speed(1.0, **band) == pytest.approx(0.637, rel=1e-3)
    assert free_speed(0.5, robot_max_speed=0.637) == pytest.approx(0.3185, rel=1e-3)         # no band


def test_the_fidelity_pages_pushing_table_is_what_the_scenes_measure_today():
    # docs/fidelity.md quotes examples/physics_scenes.py; a change of the world or the bundle
    # that moves a figure must update the page (python examples/physics_scenes.py prints it).
    root = Path(__file__).resolve().parents[1]
    spec = importlib.util.spec_from_file_location("physics_scenes", root / "examples" / "physics_scenes.py")
    scenes = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(scenes)
    page = (root / "docs" / "fidelity.md").read_text()
    for world, column in (("original", 3), ("paper", 4), ("force", 5), ("shuffled", 6)):
        for scene, value in scenes.measure(world).items():
            row = next(line for line in page.splitlines() if line.startswith(f"| {scene} |"))
            assert row.split("|")[1 + column].strip() == f"{value:.3g}", (world, scene)


def test_the_scenes_shuffled_world_is_the_physics_of_the_newest_bundle():
    # the fidelity page's last column is what protocol = "original" (version 3 and on) runs
    root = Path(__file__).resolve().parents[1]
    spec = importlib.util.spec_from_file_location("physics_scenes", root / "examples" / "physics_scenes.py")
    scenes = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(scenes)
    newest = protocol_values("original")["environment"]
    # sensing and the welded robot's keys: the scenes push without grips
    sensing = ("zone_depth", "pickup_box", "pickup_box_width", "pickup_box_depth", "ir_response", "colour_response",
               "block_sighting", "bottom_response", "wall_distance", "attached_steering", "weld_spin")
    assert scenes.physics("shuffled") == {k: v for k, v in newest.items() if k not in sensing}
    version2 = protocol_values("original", 2)["environment"]
    assert scenes.physics("original") == {k: v for k, v in version2.items() if k not in sensing}
