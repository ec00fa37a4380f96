"""One episode of collective gathering as arrays in, arrays out (no dicts, no agent names).

``GatheringSimulation`` is the engine behind the PettingZoo env and the fast path for
trainers that drive the whole team at once:

    sim = GatheringSimulation(WorldConfig.from_kwargs(environment=2))
    obs = sim.reset(seed=0, morphology=Morphology.khepera_iii())    # (N, S) float32
    obs, reward, terminated, truncated = sim.step(wheels)            # wheels: (N, 2)

Step order (docs/model.md §2): the controller's wheel commands (computed from the previous
observation) -> heuristics override them (collision avoidance, attached robots) -> drive
-> physics step -> pickup -> scoring -> sensing of the new state.

Two kernels compute the same step, chosen by ``WorldConfig.kernel``:

* ``"compiled"`` (default): ``CompiledSimulation``, numba kernels around pymunk
  (``gathering_env.compiled.engine``; one world of the batched engine).
* ``"numpy"``: ``NumpySimulation``, the vectorised numpy reference (``sensing``,
  ``heuristics``, ``scoring``) that the tests compare the compiled kernels against.

``GatheringSimulation(config)`` returns the one the config names.
"""

from __future__ import annotations

import numpy as np

from .compiled.engine import CompiledWorlds
from .config import WorldConfig
from .reference.heuristics import attached_wheels, avoidance_turns, pickup_candidates
from .reference.sensing import SensorBank
from .rewards import RewardShaper
from .scoring import gathered_mask, task_performance
from .sensors import Morphology
from .world import GatheringWorld


class GatheringSimulation:
    """The task's state machine over a ``GatheringWorld``.

    ``GatheringSimulation(config, morphology=None)`` builds the subclass of
    ``config.kernel``; both have the same interface and give the same episodes.

    Attributes (after ``reset``):
        world: the pymunk world. steps: steps taken. done: the episode has ended.
        gathered: (B,) bool blocks wholly inside the zone.
        gathered_value: sum of the values of gathered blocks (v_c).
    """

    def __new__(cls, config: WorldConfig | None = None, morphology: Morphology | None = None):
        if cls is GatheringSimulation and config is not None:
            cls = CompiledSimulation if config.kernel == "compiled" else NumpySimulation
        return super().__new__(cls)

    def __init__(self, config: WorldConfig, morphology: Morphology | None = None) -> None:
        self.config = config
        self.morphology = morphology if morphology is not None else Morphology.khepera_iii()
        self.total_value = config.total_value

    @staticmethod
    def _generator(seed: int | np.random.Generator | None) -> np.random.Generator:
        return seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)

    def reset(self, seed: int | np.random.Generator | None = None,
              morphology: Morphology | None = None) -> np.ndarray:
        """Start a new episode; returns the first observation (N, S) float32."""
        raise NotImplementedError

    def observe(self) -> np.ndarray:
        """Current readings of every robot's sensors, (N, S) float32 in [0, 1]."""
        raise NotImplementedError

    def step(self, wheels: np.ndarray) -> tuple[np.ndarray, float, bool, bool]:
        """Advance one step.

        Args:
            wheels: (N, 2) finite left/right wheel commands; values outside [-1, 1] are
                clipped. (Validation of shape and finiteness is the caller's job; the
                env and ``check_wheels`` do it.)

        Returns:
            (observation (N, S) float32, team reward, terminated, truncated). With the
            default ``reward="task"`` the reward is ``100 * (change in gathered value) /
            total value``, so an episode's rewards sum to the value part of eq. 1; with
            ``reward="shaped"`` it includes the shaping terms (``gathering_env.rewards``).
            ``robot_reward`` holds the step's per-robot rewards (``reward_scope``).
        """
        raise NotImplementedError

    @property
    def robot_reward(self) -> np.ndarray:
        """(N,) each robot's reward of the last step: the team reward for every robot with
        ``reward_scope="team"``, the local rewards (summing to it) with ``"local"``."""
        robot = self._robot_reward
        return np.full(self.config.num_robots, self.reward) if robot is None else robot.copy()

    # ------------------------------------------------------------------ statistics
    def blocks_gathered_by_type(self) -> tuple[int, int, int]:
        """Gathered blocks per type (small, medium, large)."""
        key = self.gathered.tobytes()
        cached = self.__dict__.get("_by_type")
        if cached is None or cached[0] != key or cached[1] is not self.world.block_type:
            counts = np.bincount(self.world.block_type[self.gathered], minlength=3)
            cached = (key, self.world.block_type, (int(counts[0]), int(counts[1]), int(counts[2])))
            self._by_type = cached
        return cached[2]

    def task_performance(self) -> float:
        """Paper eq. 1 for the episode so far (final once the episode has ended)."""
        return task_performance(self.gathered_value, self.total_value, self.steps,
                                self.config.max_cycles, self.config.time_bonus)


