"""Bad input: a clear ValueError naming the field, value and allowed range; nothing reaches pymunk."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gathering_env import Morphology, SensorSpec, parallel_env

pytestmark = pytest.mark.usefixtures("both_kernels")  # the same checks and messages on both kernels


@pytest.mark.parametrize("kwargs,needle", [
    (dict(type="laser", range=1, fov=1), "type='laser'"),
    (dict(type="infrared", range=0, fov=1), "range=0.0 out of range; allowed: (0, 10]"),
    (dict(type="infrared", range=-1, fov=1), "range=-1.0"),
    (dict(type="infrared", range=10.5, fov=1), "allowed: (0, 10]"),
    (dict(type="ultrasonic", range=25.1, fov=1), "allowed: (0, 25]"),
    (dict(type="camera", range=20.5, fov=1), "allowed: (0, 20]"),
    (dict(type="colour", range=5, fov=0.1), "fov=0.1 out of range"),
    (dict(type="camera", range=5, fov=3.0), "fov=3.0 out of range"),
    (dict(type="ultrasonic", range=5, fov=0.05), "fov=0.05"),
    (dict(type="infrared", bearing=4.0, range=1, fov=1), "bearing=4.0"),
    (dict(type="infrared", orientation=-2.0, range=1, fov=1), "orientation=-2.0"),
    (dict(type="infrared", range=math.nan, fov=1), "must be finite"),
    (dict(type="infrared", range=1, fov=math.inf), "must be finite"),
    (dict(type="infrared", bearing=math.nan, range=1, fov=1), "bearing=nan"),
    (dict(type="bottom", range=3.0), "not allowed for a bottom sensor"),
    (dict(type="infrared", fov=1), "range is required"),
    (dict(type="infrared", range="far", fov=1), "range='far' must be a number"),
])
def test_bad_sensor(kwargs, needle):
    with pytest.raises(ValueError) as err:
        SensorSpec(**kwargs)
    assert needle in str(err.value)


def test_too_many_sensors_and_bad_dicts():
    with pytest.raises(ValueError, match="11 sensors; allowed: at most 10"):
        Morphology([SensorSpec("bottom")] * 11)
    with pytest.raises(ValueError, match=r"sensor\[1\].*unknown sensor field"):
        Morphology([{"type": "bottom"}, {"type": "camera", "range": 1, "fov": 1, "colour": "red"}])
    with pytest.raises(ValueError, match="exactly the key 'sensors'"):
        Morphology.from_dict({"sensor": []})
    e = parallel_env(max_cycles=5)
    with pytest.raises(ValueError, match="morphology must be"):
        e.reset(seed=0, options={"morphology": 42})


@pytest.mark.parametrize("kwargs,needle", [
    (dict(environment=4), "environment=4 is not a preset; allowed: [1, 2, 3]"),
    (dict(block_counts=(2, -1, 0)), "block_counts[1] (medium)=-1 out of range"),
    (dict(block_counts=(0, 0, 0)), "at least one block"),
    (dict(num_robots=0), "num_robots=0 out of range"),
    (dict(max_cycles=2.5), "max_cycles=2.5 must be an integer"),
    (dict(dt=math.nan), "dt=nan must be finite"),
    (dict(robot_max_speed=-1), "robot_max_speed=-1 out of range"),
    (dict(zone_width=50), "zone_width=50"),
    (dict(warp_drive=True), "unknown world parameter(s) ['warp_drive']"),
    (dict(render_mode="png"), "render_mode='png'"),
    (dict(ir_response="cubic"), "ir_response='cubic'"),
    (dict(colour_response="closer"), "colour_response='closer'"),
    (dict(block_sighting="beams"), "block_sighting='beams'; allowed: 'cone', 'rays'"),
    (dict(bottom_response="sonar"), "bottom_response='sonar'; allowed: 'linear', 'khepera'"),
    (dict(wall_distance="true"), "wall_distance='true'; allowed: 'nearest', 'original'"),
    (dict(attached_steering="gentle"), "attached_steering='gentle'; allowed: 'sharp', 'original'"),
    (dict(weld_spin="loose"), "weld_spin='loose'; allowed: 'held', 'free'"),
    (dict(weld_spin="free"), "weld_spin='free' with drive_model='velocity'"),
    (dict(ground_friction="coulomb"), "ground_friction='coulomb'; allowed: 'threshold', 'mass'"),
    (dict(robot_restitution=1.2), "robot_restitution=1.2 out of range; allowed: [0.0, 1.0]"),
    (dict(drive_dead_band=1.0), "drive_dead_band=1.0 out of range; allowed: [0.0, 1.0)"),
])
def test_bad_world_parameters(kwargs, needle):
    with pytest.raises(ValueError) as err:
        parallel_env(**kwargs)
    assert needle in str(err.value)


def fresh(seed=4):
    e = parallel_env(environment=2, max_cycles=50)
    e.reset(seed=seed)
    return e


def zero_actions(e):
    return {a: np.zeros(2, dtype=np.float32) for a in e.possible_agents}


@pytest.mark.parametrize("mutate,needle", [
    (lambda a: a.update({"robot_99": np.zeros(2)}), "unknown agent(s) ['robot_99']"),
    (lambda a: a.pop("robot_7"), "missing for agent(s) ['robot_7']"),
    (lambda a: a.update({"robot_3": np.zeros(3)}), "robot_3 has shape (3,); expected (2,)"),
    (lambda a: a.update({"robot_3": "fast"}), "action of robot_3 is 'fast'"),
    (lambda a: a.update({"robot_5": np.array([np.nan, 0.0])}), "action of robot_5 is [nan, 0.0]"),
    (lambda a: a.update({"robot_5": np.array([0.0, np.inf])}), "NaN/inf not allowed"),
])
def test_bad_actions_are_refused_and_change_nothing(mutate, needle):
    e = fresh()
    reference = fresh()
    actions = zero_actions(e)
    mutate(actions)
    with pytest.raises(ValueError) as err:
        e.step(actions)
    assert needle in str(err.value)
    # The rejected call left no trace: the next valid step matches a fresh env's first step.
    rng = np.random.default_rng(0)
    good = {a: rng.uniform(-1, 1, 2) for a in e.possible_agents}
    o1, *_ = e.step(good)
    o2, *_ = reference.step(good)
    assert e.sim.steps == reference.sim.steps == 1
    for a in e.possible_agents:
        np.testing.assert_array_equal(o1[a], o2[a])


def test_step_batch_validates_too():
    e = fresh()
    with pytest.raises(ValueError, match=r"shape \(20, 3\)"):
        e.step_batch(np.zeros((20, 3)))
    bad = np.zeros((20, 2))
    bad[4, 1] = np.nan
    with pytest.raises(ValueError, match="robot_4"):
        e.step_batch(bad)
    assert e.sim.steps == 0


def test_out_of_range_actions_are_clipped():
    e1, e2 = fresh(), fresh()
    rng = np.random.default_rng(1)
    for _ in range(30):
        wheels = rng.uniform(-3, 3, (20, 2))
        o1, *_ = e1.step_batch(wheels)
        o2, *_ = e2.step_batch(np.clip(wheels, -1, 1))
        np.testing.assert_array_equal(o1, o2)


def test_step_after_the_end_and_before_reset():
    e = parallel_env(max_cycles=2)
    with pytest.raises(RuntimeError, match="reset"):
        e.step({})
    e.reset(seed=0)
    e.step(zero_actions(e))
    e.step(zero_actions(e))
    with pytest.raises(RuntimeError, match="after the episode ended"):
        e.step(zero_actions(e))
    with pytest.raises(RuntimeError, match="after the episode ended"):
        e.step_batch(np.zeros((20, 2)))
