"""Many worlds per call: W independent episodes of one configuration and morphology.

``VectorSimulation`` steps W worlds (each with its own pymunk space and seed) together:
one compiled call drives all W x N robots, one senses them, and a whole-team controller
runs once on the stacked ``(W * N, S)`` readings::

    from gathering_env.vector import VectorSimulation

    sims = VectorSimulation(num_worlds=5, environment=2, max_cycles=1000)
    obs = sims.reset(seeds=[0, 1, 2, 3, 4])                # (W, N, S) float32
    while sims.active.any():
        wheels = controller.act(obs.reshape(-1, obs.shape[-1])).reshape(5, -1, 2)
        obs, reward, terminated, truncated = sims.step(wheels)
    ft = sims.task_performance()                           # (W,) paper eq. 1

Shapes: W worlds, N robots, S sensors, B blocks.

* ``reset(seeds, morphology=None)`` -> obs ``(W, N, S)`` float32. One seed (int, None or
  ``numpy.random.Generator``) per world; world w's episode is exactly the one
  ``GatheringSimulation.reset(seed=seeds[w])`` starts.
* ``step(wheels)``: wheels ``(W, N, 2)`` finite (clipped to [-1, 1]) -> ``(obs (W, N, S),
  reward (W,), terminated (W,), truncated (W,))``. Worlds whose episode has ended are masked
  out: they are not stepped, get reward 0, keep their last observation and keep reporting
  terminated/truncated until ``reset_world``. ``active`` (W,) says which worlds still run.
* ``reset_world(w, seed)`` -> obs ``(N, S)``: a new episode in one world (auto-reset).
* ``robot_rewards()`` (W, N): each robot's reward of the last step (``reward_scope``).
* ``observations()`` (W, N, S): the current readings (after ``reset``, ``step`` or ``reset_world``).
* ``states()`` (W, D) float32: each world's global state (``gathering_env.state``).
* ``task_performance()`` (W,), ``gathered_value`` (W,), ``steps`` (W,),
  ``blocks_gathered_by_type()`` (W, 3).

Each world's trajectory is identical to stepping it alone, with either kernel
(``kernel="compiled"``, the default, or the ``"numpy"`` reference, which steps W
``NumpySimulation`` objects in a loop).
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from typing import Any

import numpy as np

from .compiled.engine import CompiledWorlds
from .config import WorldConfig
from .scoring import task_performance
from .sensors import Morphology
from .simulation import GatheringSimulation, NumpySimulation
from .state import world_state

Seed = int | np.random.Generator | None

MAX_WORLDS = 4096
"""Upper bound on ``num_worlds`` (each world holds a pymunk space of ~60 bodies)."""


class VectorSimulation:
    """W independent episodes of one configuration, stepped together (see the module docstring).

    Args:
        num_worlds: W, in [1, MAX_WORLDS].
        config: a ``WorldConfig``; or leave it out and pass ``WorldConfig.from_kwargs``
            keyword arguments (``environment=2``, ``max_cycles=...``, ``kernel=...``, ...).
        morphology: the sensor suite of every robot (default: Khepera III).
    """

    def __init__(self, num_worlds: int, config: WorldConfig | None = None,
                 morphology: Morphology | Sequence | dict | None = None, **world_parameters: Any) -> None:
        if isinstance(num_worlds, bool) or not isinstance(num_worlds, numbers.Integral) \
                or not 1 <= int(num_worlds) <= MAX_WORLDS:
            raise ValueError(f"num_worlds={num_worlds!r}; allowed: an integer in [1, {MAX_WORLDS}]")
        if config is not None and world_parameters:
            raise ValueError(f"pass either config or world parameters, not both (got {sorted(world_parameters)})")
        self.config = config if config is not None else WorldConfig.from_kwargs(**world_parameters)
        self.num_worlds = int(num_worlds)
        self.morphology = Morphology.khepera_iii() if morphology is None else Morphology.coerce(morphology)
        self.total_value = self.config.total_value
        if self.config.kernel == "compiled":
            self._engine: CompiledWorlds | None = CompiledWorlds(self.config, self.num_worlds)
            self._sims: list[NumpySimulation] = []
        else:
            self._engine = None
            self._sims = [GatheringSimulation(self.config) for _ in range(self.num_worlds)]
        self._started = False

    # ------------------------------------------------------------------ episodes
    def reset(self, seeds: Sequence[Seed], morphology: Morphology | Sequence | dict | None = None) -> np.ndarray:
        """Start a new episode in every world; returns obs (W, N, S) float32."""
        if isinstance(seeds, (str, bytes)) or not isinstance(seeds, Sequence) or len(seeds) != self.num_worlds:
            raise ValueError(f"seeds must be a sequence of {self.num_worlds} seeds (one per world); got {seeds!r}")
        rngs = [_generator(s, f"seeds[{i}]") for i, s in enumerate(seeds)]
        if morphology is not None:
            self.morphology = Morphology.coerce(morphology)
        if self._engine is not None:
            self._engine.reset(rngs, self.morphology)
            obs = self._engine.obs.copy()
        else:
            obs = np.stack([sim.reset(rng, self.morphology) for sim, rng in zip(self._sims, rngs)])
            self._sync()
        self._started = True
        return obs

    def reset_world(self, world: int, seed: Seed = None) -> np.ndarray:
        """A new episode in world ``world`` (same morphology); returns its obs (N, S)."""
        self._require_started()
        if isinstance(world, bool) or not isinstance(world, numbers.Integral) or not 0 <= world < self.num_worlds:
            raise ValueError(f"world={world!r}; allowed: an integer in [0, {self.num_worlds - 1}]")
        rng = _generator(seed, "seed")
        if self._engine is not None:
            self._engine.reset_world(int(world), rng)
            return self._engine.obs[world].copy()
        obs = self._sims[world].reset(rng, self.morphology)
        self._sync()
        return obs

    def step(self, wheels: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """One step of every active world; see the module docstring for shapes."""
        self._require_started()
        if not self.active.any():
            raise RuntimeError("step() called with every world's episode ended; call reset() or reset_world()")
        wheels = self.check_wheels(wheels)
        if self._engine is not None:
            engine = self._engine
            engine.step(wheels)
            return engine.obs.copy(), engine.reward.copy(), engine.terminated.copy(), engine.truncated.copy()
        reward = np.zeros(self.num_worlds)
        self._robot_reward[:] = 0.0
        for w, sim in enumerate(self._sims):
            if not sim.done:
                self._obs[w], reward[w], self._terminated[w], self._truncated[w] = sim.step(wheels[w])
                self._robot_reward[w] = sim.robot_reward
        return self._obs.copy(), reward, self._terminated.copy(), self._truncated.copy()

    def check_wheels(self, wheels: np.ndarray) -> np.ndarray:
        """Validate a (W, N, 2) finite action array; returns it as float64."""
        arr = np.asarray(wheels, dtype=np.float64)
        expected = (self.num_worlds, self.config.num_robots, 2)
        if arr.shape != expected:
            raise ValueError(f"wheels have shape {arr.shape}; expected {expected} (world, robot, left/right)")
        if not np.isfinite(arr).all():
            w, i, _ = np.argwhere(~np.isfinite(arr))[0]
            raise ValueError(f"wheels of world {w}, robot_{i} are {arr[w, i].tolist()}: NaN/inf not allowed; "
                             "allowed: finite values (clipped to [-1, 1])")
        return arr

    def _require_started(self) -> None:
        if not self._started:
            raise RuntimeError("call reset(seeds) before stepping the worlds")

    def _sync(self) -> None:
        """numpy kernel: per-world status arrays after resets."""
        self._obs = np.stack([sim.observe() for sim in self._sims])
        self._terminated = np.array([sim.done and sim.gathered.all() for sim in self._sims])
        self._truncated = np.array([sim.done and not sim.gathered.all() for sim in self._sims])
        if not hasattr(self, "_robot_reward"):
            self._robot_reward = np.zeros((self.num_worlds, self.config.num_robots))

    # ------------------------------------------------------------------ status
    @property
    def active(self) -> np.ndarray:
        """(W,) bool: worlds whose episode is still running."""
        if self._engine is not None:
            return self._engine.active.copy() if self._started else np.zeros(self.num_worlds, bool)
        return np.array([not sim.done for sim in self._sims])

    @property
    def steps(self) -> np.ndarray:
        """(W,) steps taken in each world's current episode."""
        if self._engine is not None:
            return self._engine.steps.copy()
        return np.array([sim.steps for sim in self._sims], dtype=np.int64)

    @property
    def gathered_value(self) -> np.ndarray:
        """(W,) value of the blocks gathered in each world (v_c of eq. 1)."""
        if self._engine is not None:
            return self._engine.gathered_value.copy()
        return np.array([sim.gathered_value for sim in self._sims])

    def gathered(self) -> np.ndarray:
        """(W, B) bool: blocks wholly inside the zone."""
        if self._engine is not None:
            return self._engine.gathered.copy()
        return np.stack([sim.gathered for sim in self._sims])

    def blocks_gathered_by_type(self) -> np.ndarray:
        """(W, 3) gathered blocks per type (small, medium, large)."""
        gathered = self.gathered()
        types = self.worlds[0].block_type
        return np.stack([(gathered & (types == t)).sum(axis=1) for t in range(3)], axis=1)

    def robot_rewards(self) -> np.ndarray:
        """(W, N) each robot's reward of the last step (``WorldConfig.reward_scope``): the
        world's team reward for every robot ('team'), or local rewards summing to it ('local')."""
        if self._engine is not None:
            engine = self._engine
            if engine.robot_reward is None:
                return np.repeat(engine.reward[:, None], self.config.num_robots, axis=1)
            return engine.robot_reward.copy()
        return self._robot_reward.copy()

    def observations(self) -> np.ndarray:
        """(W, N, S) float32: every robot's current readings."""
        self._require_started()
        if self._engine is not None:
            return self._engine.obs.copy()
        return self._obs.copy()

    def states(self) -> np.ndarray:
        """(W, D) float32: each world's global state (layout in ``gathering_env.state``)."""
        self._require_started()
        gathered, steps = self.gathered(), self.steps
        return np.stack([world_state(self.config, w.robot_pos, w.robot_angle, w.robot_attached, w.block_pos,
                                     w.block_angle, gathered[i], int(steps[i]))
                         for i, w in enumerate(self.worlds)])

    def task_performance(self) -> np.ndarray:
        """(W,) paper eq. 1 of each world's episode so far (final once it has ended)."""
        cfg = self.config
        return np.array([task_performance(v, self.total_value, int(s), cfg.max_cycles, cfg.time_bonus)
                         for v, s in zip(self.gathered_value, self.steps)])

    @property
    def worlds(self) -> list:
        """The W ``GatheringWorld`` objects (pymunk spaces and state arrays), e.g. to render."""
        if self._engine is not None:
            return self._engine.worlds
        return [sim.world for sim in self._sims]


def _generator(seed: Seed, name: str) -> np.random.Generator:
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0):
        raise ValueError(f"{name}={seed!r}; allowed: a non-negative integer, None or a numpy Generator")
    return np.random.default_rng(seed)


__all__ = ["MAX_WORLDS", "VectorSimulation"]