class NumpySimulation(GatheringSimulation):
    """The numpy reference kernel (``kernel="numpy"``). ``bank``: its ``SensorBank``."""

    def __init__(self, config: WorldConfig, morphology: Morphology | None = None) -> None:
        super().__init__(config, morphology)
        self.world = GatheringWorld(config)
        self.steps = 0
        self.done = True

    def reset(self, seed: int | np.random.Generator | None = None,
              morphology: Morphology | None = None) -> np.ndarray:
        if morphology is not None:
            self.morphology = morphology
        self.world.reset(self._generator(seed))
        w = self.world
        self.bank = SensorBank(self.morphology, self.config, w.block_half, w.block_need)
        self.shaper = RewardShaper(self.config, w.block_half, w.block_value)
        self.reward, self._robot_reward = 0.0, None
        self.steps = 0
        self.done = False
        self.gathered = gathered_mask(w.block_pos, w.block_angle, w.block_half, self.config.zone_rect)
        self.gathered_value = float(self.world.block_value[self.gathered].sum())
        return self.observe()

    def observe(self) -> np.ndarray:
        w = self.world
        return self.bank.read(w.robot_pos, w.robot_angle, w.block_pos, w.block_angle)

    def step(self, wheels: np.ndarray) -> tuple[np.ndarray, float, bool, bool]:
        if self.done:
            raise RuntimeError("step() called after the episode ended; call reset() first")
        cfg, w = self.config, self.world
        shaper = self.shaper
        if shaper.active:
            shaper.before(w.block_pos[None], w.robot_attached[None])
        wheels = np.clip(wheels, -1.0, 1.0)
        if cfg.collision_avoidance:
            wheels = avoidance_turns(w, wheels)
        attached = np.flatnonzero(w.robot_attached >= 0)
        if attached.size:
            wheels[attached] = attached_wheels(w, attached)
        w.apply_drive(wheels)
        w.step_physics()
        self.steps += 1

        gathered = gathered_mask(w.block_pos, w.block_angle, w.block_half, cfg.zone_rect)
        if cfg.pickup_heuristic:
            for robot, block in pickup_candidates(w, gathered):
                if w.robot_attached[robot] < 0:
                    w.try_attach(robot, block)
        newly = np.flatnonzero(gathered & ~self.gathered)
        for block in newly:
            w.detach_block(int(block))
        self.gathered = gathered
        value = float(w.block_value[gathered].sum())
        reward = 100.0 * (value - self.gathered_value) / self.total_value
        self.gathered_value = value
        self._robot_reward = None
        if shaper.active:
            team, robot = shaper.after(np.array([reward]), w.block_pos[None], w.robot_attached[None])
            reward, self._robot_reward = float(team[0]), robot[0]
        self.reward = reward

        terminated = bool(gathered.all())
        truncated = (not terminated) and self.steps >= cfg.max_cycles
        self.done = terminated or truncated
        return self.observe(), reward, terminated, truncated


class CompiledSimulation(GatheringSimulation):
    """The compiled kernel (``kernel="compiled"``): one world of ``CompiledWorlds``."""

    def __init__(self, config: WorldConfig, morphology: Morphology | None = None) -> None:
        super().__init__(config, morphology)
        self.engine = CompiledWorlds(config, 1)
        self.world = self.engine.worlds[0]
        self._started = False
        self.reward, self._robot_reward = 0.0, None

    def reset(self, seed: int | np.random.Generator | None = None,
              morphology: Morphology | None = None) -> np.ndarray:
        if morphology is not None:
            self.morphology = morphology
        self.engine.reset([self._generator(seed)], self.morphology)
        self._started = True
        self.reward, self._robot_reward = 0.0, None
        return self.engine.obs[0].copy()

    def observe(self) -> np.ndarray:
        self.engine.sense(np.ones(1, dtype=np.bool_))
        return self.engine.obs[0].copy()

    def step(self, wheels: np.ndarray) -> tuple[np.ndarray, float, bool, bool]:
        engine = self.engine
        if not engine.active[0]:
            raise RuntimeError("step() called after the episode ended; call reset() first")
        engine.step(np.asarray(wheels, dtype=np.float64).reshape(1, -1, 2))
        self.reward = float(engine.reward[0])
        self._robot_reward = None if engine.robot_reward is None else engine.robot_reward[0]
        return (engine.obs[0].copy(), float(engine.reward[0]), bool(engine.terminated[0]),
                bool(engine.truncated[0]))

    @property
    def steps(self) -> int:
        return int(self.engine.steps[0]) if self._started else 0

    @property
    def done(self) -> bool:
        return not self._started or not bool(self.engine.active[0])

    @property
    def gathered(self) -> np.ndarray:
        return self.engine.gathered[0]

    @property
    def gathered_value(self) -> float:
        return float(self.engine.gathered_value[0])


def check_wheels(wheels: np.ndarray, num_robots: int) -> np.ndarray:
    """Validate a team action array: shape (num_robots, 2), finite. Returns float64 copy."""
    arr = np.asarray(wheels, dtype=np.float64)
    if arr.shape != (num_robots, 2):
        raise ValueError(f"actions have shape {arr.shape}; expected ({num_robots}, 2) (left, right wheel)")
    if not np.isfinite(arr).all():
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise ValueError(
            f"action of robot_{bad[0]} is {arr[bad[0]].tolist()}: NaN/inf not allowed; "
            "allowed: finite values (clipped to [-1, 1])"
        )
    return arr
