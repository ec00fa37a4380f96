"""The compiled kernels against the numpy reference: readings, whole episodes, many worlds.

The numpy implementation (``SensorBank``, ``NumpySimulation``) is the reference; the
compiled one must give the same readings (to 1e-9, in float64) on generated scenes that
include the hard cases (objects exactly on a cone's edge or at the range limit, rotated
blocks, robots touching walls), the same trajectories and task performance over whole
episodes with every world option, and the same worlds when W of them are stepped together.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from evolution.policies.scripted import WanderTeam
from gathering_env import parallel_env
from gathering_env.compiled.kernels import CompiledSensorBank
from gathering_env.config import WorldConfig
from gathering_env.reference.sensing import SensorBank
from gathering_env.sensors import SENSOR_TYPES, Morphology, SensorSpec
from gathering_env.simulation import CompiledSimulation, GatheringSimulation, NumpySimulation
from gathering_env.vector import VectorSimulation

R = 0.15


def _sensor(draw, kind):
    spec = SENSOR_TYPES[kind]
    if not spec.configurable:
        return SensorSpec("bottom")
    return SensorSpec(
        kind,
        bearing=draw(st.sampled_from([0.0, math.pi, -math.pi, math.pi / 2]) | st.floats(-math.pi, math.pi)),
        orientation=draw(st.sampled_from([0.0, math.pi / 2, -math.pi / 2]) | st.floats(-math.pi / 2, math.pi / 2)),
        range=draw(st.sampled_from([spec.range_max]) | st.floats(0.05, spec.range_max)),
        fov=draw(st.sampled_from([spec.fov_min, spec.fov_max]) | st.floats(spec.fov_min, spec.fov_max)),
    )


@st.composite
def scenes(draw):
    kinds = draw(st.lists(st.sampled_from(list(SENSOR_TYPES)), min_size=1, max_size=10))
    morph = Morphology([_sensor(draw, k) for k in kinds])
    n = draw(st.integers(2, 10))
    b = draw(st.integers(1, 8))
    size = draw(st.sampled_from([3.0, 8.0, 40.0]))
    seed = draw(st.integers(0, 2**32 - 1))
    edge_cases = draw(st.booleans())
    gamma = draw(st.booleans())
    return morph, n, b, size, seed, edge_cases, gamma


def _place_on_edges(morph, robot_pos, robot_angle, block_pos, block_angle, block_half, rng):
    """Put objects exactly on the cone edge and/or at the range limit of robot 0's sensors,
    and robots touching the walls."""
    cones = [s for s in morph if s.type != "bottom"]
    if not cones:
        return
    x, y, a = robot_pos[0, 0], robot_pos[0, 1], robot_angle[0]
    for k in range(1, len(robot_pos)):
        s = cones[k % len(cones)]
        mount = a + s.bearing
        mx, my = x + R * math.cos(mount), y + R * math.sin(mount)
        axis = mount + s.orientation
        direction = axis + rng.choice([-0.5, 0.5, 0.0]) * s.fov       # edge or axis
        centre = s.range + R if rng.random() < 0.5 else rng.uniform(0.0, s.range + R)  # range limit
        robot_pos[k] = (mx + centre * math.cos(direction), my + centre * math.sin(direction))
    for b in range(len(block_pos)):
        s = cones[b % len(cones)]
        mount = a + s.bearing
        mx, my = x + R * math.cos(mount), y + R * math.sin(mount)
        axis = mount + s.orientation + rng.choice([-0.5, 0.5]) * s.fov
        # an axis-aligned block whose near face lies exactly at the range, on the edge ray
        block_angle[b] = 0.0 if rng.random() < 0.5 else axis
        d = s.range + block_half[b]
        block_pos[b] = (mx + d * math.cos(axis), my + d * math.sin(axis))
    # robots inside the arena, some touching a wall or overlapping it by a contact's slack
    np.clip(robot_pos, R, None, out=robot_pos)
    if len(robot_pos) > 2:
        robot_pos[-1, 0] = R
        robot_pos[-2, 1] = R - 0.05


def _extreme_morphology():
    """Every type once, at the bounds of its range, field of view and mounting angles."""
    t = SENSOR_TYPES
    return Morphology([
        SensorSpec("bottom"),
        SensorSpec("infrared", 0.0, 0.0, t["infrared"].range_max, t["infrared"].fov_max),
        SensorSpec("ultrasonic", math.pi, math.pi / 2, t["ultrasonic"].range_max, t["ultrasonic"].fov_min),
        SensorSpec("colour", -math.pi, -math.pi / 2, t["colour"].range_max, t["colour"].fov_min),
        SensorSpec("camera", math.pi / 2, 0.0, t["camera"].range_max, t["camera"].fov_max),
    ])


# Derandomized by the suite's hypothesis profile (tests/conftest.py), plus explicit edge scenes:
# every type at its bounds with objects on cone edges and range limits in the smallest arena
# (crowded, gamma response) and in the largest (sparse, linear).
@settings(max_examples=200, deadline=None)
@example((_extreme_morphology(), 10, 8, 3.0, 0, True, True))
@example((_extreme_morphology(), 2, 1, 40.0, 2**32 - 1, True, False))
@given(scenes())
def test_compiled_readings_equal_the_numpy_reference(scene):
    morph, n, b, size, seed, edge_cases, gamma = scene
    rng = np.random.default_rng(seed)
    cfg = WorldConfig.from_kwargs(environment=None, block_counts=(b, 0, 0), num_robots=n,
                                  arena_width=size, arena_height=size, zone_width=size / 2,
                                  zone_depth=size / 5, ir_response="gamma" if gamma else "linear")
    robot_pos = rng.uniform(R, size - R, (n, 2))
    robot_angle = rng.uniform(-math.pi, math.pi, n)
    block_pos = rng.uniform(0.2, size - 0.2, (b, 2))
    block_angle = rng.uniform(-math.pi, math.pi, b)
    block_half = rng.choice([0.2, 0.3, 0.4], b)
    block_need = rng.choice([1, 2, 3], b).astype(float)
    if edge_cases:
        _place_on_edges(morph, robot_pos, robot_angle, block_pos, block_angle, block_half, rng)
        np.clip(robot_pos, R - 0.05, size - R + 0.05, out=robot_pos)
    want = SensorBank(morph, cfg, block_half, block_need).read(robot_pos, robot_angle, block_pos, block_angle,
                                                               dtype=np.float64)
    got = CompiledSensorBank(morph, cfg, block_half, block_need).read(robot_pos, robot_angle, block_pos,
                                                                      block_angle, dtype=np.float64)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
    assert ((got >= 0) & (got <= 1)).all()


# ---------------------------------------------------------------------------- episodes
MIXED = Morphology([
    SensorSpec("bottom"),
    SensorSpec("ultrasonic", 0.0, 0.0, 25.0, 1.0),
    SensorSpec("camera", 0.5, 0.2, 20.0, 2.0),
    SensorSpec("colour", -0.7, -0.3, 10.0, 1.5),
    SensorSpec("infrared", 2.5, 0.4, 3.0, 2.0),
    SensorSpec("ultrasonic", -math.pi, 0.0, 4.0, 0.5),
])

# A small arena so that robots meet blocks, attach, and gather them within a few hundred steps.
SMALL = dict(environment=None, arena_width=10.0, arena_height=10.0, zone_width=5.0, zone_depth=2.0,
             block_counts=(4, 3, 2), num_robots=12)


def _episode(kernel: str, steps: int, morphology: Morphology, seed: int, **world):
    cfg = WorldConfig.from_kwargs(kernel=kernel, max_cycles=steps, **world)
    sim = GatheringSimulation(cfg, morphology)
    obs = sim.reset(seed=seed)
    team = WanderTeam(morphology, seed=seed)
    rng = np.random.default_rng(seed)
    record = {"obs": [obs], "pose": [], "reward": [], "attached": [], "anchors": [], "sticky": [], "gathered": [],
              "gathered_value": [], "steps": [], "robot_reward": []}
    while True:
        wheels = team.act(obs)
        wheels[::3] = rng.uniform(-1.5, 1.5, wheels[::3].shape)   # some random and out-of-range commands
        obs, reward, terminated, truncated = sim.step(wheels)
        w = sim.world
        record["obs"].append(obs)
        record["pose"].append(np.concatenate([w.robot_pos.ravel(), w.robot_angle, w.block_pos.ravel(),
                                              w.block_angle]))
        record["reward"].append(reward)
        record["attached"].append(w.robot_attached.copy())
        record["anchors"].append(w.anchor_owner.copy())
        record["sticky"].append(w.block_sticky_side.copy())
        record["gathered"].append(sim.gathered.copy())
        record["gathered_value"].append(sim.gathered_value)
        record["steps"].append(sim.steps)
        record["robot_reward"].append(np.asarray(sim.robot_reward).copy())
        if terminated or truncated:
            break
    return sim, record


@pytest.mark.parametrize("world", [
    dict(SMALL),
    dict(SMALL, collision_avoidance=True),
    dict(SMALL, weld_seat=False),
    dict(SMALL, ir_response="gamma", physics_substeps=2),
    dict(environment=3, num_robots=20),
    dict(SMALL, pickup_box="centre", pickup_box_width=0.4, pickup_box_depth=0.4),
    dict(SMALL, pickup_box="centre", pickup_box_width=0.2, pickup_box_depth=0.1, zone_depth=4.0),
    dict(SMALL, ground_friction="mass", robot_restitution=1.0, block_restitution=0.4, wall_restitution=1.0,
         robot_drive_force=3.63, robot_max_speed=0.637, drive_dead_band=0.28),
    dict(SMALL, ground_friction="mass", robot_restitution=1.0, block_restitution=0.4, wall_restitution=1.0,
         drive_model="force", damping=0.1),
    dict(SMALL, drive_model="force", physics_substeps=3, collision_avoidance=True),
    dict(SMALL, ground_friction="mass", robot_restitution=1.0, block_restitution=0.4, wall_restitution=1.0,
         drive_model="force", damping=0.1, schedule="shuffled"),
    dict(SMALL, colour_response="farther", block_sighting="rays", ir_response="khepera", bottom_response="khepera",
         wall_distance="original"),
    dict(SMALL, pickup_box="centre", pickup_box_width=0.4, pickup_box_depth=0.4, attached_steering="original"),
    dict(SMALL, ground_friction="mass", robot_restitution=1.0, block_restitution=0.4, wall_restitution=1.0,
         drive_model="force", damping=0.1, pickup_box="centre", pickup_box_width=0.4, pickup_box_depth=0.4,
         attached_steering="original", weld_spin="free"),
], ids=["small", "avoidance", "weld-in-place", "gamma-substeps", "env3", "centre-box", "original-box",
        "original-physics", "force-drive", "force-drive-substeps", "force-drive-shuffled", "original-sensing",
        "original-steering", "weld-spin-free"])
def test_whole_episodes_are_identical_on_both_kernels(world):
    steps = 1000 if world.get("drive_model") == "force" else 400   # slower robots: reach the zone
    attached = gathered = shared = False
    for morphology in (Morphology.khepera_iii(), MIXED):
        ref, want = _episode("numpy", steps, morphology, 7, **world)
        sim, got = _episode("compiled", steps, morphology, 7, **world)
        assert isinstance(ref, NumpySimulation) and isinstance(sim, CompiledSimulation)
        for key in want:
            np.testing.assert_array_equal(np.asarray(got[key]), np.asarray(want[key]), err_msg=key)
        assert sim.task_performance() == ref.task_performance()
        assert sim.steps == ref.steps and sim.blocks_gathered_by_type() == ref.blocks_gathered_by_type()
        attached |= bool(np.asarray(want["attached"]).max() >= 0)
        gathered |= bool(np.asarray(want["gathered"]).any())
        shared |= bool(((np.asarray(want["anchors"]) >= 0).sum(axis=-1) >= 2).any())
    if world.get("arena_width") == 10.0 and world.get("pickup_box_depth") != 0.1:
        # the comparison covered attachments and gathering (with releases), not only driving,
        # and in the plain small world blocks held by two robots on one sticky side (the
        # original's centre box of 0.1 x 0.2 lies inside the body and grips nothing here: its
        # attachments are covered by the larger centre box); under the force drive an attached
        # robot's steering hardly turns it against its ground friction, so nothing is gathered
        # in 1000 steps: its gathering is the same code, covered by the other worlds
        force = world.get("drive_model") == "force"
        assert attached and (gathered or force) and (shared or world != SMALL)


def test_episode_that_terminates_early_is_identical():
    world = dict(SMALL, block_counts=(1, 0, 0), num_robots=15)
    finished = 0
    for seed in (4, 0, 2):   # these end after 224 steps, by truncation at 1000, and after 589 steps
        ref, want = _episode("numpy", 1000, Morphology.khepera_iii(), seed, **world)
        sim, got = _episode("compiled", 1000, Morphology.khepera_iii(), seed, **world)
        for key in want:
            np.testing.assert_array_equal(np.asarray(got[key]), np.asarray(want[key]), err_msg=key)
        assert (sim.steps, sim.task_performance()) == (ref.steps, ref.task_performance())
        finished += sim.task_performance() > 100
    assert finished == 2   # two episodes ended by gathering everything (time bonus paid)


def _hand_scene(kernel: str):
    """Edge example: a large block (needs 3) held by three robots and a medium one (needs 2) held by
    two are pushed into the zone; every state array recorded at every step until both are gathered."""
    cfg = WorldConfig.from_kwargs(kernel=kernel, environment=None, block_counts=(0, 1, 1), num_robots=6,
                                  max_cycles=600)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=1)
    w = sim.world
    r = cfg.robot_radius
    robot = 0
    for block, x in ((0, 12.0), (1, 26.0)):                         # block 0 medium, block 1 large
        w.place_block(block, x, 10.0, 0.0)
        half, k = w.block_half[block], int(w.block_need[block])
        for offset in ((np.arange(k) + 0.5) / k * 2 - 1) * half:  # the side's anchor points
            w.place_robot(robot, x + offset, 10.0 + half + r + 0.01, -math.pi / 2)
            robot += 1
    w.place_robot(robot, 5.0, 35.0, 0.0)
    record = {key: [] for key in ("pose", "attached", "anchors", "sticky", "gathered", "reward", "steps")}
    while True:
        _, reward, terminated, truncated = sim.step(np.zeros((cfg.num_robots, 2)))
        record["pose"].append(np.concatenate([w.robot_pos.ravel(), w.robot_angle, w.block_pos.ravel()]))
        record["attached"].append(w.robot_attached.copy())
        record["anchors"].append(w.anchor_owner.copy())
        record["sticky"].append(w.block_sticky_side.copy())
        record["gathered"].append(sim.gathered.copy())
        record["reward"].append(reward)
        record["steps"].append(sim.steps)
        if terminated or truncated:
            return sim, {key: np.asarray(v) for key, v in record.items()}


def test_blocks_held_by_every_anchor_and_gathered_are_identical_on_both_kernels():
    ref, want = _hand_scene("numpy")
    sim, got = _hand_scene("compiled")
    for key in want:
        np.testing.assert_array_equal(got[key], want[key], err_msg=key)
    full = (want["anchors"] >= 0).sum(axis=-1)
    assert full[:, 1].max() == 3 and full[:, 0].max() == 2          # every anchor of both blocks held
    assert want["gathered"][-1].all() and (want["anchors"][-1] < 0).all() and (want["sticky"][-1] < 0).all()
    assert sim.task_performance() == ref.task_performance() > 100    # both gathered, time bonus paid


# ---------------------------------------------------------------------------- many worlds
@pytest.mark.parametrize("kernel", ["compiled", "numpy"])
def test_each_world_of_a_batch_is_the_world_stepped_alone(kernel):
    seeds = [11, 12, 13]
    world = dict(SMALL, kernel=kernel, max_cycles=150)
    sims = VectorSimulation(3, **world, morphology=MIXED)
    alone = [GatheringSimulation(WorldConfig.from_kwargs(**world), MIXED) for _ in seeds]
    obs = sims.reset(seeds)
    for w, sim in enumerate(alone):
        np.testing.assert_array_equal(obs[w], sim.reset(seed=seeds[w]))
    rng = np.random.default_rng(0)
    restarted = False
    while sims.active.any():
        wheels = rng.uniform(-1, 1, (3, SMALL["num_robots"], 2))
        before = [s.world.robot_pos.copy() for s in alone]
        active = sims.active
        obs, reward, terminated, truncated = sims.step(wheels)
        for w, sim in enumerate(alone):
            if active[w]:
                o, r, te, tr = sim.step(wheels[w])
                np.testing.assert_array_equal(obs[w], o)
                assert (reward[w], terminated[w], truncated[w]) == (r, te, tr)
            else:   # masked out: not stepped
                assert reward[w] == 0.0
                np.testing.assert_array_equal(sims.worlds[w].robot_pos, before[w])
        if not restarted and sims.steps[1] == 60:
            # world 1 starts over: it ends 60 steps after the others
            np.testing.assert_array_equal(sims.reset_world(1, 99), alone[1].reset(seed=99))
            restarted = True
    assert sims.steps.tolist() == [150, 150, 150]
    np.testing.assert_array_equal(sims.task_performance(), [s.task_performance() for s in alone])
    np.testing.assert_array_equal(sims.blocks_gathered_by_type(), [s.blocks_gathered_by_type() for s in alone])


def test_compiled_and_numpy_batches_agree():
    runs = {}
    for kernel in ("compiled", "numpy"):
        sims = VectorSimulation(4, environment=2, max_cycles=200, kernel=kernel)
        obs = sims.reset([0, 1, 2, 3])
        team = WanderTeam(sims.morphology, seed=0)
        trace = [obs]
        while sims.active.any():
            obs, reward, *_ = sims.step(team.act(obs.reshape(-1, obs.shape[-1])).reshape(4, -1, 2))
            trace.append(obs)
        runs[kernel] = (np.stack(trace), sims.task_performance())
    np.testing.assert_array_equal(runs["compiled"][0], runs["numpy"][0])
    np.testing.assert_array_equal(runs["compiled"][1], runs["numpy"][1])


def test_vector_bad_input():
    with pytest.raises(ValueError, match=r"num_worlds=0; allowed: an integer in \[1, 4096\]"):
        VectorSimulation(0)
    with pytest.raises(ValueError, match="kernel='fast'; allowed: 'compiled', 'numpy'"):
        VectorSimulation(2, kernel="fast")
    sims = VectorSimulation(2, environment=1, max_cycles=5)
    with pytest.raises(RuntimeError, match="reset"):
        sims.step(np.zeros((2, 20, 2)))
    with pytest.raises(ValueError, match="seeds must be a sequence of 2 seeds"):
        sims.reset([1])
    with pytest.raises(ValueError, match=r"seeds\[1\]=True"):
        sims.reset([1, True])
    sims.reset([1, 2])
    with pytest.raises(ValueError, match=r"expected \(2, 20, 2\)"):
        sims.step(np.zeros((20, 2)))
    bad = np.zeros((2, 20, 2))
    bad[1, 4, 0] = np.nan
    with pytest.raises(ValueError, match="world 1, robot_4 .* NaN/inf not allowed"):
        sims.step(bad)
    with pytest.raises(ValueError, match=r"world=2; allowed: an integer in \[0, 1\]"):
        sims.reset_world(2, 0)
    for _ in range(5):
        sims.step(np.zeros((2, 20, 2)))
    with pytest.raises(RuntimeError, match="every world's episode ended"):
        sims.step(np.zeros((2, 20, 2)))


def test_bad_kernel_name_names_the_allowed_values():
    with pytest.raises(ValueError, match="kernel='numba'; allowed: 'compiled', 'numpy'"):
        parallel_env(kernel="numba")


@pytest.mark.parametrize("kernel", ["compiled", "numpy"])
def test_pickled_env_continues_identically(kernel):
    env = parallel_env(environment=2, max_cycles=300, kernel=kernel)
    obs, _ = env.reset(seed=4)
    rng = np.random.default_rng(1)
    for _ in range(50):
        env.step({a: rng.uniform(-1, 1, 2) for a in env.agents})
    twin = pickle.loads(pickle.dumps(env))
    for _ in range(100):
        actions = {a: rng.uniform(-1, 1, 2) for a in env.agents}
        o1, r1, *_ = env.step(actions)
        o2, r2, *_ = twin.step(actions)
        for agent in o1:
            np.testing.assert_array_equal(o1[agent], o2[agent])
        assert r1 == r2
    np.testing.assert_array_equal(env.sim.world.robot_pos, twin.sim.world.robot_pos)


@pytest.mark.parametrize("wall_distance", ["nearest", "original"])
def test_wall_readings_agree_on_both_kernels_at_every_wall(wall_distance):
    """Ten colour sensors of random range, FOV and direction on a lone robot placed anywhere in
    the arena (half of the poses near a corner): every reading is a wall's (or nothing), and the
    two kernels' wall formulas (written apart) give the same readings over 1 000 poses, walls
    seen in thousands of readings, the original's formulas beyond the range in hundreds (0.5)."""
    rng = np.random.default_rng(20261206)
    n = 1000
    sensors = [SensorSpec("colour", bearing=float(rng.uniform(-math.pi, math.pi)), orientation=float(rng.uniform(-1.5, 1.5)),
                          range=float(rng.uniform(0.5, 10.0)), fov=float(rng.uniform(math.pi / 6, 5 * math.pi / 6)))
               for _ in range(10)]
    cfg = dict(environment=None, block_counts=(1, 0, 0), num_robots=1, colour_response="farther",
               wall_distance=wall_distance)
    half, need = np.array([0.2]), np.array([1.0])
    pos = rng.uniform(0.15, 39.85, (n, 2))
    corner = rng.random((n // 2, 2)) < 0.5
    pos[: n // 2] = np.where(corner, rng.uniform(0.15, 3.0, (n // 2, 2)), rng.uniform(37.0, 39.85, (n // 2, 2)))
    angle = rng.uniform(-math.pi, math.pi, n)
    far_block = (np.array([[-100.0, -100.0]]), np.array([0.0]))        # outside every cone's reach
    got = {}
    for kernel, bank in (("numpy", SensorBank), ("compiled", CompiledSensorBank)):
        b = bank(Morphology(sensors), WorldConfig.from_kwargs(kernel=kernel, **cfg), half, need)
        got[kernel] = np.concatenate([b.read(pos[k:k + 1], angle[k:k + 1], *far_block).astype(float) for k in range(n)])
    np.testing.assert_allclose(got["compiled"], got["numpy"], atol=2e-6)
    walls_seen = (got["numpy"] > 0) & (got["numpy"] < 0.5)
    assert walls_seen.sum() > 2000
    if wall_distance == "original":
        assert (got["numpy"] == 0.5).sum() > 300     # seen, but put beyond the range
