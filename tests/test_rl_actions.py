"""Actions given to ``GatheringVecEnv`` are checked: discrete wheel levels are integers in
0..K-1 (no negative indexing, no truncation), the array has shape (num_envs, 2) (a transposed
array is refused), nothing non-finite; the message lists the allowed values."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from gathering_env.rl.sb3 import GatheringVecEnv  # noqa: E402
from gathering_env.vector import VectorSimulation  # noqa: E402

OPTIONS = dict(environment=1, num_robots=3, max_cycles=30)


@pytest.fixture
def discrete():
    venv = GatheringVecEnv(1, seed=5, wheel_levels=3, **OPTIONS)
    venv.reset()
    return venv


@pytest.mark.parametrize("actions, needle", [
    ([[-1, 0], [0, 0], [0, 0]], "actions[0, 0] = -1 is out of range"),       # was: the last level
    ([[0, 0], [0, 3], [0, 0]], "actions[1, 1] = 3 is out of range"),
    ([[0, 0], [0, 0], [2.7, 0]], "2.7 is not an integer"),                    # was: truncated to 2
    ([[0, 0], [np.nan, 0], [0, 0]], "nan is not an integer"),
    ([[True, False]] * 3, "dtype bool"),
    (np.zeros((2, 3), np.int64), "shape (2, 3) (transposed?"),              # was: scrambled robots
    (np.zeros(6, np.int64), "shape (6,)"),
    (np.zeros((3, 3), np.int64), "shape (3, 3)"),
])
def test_bad_discrete_actions_name_the_allowed_values(discrete, actions, needle):
    with pytest.raises(ValueError) as caught:
        discrete.step(np.asarray(actions))
    message = str(caught.value)
    assert needle in message and "\n" not in message
    assert "allowed: " in message and ("integers 0..2 (wheel commands -1, 0, 1)" in message or "shape (3, 2)" in message)


def test_edge_levels_and_integral_floats_step_the_mapped_commands(discrete):
    """0 and K-1 are the commands -1 and +1; 2.0 is level 2: stepped exactly as VectorSimulation."""
    reference = VectorSimulation(1, **OPTIONS)
    reference.reset([int(np.random.default_rng(5).integers(0, 2**31))])
    for actions in (np.array([[0, 2], [2, 0], [0, 0]]), np.array([[2.0, 2.0], [1.0, 0.0], [2.0, 1.0]]),
                    np.array([[2, 2], [2, 2], [2, 2]], np.uint8)):
        obs, *_ = discrete.step(actions)
        ref_obs, *_ = reference.step((np.asarray(actions, float) - 1.0).reshape(1, 3, 2))
        np.testing.assert_array_equal(obs, ref_obs.reshape(3, -1))


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_continuous_actions_must_be_finite(value):
    venv = GatheringVecEnv(1, seed=5, **OPTIONS)
    venv.reset()
    actions = np.zeros((3, 2), np.float32)
    actions[2, 1] = value
    with pytest.raises(ValueError, match=r"actions\[2, 1\] = .*; allowed: finite numbers in \[-1, 1\]"):
        venv.step(actions)
    with pytest.raises(ValueError, match=r"shape \(2, 3\) \(transposed"):
        venv.step(np.zeros((2, 3), np.float32))
