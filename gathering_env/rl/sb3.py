"""The W-world simulation as a Stable-Baselines3 ``VecEnv``: one sub-environment per robot.

Every robot of every world is one sub-environment, so a single SB3 policy (PPO, A2C, ...)
is shared by the whole team and trained on all robots' experience at once::

    from stable_baselines3 import PPO
    from gathering_env.rl.sb3 import GatheringVecEnv

    venv = GatheringVecEnv(num_worlds=4, seed=0, environment=1, max_cycles=2000, reward="shaped")
    model = PPO("MlpPolicy", venv).learn(200_000)       # timesteps count robot-steps

Sub-environment ``k`` is robot ``k % N`` of world ``k // N`` (W worlds of N robots:
``num_envs = W * N``). Observation ``Box(0, 1, (S,), float32)`` (the morphology's
readings), action ``Box(-1, 1, (2,), float32)`` (left, right wheel). Rewards are
``VectorSimulation.robot_rewards()`` (``reward`` / ``attach_reward`` / ``reward_scope``
world options; see ``gathering_env.rewards``). With ``wheel_levels=K`` the action space is
``MultiDiscrete([K, K])`` instead: each wheel picks one of K commands evenly spaced in
[-1, 1] (K = 3: back, stop, forward) — categorical policies keep a bounded exploration noise
where a Gaussian's standard deviation can grow far beyond the action range (docs/rl).

When a world's episode ends, its N sub-environments report ``done`` together, their infos
carry ``terminal_observation``, ``TimeLimit.truncated`` and the episode's
``task_performance`` (ft, paper eq. 1), ``blocks_gathered`` and ``team_return`` (the sum of
the world's team rewards), and the world starts a new episode (auto-reset). Episode seeds
are drawn from one generator seeded by ``seed`` (constructor or ``seed()``, applied at the
next ``reset()``), so training runs are reproducible.

Needs Stable-Baselines3 (``pip install 'gathering-evolution[rl]'``); nothing else in the
package imports this module.
"""

from __future__ import annotations

import functools
import numbers
from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices

from ..sensors import Morphology
from ..vector import VectorSimulation
from .seeds import SEED_LIMIT, check_seed, episode_seeds

MAX_WHEEL_LEVELS = 101
"""Upper bound on ``wheel_levels`` (commands per wheel of the discrete action space)."""


def action_space(wheel_levels: int | None) -> spaces.Space:
    """``Box(-1, 1, (2,))`` for ``None``, else ``MultiDiscrete([K, K])`` (see the module docstring)."""
    if wheel_levels is None:
        return spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
    if (isinstance(wheel_levels, bool) or not isinstance(wheel_levels, numbers.Integral)
            or not 2 <= wheel_levels <= MAX_WHEEL_LEVELS):
        raise ValueError(f"wheel_levels={wheel_levels!r}; allowed: None (continuous wheel commands) or an "
                         f"integer in [2, {MAX_WHEEL_LEVELS}]")
    return spaces.MultiDiscrete([int(wheel_levels)] * 2)


def check_actions(actions: Any, space: spaces.Space, num_envs: int) -> np.ndarray:
    """``actions`` as an array of shape ``(num_envs, 2)``, or ``ValueError`` saying what is allowed.

    A ``MultiDiscrete([K, K])`` action must be integers 0..K-1 (an integer array, or floats
    with integer values): -1 is not "the last level" and 2.7 is not rounded. A ``Box`` action
    must be finite. The shape must be exactly ``(num_envs, 2)``: a transposed ``(2, num_envs)``
    array would scramble the robots' commands, so it is refused.
    """
    arr = np.asarray(actions)
    if arr.shape != (num_envs, 2):
        hint = " (transposed? one row per sub-environment)" if arr.shape == (2, num_envs) else ""
        raise ValueError(f"actions: shape {arr.shape}{hint}; allowed: shape ({num_envs}, 2), one (left, right) "
                         "row per sub-environment")
    if isinstance(space, spaces.MultiDiscrete):
        k = int(space.nvec[0])
        allowed = f"integers 0..{k - 1} (wheel commands {', '.join(f'{v:g}' for v in _levels(k))})"
        if arr.dtype == bool or not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
            raise ValueError(f"actions: dtype {arr.dtype}; allowed: {allowed}")
        if np.issubdtype(arr.dtype, np.floating):
            bad = ~np.isfinite(arr) | (arr != np.round(arr))
            if bad.any():
                value = arr[tuple(np.argwhere(bad)[0])].item()
                raise ValueError(f"actions: {value!r} is not an integer; allowed: {allowed}")
        out = (arr < 0) | (arr > k - 1)
        if out.any():
            row, col = np.argwhere(out)[0]
            raise ValueError(f"actions[{row}, {col}] = {arr[row, col].item()!r} is out of range; allowed: {allowed}")
        return arr.astype(np.int64)
    if not np.issubdtype(arr.dtype, np.number) or arr.dtype == bool:
        raise ValueError(f"actions: dtype {arr.dtype}; allowed: finite numbers in [-1, 1]")
    if not np.isfinite(arr).all():
        row, col = np.argwhere(~np.isfinite(arr))[0]
        raise ValueError(f"actions[{row}, {col}] = {arr[row, col].item()!r}; allowed: finite numbers in [-1, 1]")
    return arr


