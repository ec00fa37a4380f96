"""The task as one centralised Gymnasium env: the whole team is a single agent.

``gymnasium.make("gathering_env/GatheringTeam-v0", environment=2)`` (registered when
``gathering_env`` is imported) wraps the same simulation as the PettingZoo env, for
single-agent libraries.

## Observation space
``Box(0, 1, (num_robots * S,), float32)``: every robot's S sensor readings, robot_0 first.

## Action space
``Box(-1, 1, (num_robots * 2,), float32)``: (left, right) wheel drive of robot_0, robot_1, ...
Out-of-range values are clipped; NaN/inf raise ``ValueError``.

## Reward, episode end, info
As the PettingZoo env: the team reward (``reward="task"``: ``100 * (change in gathered value) /
total value``; ``reward="shaped"``: plus the shaping terms; ``reward_scope`` does not apply, the
single agent receives the team reward);
terminated when every block is gathered, truncated after ``max_cycles`` steps; ``info`` holds
``gathered_value``, ``total_value``, ``blocks_gathered``, ``blocks_gathered_by_type``, ``steps``
and, at the end, ``task_performance``.

Arguments are those of ``parallel_env``; ``reset(options={"morphology": ...})`` replaces the
sensor suite, and the observation space follows it.
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from .env import GatheringEnv


class GatheringTeamEnv(gymnasium.Env):
    """Centralised single-agent view of ``GatheringEnv`` (see the module docstring)."""

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 30}

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        self.team = GatheringEnv(render_mode=render_mode, **kwargs)
        self.render_mode = render_mode
        self.num_robots = self.team.config.num_robots
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2 * self.num_robots,), dtype=np.float32)
        self._set_observation_space()

    def _set_observation_space(self) -> None:
        width = self.num_robots * len(self.team.morphology)
        self.observation_space = spaces.Box(0.0, 1.0, shape=(width,), dtype=np.float32)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        obs, _ = self.team.reset(seed=seed, options=options)  # checks seed and options first
        super().reset(seed=seed)
        self._set_observation_space()
        return self._flatten(obs), self.team.team_info()

    def step(self, action: np.ndarray):
        wheels = np.asarray(action, dtype=np.float64)
        if wheels.shape != (2 * self.num_robots,):
            raise ValueError(f"action has shape {wheels.shape}; expected ({2 * self.num_robots},) = "
                             f"{self.num_robots} robots x (left, right)")
        obs, reward, terminated, truncated = self.team.step_batch(wheels.reshape(self.num_robots, 2))
        if self.render_mode == "human":
            self.team.render()
        return obs.reshape(-1), float(reward), terminated, truncated, self.team.team_info()

    def _flatten(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return np.concatenate([obs[a] for a in self.team.possible_agents]).astype(np.float32)

    def render(self):
        return self.team.render()

    def close(self) -> None:
        self.team.close()
