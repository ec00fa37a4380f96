"""Collective gathering as a PettingZoo ``ParallelEnv`` (and its AEC form).

A team of differential-drive robots must find small, medium and large blocks, which need
1, 2 and 3 robots to push, and bring them into the gathering zone along the south wall.
Every robot carries the same configurable sensor suite (the *morphology*), which can be
replaced at every ``reset``.

## Agents
``robot_0 ... robot_{n-1}`` (``num_robots``, default 20). All agents act simultaneously.

## Action space
``Box(-1, 1, (2,), float32)`` per robot: (left, right) wheel drive as a fraction of the top
wheel speed (``robot_max_speed``, 0.5 units/s). Values outside [-1, 1] are clipped; NaN
or inf raise ``ValueError``. A robot attached to a block (pickup heuristic) ignores its
action and drives towards the zone.

## Observation space
``Box(0, 1, (S,), float32)`` per robot, one entry per sensor of the current morphology,
in morphology order (see ``gathering_env.reference.sensing`` for each type's reading). With the
default Khepera III morphology S = 6: bottom, IR +40 deg, IR -40 deg, ultrasonic 0 deg,
ultrasonic +90 deg, ultrasonic -90 deg.

## Rewards
Three world options (``gathering_env.rewards``; docs/rl/README.md); ``ft`` never depends on them:

| option | values | meaning |
|---|---|---|
| ``reward`` | ``"task"`` (default), ``"shaped"`` | task: the team reward ``100 * (change in gathered value) / total value``, so an episode's rewards sum to the value part of ``ft`` (paper eq. 1; the time bonus is reported in ``infos``, not rewarded). shaped: plus ``Phi(s') - Phi(s)``, ``Phi = -100 * sum_b value_b * distance_b(zone) / (total value * arena diagonal) + attach_reward * (robots attached)``. With discount 1 the shaped return is the task return + ``Phi(end) - Phi(start)``: potential-based shaping keeps the optimal policies (Ng, Harada & Russell 1999). |
| ``attach_reward`` | float >= 0, default 1.0 | shaped only: a robot earns it when it attaches to a block and gives it back when released (its block gathered) |
| ``reward_scope`` | ``"team"`` (default), ``"local"`` | team: every robot receives the team reward. local: a block's distance term is split among the robots attached to it, a robot's attachment term goes to that robot, the rest equally to all robots; the robots' rewards sum to the team reward. |

## Global state
``state_space`` (a ``Box``) and ``state()``: one float32 vector of every robot's pose and
attachment, every block's pose and gathered flag and the step fraction, for centralised
critics (MAPPO, QMIX); layout in ``gathering_env.state`` and docs/environment.md. ``state()``
before ``reset`` raises ``ValueError``.

## Episode end
*Terminated* when every block lies wholly inside the zone; *truncated* after
``max_cycles`` steps (default 10 000). Agents are removed when the episode ends; calling
``step`` afterwards raises ``RuntimeError``.

## Infos
``gathered_value``, ``total_value``, ``blocks_gathered`` (count), ``blocks_gathered_by_type``
(small, medium, large), ``steps``, ``task_performance`` (ft of the episode so far, final at its
end; present at every step so that wrappers which fix their info specs at reset, such as
TorchRL's ``PettingZooWrapper``, see it).

## Arguments
``parallel_env(environment=2, num_robots=20, max_cycles=10_000, render_mode=None,
render_options=None, morphology=None, **world_parameters)``: ``environment`` picks the paper's
block counts (1: 10/5/0, 2: 5/5/5, 3: 0/5/10); any field of ``WorldConfig`` can be overridden by
keyword. ``reset(seed=..., options={"morphology": Morphology | list of sensor dicts})``.

## Rendering
``render_mode="rgb_array"`` (frames as arrays) or ``"human"`` (a pygame window with keys).
``render_options={"cones": ..., "view": ..., "size_px": ..., "trail": ..., "panel": ...,
"min_robot_px": ...}`` choose what frames show (``gathering_env.render``, ``docs/rendering.md``);
``render(**options)`` overrides them for one frame.

## Kernels
``kernel="compiled"`` (default) computes everything of a step but pymunk's physics in numba
kernels; ``kernel="numpy"`` uses the vectorised numpy reference. Both give the same
episodes (tested bit for bit); the compiled one is several times faster (docs/performance.md).
The first use of the compiled kernel in a fresh environment compiles it (a few seconds, once;
the machine code is cached on disk, see ``gathering_env.compiled.kernels``).

## Many worlds
``gathering_env.vector.VectorSimulation(num_worlds, **world_parameters)`` steps W
independent episodes together (arrays of shape (W, N, ...)); each world's episode is the
one this env gives for the same seed.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import asdict
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv
from pettingzoo.utils import wrappers
from pettingzoo.utils.conversions import parallel_to_aec_wrapper

from .config import WorldConfig
from .render import RenderOptions
from .sensors import Morphology
from .simulation import GatheringSimulation, check_wheels
from .state import state_space, world_state
from .world import GatheringWorld

_ACTION_SPACE_BOUNDS = (-1.0, 1.0)


class GatheringEnv(ParallelEnv):
    """The collective gathering task (see the module docstring for spaces and rewards)."""

    metadata = {
        "name": "collective_gathering_v0",
        "render_modes": ["human", "rgb_array"],
        "render_fps": 30,
        "is_parallelizable": True,
    }

    def __init__(self, environment: int | None = 2, render_mode: str | None = None,
                 morphology: Morphology | list | dict | None = None,
                 render_options: dict[str, Any] | None = None, **world_parameters: Any) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode={render_mode!r}; allowed: None, {self.metadata['render_modes']}"
            )
        self.config = WorldConfig.from_kwargs(environment=environment, **world_parameters)
        GatheringWorld.check_placement(self.config)  # an impossible world fails here, not at reset
        self.render_mode = render_mode
        if render_options is not None and not isinstance(render_options, dict):
            raise TypeError(f"render_options={render_options!r}; allowed: None or a dict of render options")
        self.render_options = RenderOptions.checked(self.config.num_robots, **(render_options or {}))
        self.morphology = Morphology.khepera_iii() if morphology is None else Morphology.coerce(morphology)
        self.sim = GatheringSimulation(self.config, self.morphology)
        n = self.config.num_robots
        self.possible_agents = [f"robot_{i}" for i in range(n)]
        self._agent_index = {a: i for i, a in enumerate(self.possible_agents)}
        self.agents: list[str] = []
        self._action_space = spaces.Box(*_ACTION_SPACE_BOUNDS, shape=(2,), dtype=np.float32)
        self._action_spaces = {a: self._action_space for a in self.possible_agents}
        self._set_observation_spaces()
        self.state_space = state_space(self.config)
        self._np_random: np.random.Generator | None = None
        self._renderer = None

    # ------------------------------------------------------------------ spaces
    def _set_observation_spaces(self) -> None:
        space = spaces.Box(0.0, 1.0, shape=(len(self.morphology),), dtype=np.float32)
        self._observation_spaces = {a: space for a in self.possible_agents}

    def observation_space(self, agent: str) -> spaces.Box:
        """``Box(0, 1, (num_sensors,), float32)``; follows the morphology set at reset."""
        return self._observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Box:
        """``Box(-1, 1, (2,), float32)``: left and right wheel drive."""
        return self._action_spaces[agent]

    def state(self) -> np.ndarray:
        """The global state (``state_space``; layout in ``gathering_env.state``) of the current step."""
        if self._np_random is None:
            raise ValueError("state() called before reset(); allowed: call reset() first, then state()")
        sim, w = self.sim, self.sim.world
        return world_state(self.config, w.robot_pos, w.robot_angle, w.robot_attached, w.block_pos,
                           w.block_angle, sim.gathered, sim.steps)

    # ------------------------------------------------------------------ episode
    def reset(self, seed: int | None = None, options: dict | None = None):
        """Start an episode. ``options={"morphology": ...}`` replaces the sensor suite.

        Every random choice (positions, headings) comes from ``seed``; with ``seed=None``
        the generator seeded at the previous reset continues.
        """
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer))):
            raise TypeError(f"seed={seed!r} must be an integer >= 0 or None")
        if seed is not None and seed < 0:
            raise ValueError(f"seed={seed!r} out of range; allowed: an integer >= 0 or None")
        if options is not None and not isinstance(options, Mapping):
            raise TypeError(f"options={options!r} must be a dict (e.g. {{'morphology': ...}}) or None")
        if options:
            unknown = sorted(set(options) - {"morphology"}, key=str)
            if unknown:
                warnings.warn(f"ignoring unknown reset option(s) {unknown}; known: ['morphology']",
                              stacklevel=2)
            if options.get("morphology") is not None:
                morphology = Morphology.coerce(options["morphology"])
                if morphology != self.morphology:
                    self.morphology = morphology
                    self._set_observation_spaces()
        if seed is not None or self._np_random is None:
            self._np_random = np.random.default_rng(seed)
        obs = self.sim.reset(self._np_random, self.morphology)
        self.agents = list(self.possible_agents)
        if self.render_mode is not None:
            self._get_renderer().record(self.sim)
        if self.render_mode == "human":
            self.render()
        observations = dict(zip(self.agents, obs))
        info = self._team_info()
        return observations, {a: dict(info) for a in self.agents}

    def step(self, actions: dict[str, Any]):
        """Apply one action per live agent; returns the five PettingZoo dicts."""
        if not self.agents:
            raise RuntimeError(
                "step() called after the episode ended (or before reset()); call reset() first"
            )
        if not isinstance(actions, Mapping):
            raise TypeError(f"actions must be a dict {{agent: (left, right)}}; got {type(actions).__name__}")
        if actions.keys() != self._agent_index.keys():
            self._explain_action_keys(actions)
        try:
            wheels = np.array([actions[a] for a in self.possible_agents], dtype=np.float64)
        except (ValueError, TypeError):
            wheels = None
        if wheels is None or wheels.shape != (len(self.possible_agents), 2):
            self._explain_action_shapes(actions)
        if not np.isfinite(wheels).all():
            row = int(np.argwhere(~np.isfinite(wheels))[0, 0])
            raise ValueError(
                f"action of {self.possible_agents[row]} is {wheels[row].tolist()}: NaN/inf not "
                "allowed; allowed: finite values, clipped to [-1, 1]"
            )
        obs, reward, terminated, truncated = self.sim.step(wheels)
        agents = self.agents
        observations = dict(zip(agents, obs))
        if self.config.reward_scope == "local":
            rewards = dict(zip(agents, self.sim.robot_reward.tolist()))
        else:
            rewards = dict.fromkeys(agents, reward)
        terminations = dict.fromkeys(agents, terminated)
        truncations = dict.fromkeys(agents, truncated)
        info = self._team_info()
        infos = {a: info.copy() for a in agents}
        if terminated or truncated:
            self.agents = []
        if self._renderer is not None:
            self._renderer.record(self.sim)
        if self.render_mode == "human":
            self.render()
        return observations, rewards, terminations, truncations, infos

    def step_batch(self, wheels: np.ndarray) -> tuple[np.ndarray, float, bool, bool]:
        """Dict-free fast path for whole-team controllers.

        Args:
            wheels: (num_robots, 2) wheel commands in robot order (robot_0 first).

        Returns:
            (observations (num_robots, num_sensors) float32, team reward, terminated,
            truncated). ``infos`` are available from ``team_info()``, per-robot rewards
            (``reward_scope``) from ``sim.robot_reward``. Ends the episode
            (``agents == []``) on termination or truncation, like ``step``.
        """
        if not self.agents:
            raise RuntimeError(
                "step_batch() called after the episode ended (or before reset()); call reset() first"
            )
        obs, reward, terminated, truncated = self.sim.step(check_wheels(wheels, len(self.possible_agents)))
        if terminated or truncated:
            self.agents = []
        if self._renderer is not None:
            self._renderer.record(self.sim)
        return obs, reward, terminated, truncated

    def team_info(self) -> dict[str, Any]:
        """The info dict every agent receives (see the module docstring)."""
        return self._team_info()

    def _team_info(self) -> dict[str, Any]:
        sim = self.sim
        by_type = sim.blocks_gathered_by_type()
        info: dict[str, Any] = {
            "gathered_value": sim.gathered_value,
            "total_value": sim.total_value,
            "blocks_gathered": int(sum(by_type)),
            "blocks_gathered_by_type": by_type,
            "steps": sim.steps,
            "task_performance": sim.task_performance(),
        }
        return info

    def _explain_action_keys(self, actions: dict[str, Any]) -> None:
        unknown = sorted(set(actions) - self._agent_index.keys(), key=str)
        if unknown:
            raise ValueError(
                f"actions for unknown agent(s) {unknown}; allowed: robot_0 ... robot_{len(self.possible_agents) - 1}"
            )
        missing = sorted(self._agent_index.keys() - set(actions), key=self._agent_index.get)
        raise ValueError(f"actions missing for agent(s) {missing}; every live agent must act")

    def _explain_action_shapes(self, actions: dict[str, Any]) -> None:
        for agent in self.possible_agents:
            try:
                shape = np.asarray(actions[agent], dtype=np.float64).shape
            except (ValueError, TypeError):
                raise ValueError(
                    f"action of {agent} is {actions[agent]!r}; allowed: 2 numbers (left, right wheel)"
                ) from None
            if shape != (2,):
                raise ValueError(f"action of {agent} has shape {shape}; expected (2,) (left, right wheel)")
        raise ValueError("actions could not be stacked into a (num_robots, 2) array")

    # ------------------------------------------------------------------ rendering
    def render(self, **options: Any):
        """'rgb_array': (H, W, 3) uint8 frame; 'human': draw into a pygame window.

        ``options`` (render options, see ``render_options``) apply to this frame only.
        """
        if self.render_mode is None:
            import gymnasium

            gymnasium.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' or 'human'")
            return None
        return self._get_renderer().render(self.sim, **options)

    def _get_renderer(self):
        if self._renderer is None:
            from .render import Renderer

            self._renderer = Renderer(self.config, self.render_mode, fps=self.metadata["render_fps"],
                                      **asdict(self.render_options))
        return self._renderer

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


def parallel_env(**kwargs: Any) -> GatheringEnv:
    """The task as a PettingZoo ``ParallelEnv`` (keyword arguments: see ``GatheringEnv``)."""
    return GatheringEnv(**kwargs)


def raw_env(**kwargs: Any) -> parallel_to_aec_wrapper:
    """The task as an AEC env (PettingZoo's parallel-to-AEC conversion, no wrappers)."""
    return parallel_to_aec_wrapper(parallel_env(**kwargs))


def env(**kwargs: Any):
    """The AEC env with PettingZoo's usual order-enforcing wrapper.

    (Out-of-bounds actions are clipped by the env itself, so no clip/assert wrapper.)
    """
    return wrappers.OrderEnforcingWrapper(raw_env(**kwargs))