def wheel_commands(actions: np.ndarray, space: spaces.Space) -> np.ndarray:
    """Wheel commands in [-1, 1] for (checked, ``check_actions``) actions of ``space``: a
    ``MultiDiscrete([K, K])`` action picks among K evenly spaced commands; a ``Box`` action is
    the command itself (as float64)."""
    actions = np.asarray(actions)
    if isinstance(space, spaces.MultiDiscrete):
        return _levels(int(space.nvec[0]))[actions.astype(np.int64)]
    return actions.astype(np.float64)


@functools.cache
def _levels(count: int) -> np.ndarray:
    """The ``count`` wheel commands of the discrete action space (built once per count)."""
    levels = np.linspace(-1.0, 1.0, count)
    levels.flags.writeable = False
    return levels


class GatheringVecEnv(VecEnv):
    """W worlds x N robots as ``W * N`` SB3 sub-environments (see the module docstring).

    Args:
        num_worlds: W worlds stepped together (``VectorSimulation``).
        seed: seeds the generator of episode seeds (None: fresh entropy).
        morphology: every robot's sensor suite (default Khepera III).
        wheel_levels: None (default) for continuous wheel commands, ``Box(-1, 1, (2,))``; or K
            in [2, 101] for ``MultiDiscrete([K, K])``, K evenly spaced commands per wheel.
        **world_parameters: ``WorldConfig.from_kwargs`` arguments (``environment``,
            ``max_cycles``, ``num_robots``, ``reward``, ``reward_scope``, ...).
    """

    render_mode = None

    def __init__(self, num_worlds: int = 1, seed: int | None = None,
                 morphology: Morphology | Sequence | dict | None = None, wheel_levels: int | None = None,
                 **world_parameters: Any) -> None:
        actions = action_space(wheel_levels)
        self.sim = VectorSimulation(num_worlds, morphology=morphology, **world_parameters)
        self.config = self.sim.config
        self.num_worlds, self.num_robots = self.sim.num_worlds, self.config.num_robots
        observation_space = spaces.Box(0.0, 1.0, shape=(len(self.sim.morphology),), dtype=np.float32)
        super().__init__(self.num_worlds * self.num_robots, observation_space, actions)
        self._seed = check_seed(seed)
        self._rng = np.random.default_rng(self._seed)
        self._actions: np.ndarray | None = None
        self._team_return = np.zeros(self.num_worlds)

    # ------------------------------------------------------------------ VecEnv API
    def seed(self, seed: int | None = None) -> list[int | None]:
        """Seed the episode-seed generator; takes effect at the next ``reset()``."""
        self._seed = check_seed(seed)
        self._rng = np.random.default_rng(self._seed)
        return [self._seed] * self.num_envs

    def reset(self) -> np.ndarray:
        obs = self.sim.reset(self._episode_seeds(self.num_worlds))
        self._team_return[:] = 0.0
        self.reset_infos = [{} for _ in range(self.num_envs)]
        return obs.reshape(self.num_envs, -1)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = check_actions(actions, self.action_space, self.num_envs)

    def step_wait(self):
        if self._actions is None:
            raise RuntimeError("step_wait() without step_async(actions)")
        wheels = wheel_commands(self._actions, self.action_space).reshape(self.num_worlds, self.num_robots, 2)
        self._actions = None
        obs, team, terminated, truncated = self.sim.step(wheels)
        rewards = self.sim.robot_rewards().reshape(-1).astype(np.float32)
        self._team_return += team
        ended = terminated | truncated
        dones = np.repeat(ended, self.num_robots)
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        if ended.any():
            ft = self.sim.task_performance()
            gathered = self.sim.blocks_gathered_by_type()
            for w in np.flatnonzero(ended):
                episode = {"task_performance": float(ft[w]), "blocks_gathered": gathered[w].tolist(),
                           "team_return": float(self._team_return[w]),
                           "TimeLimit.truncated": bool(truncated[w] and not terminated[w])}
                for i in range(self.num_robots):
                    infos[w * self.num_robots + i] = dict(episode, terminal_observation=obs[w, i].copy())
                obs[w] = self.sim.reset_world(int(w), self._episode_seeds(1)[0])
                self._team_return[w] = 0.0
        return obs.reshape(self.num_envs, -1), rewards, dones, infos

    def close(self) -> None:
        pass

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        return [getattr(self, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        raise AttributeError(f"set_attr({attr_name!r}): the sub-environments share one simulation; "
                             "allowed: none (build a new GatheringVecEnv)")

    def env_method(self, method_name: str, *method_args, indices: VecEnvIndices = None, **method_kwargs) -> list[Any]:
        raise AttributeError(f"env_method({method_name!r}): the sub-environments are robots of a shared "
                             "simulation, not separate envs; call methods of GatheringVecEnv.sim instead")

    def env_is_wrapped(self, wrapper_class: type, indices: VecEnvIndices = None) -> list[bool]:
        return [False] * len(self._indices(indices))

    # ------------------------------------------------------------------ helpers
    def _episode_seeds(self, count: int) -> list[int]:
        return episode_seeds(self._rng, count)

    def _indices(self, indices: VecEnvIndices) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        if isinstance(indices, numbers.Integral):
            return [int(indices)]
        return list(indices)


__all__ = ["SEED_LIMIT", "GatheringVecEnv", "action_space", "check_actions", "wheel_commands"]
