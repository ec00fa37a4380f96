"""The compiled step of W worlds: pymunk for the physics, numba kernels for the rest.

``CompiledWorlds`` owns one ``GatheringWorld`` (one pymunk space) per world and every
world's state as (W, ...) arrays; each world's ``robot_pos``, ``anchor_owner``, ... are views
of them (``GatheringWorld.adopt``). A step of the batch is

    kernels.drive   (one call: all worlds' wheel commands -> control velocities)
    per world:      pymunk set velocities, space.step, get poses and velocities
    kernels.settle  (one call: poses, gathered blocks, pickup, release, step bookkeeping)
    kernels.sense   (one call: every sensor of every robot of every world)
    per event:      add or remove the weld joints of robots that attached or were released

The worlds share nothing but their configuration and morphology, so each world's
trajectory is exactly the one it has when stepped alone (W = 1). Ended worlds are masked
out: they are not stepped and keep their last state until ``reset_world``.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence

import numpy as np

from ..config import WorldConfig
from ..rewards import RewardShaper
from ..sensors import Morphology
from ..world import STATE_ARRAYS, GatheringWorld
from . import kernels

COMPILE_SECONDS = 10
"""About how long the first compile of the kernels takes on one core of a 2-core machine
(measured 7-9 s; once per installation, numba caches the machine code on disk)."""
_announced = False


def announce_compile(stream=None) -> bool:
    """Print one line to ``stream`` (stderr) if the kernels have no usable cache yet and will be
    compiled on first use; once per process. Returns whether the line was printed."""
    global _announced
    if _announced:
        return False
    _announced = True
    try:  # numba's cache index: empty when missing or stale (source changed)
        cold = any(not d._cache._cache_file._load_index()
                   for d in (kernels.sense, kernels.drive, kernels.settle, kernels.gathered_blocks))
    except Exception:  # another numba layout: say nothing rather than guess
        return False
    if cold:
        print(f"compiling the simulation kernels once, ~{COMPILE_SECONDS} s", file=stream or sys.stderr, flush=True)
    return cold


class CompiledWorlds:
    """W independent episodes of one configuration, stepped by the compiled kernels.

    Arrays (after ``reset``): ``robot_pos`` (W, N, 2), ``robot_angle`` (W, N), ``block_pos``
    (W, B, 2), ``block_angle`` (W, B), ``robot_attached`` (W, N), ``block_sticky_side``
    (W, B), ``anchor_owner`` (W, B, K), ``gathered`` (W, B) bool, ``gathered_value`` (W,),
    ``obs`` (W, N, S) float32, ``steps`` (W,) int, ``reward`` (W,) team reward of the last step
    (``WorldConfig.reward``), ``robot_reward`` (W, N) per-robot rewards of the last step (None
    for the default task reward with team scope, where every robot gets ``reward``),
    ``terminated`` / ``truncated`` (W,) bool.
    """

    def __init__(self, config: WorldConfig, num_worlds: int) -> None:
        announce_compile()
        self.config = config
        self.num_worlds = int(num_worlds)
        self.params, self.flags = kernels.world_params(config)
        self.total_value = config.total_value
        self.worlds = [GatheringWorld(config) for _ in range(self.num_worlds)]
        self.morphology: Morphology | None = None
        self.timings: dict[str, float] | None = None
        """Set to a dict to accumulate seconds per phase of ``step`` (drive, physics,
        settle, sensing) — what the benchmarks report; None (default) records nothing."""

    # ------------------------------------------------------------------ episodes
    def reset(self, rngs: Sequence[np.random.Generator], morphology: Morphology) -> None:
        """Build every world afresh from its generator; readings of the first state in ``obs``."""
        if len(rngs) != self.num_worlds:
            raise ValueError(f"{len(rngs)} generators given; expected one per world ({self.num_worlds})")
        self.morphology = morphology
        self.table = kernels.sensor_table(morphology)
        for world, rng in zip(self.worlds, rngs):
            world.reset(rng)
        self._allocate()
        for w in range(self.num_worlds):
            self._bind(w)
        self.active = np.ones(self.num_worlds, dtype=np.bool_)
        self._start(self.active)

    def reset_world(self, w: int, rng: np.random.Generator) -> None:
        """Start a new episode in world ``w`` only (same morphology)."""
        self.worlds[w].reset(rng)
        self._bind(w)
        only = np.zeros(self.num_worlds, dtype=np.bool_)
        only[w] = True
        self._start(only)

    def _allocate(self) -> None:
        cfg, first = self.config, self.worlds[0]
        w, n, b = self.num_worlds, cfg.num_robots, len(first.block_half)
        self.robot_pos = np.zeros((w, n, 2))
        self.robot_angle = np.zeros((w, n))
        self.block_pos = np.zeros((w, b, 2))
        self.block_angle = np.zeros((w, b))
        self.robot_attached = np.full((w, n), -1, dtype=np.int64)
        self.block_sticky_side = np.full((w, b), -1, dtype=np.int64)
        self.anchor_owner = np.full((w, b, first.anchor_slots), -1, dtype=np.int64)
        self.raw = np.zeros((w,) + first.raw.shape)
        self.vel = np.zeros((w, first.raw.shape[0], first.drive_columns))
        self._shuffled = cfg.schedule == "shuffled"
        self.times = np.ones((w, n), dtype=np.int64)   # force-drive actions a step (drive.shuffled_times)
        self._vel_rows = list(self.vel)   # fixed views: pymunk keeps the buffer registered
        self.robot_rows = np.zeros((w, n), dtype=np.intp)
        self.block_rows = np.zeros((w, b), dtype=np.intp)
        self.control_rows = np.zeros((w, n), dtype=np.intp)
        self.gathered = np.zeros((w, b), dtype=np.bool_)
        self.gathered_value = np.zeros(w)
        self.steps = np.zeros(w, dtype=np.int64)
        self.reward = np.zeros(w)
        self.terminated = np.zeros(w, dtype=np.bool_)
        self.truncated = np.zeros(w, dtype=np.bool_)
        self.obs = np.zeros((w, n, len(self.morphology)), dtype=np.float32)
        self.block_half = first.block_half.astype(np.float64)
        self.block_need = first.block_need.astype(np.float64)
        self.block_value = first.block_value.astype(np.float64)
        # room for every robot attaching and every robot being released in one step
        self.shaper = RewardShaper(cfg, self.block_half, self.block_value)
        self.robot_reward = np.zeros((w, n)) if self.shaper.active else None
        self._events = np.zeros((2 * w * n, 5), dtype=np.int64)
        self._weld_points = np.zeros((2 * w * n, 2))

    def _bind(self, w: int) -> None:
        world = self.worlds[w]
        world.adopt({name: getattr(self, name)[w] for name in STATE_ARRAYS})
        self.robot_rows[w] = world._robot_rows
        self.block_rows[w] = world._block_rows
        self.control_rows[w] = world._control_rows

    def _start(self, which: np.ndarray) -> None:
        """Episode bookkeeping and first readings of the worlds in ``which``."""
        kernels.gathered_blocks(self.block_pos, self.block_angle, self.block_half, self.params, which,
                                self.gathered)
        self.gathered_value[which] = (self.gathered[which] * self.block_value).sum(axis=1)
        self.active[which] = True
        self.steps[which] = 0
        self.reward[which] = 0.0
        if self.robot_reward is not None:
            self.robot_reward[which] = 0.0
        self.terminated[which] = False
        self.truncated[which] = False
        self.sense(which)

    def sense(self, which: np.ndarray | None = None) -> None:
        """Refresh ``obs`` of the worlds in ``which`` (default: all) from the current poses."""
        kernels.sense(self.robot_pos, self.robot_angle, self.block_pos, self.block_angle, self.block_half,
                      self.block_need, self.table, self.params, self.flags,
                      self.active if which is None else which, self.obs)

    # ------------------------------------------------------------------ stepping
    def step(self, wheels: np.ndarray) -> None:
        """Advance every active world by one step with ``wheels`` (W, N, 2), finite.

        Updates the state arrays, ``obs``, ``reward``, ``steps``, ``terminated``,
        ``truncated`` and ``active`` (worlds that end are masked out)."""
        clock = time.perf_counter
        t0 = clock()
        active = self.active
        stepped = active.copy()
        shaper = self.shaper
        if shaper.active:
            shaper.before(self.block_pos, self.robot_attached)
        if self._shuffled:
            for w, world in enumerate(self.worlds):
                if active[w]:
                    self.times[w] = world.schedule_times()
        kernels.drive(wheels, self.robot_pos, self.robot_angle, self.robot_attached, self.robot_rows,
                      self.control_rows, self.raw, self.params, self.flags, active, self.times, self.vel)
        substeps = self.config.physics_substeps
        h = self.config.dt / substeps
        vel = self._vel_rows
        t1 = clock()
        for w, world in enumerate(self.worlds):
            if not active[w]:
                continue
            world.set_drive(vel[w])
            space = world.space
            for _ in range(substeps):
                space.step(h)
            world.fetch_raw()
        t2 = clock()
        count = kernels.settle(
            self.raw, self.robot_rows, self.block_rows, active, self.block_half, self.block_need,
            self.block_value, self.params, self.flags, self.robot_pos, self.robot_angle, self.block_pos,
            self.block_angle, self.robot_attached, self.block_sticky_side, self.anchor_owner, self.gathered,
            self.gathered_value, self.steps, self.reward, self.terminated, self.truncated,
            self._events, self._weld_points)
        if count:
            self._apply_events(count)
        if shaper.active:
            self.reward[:], self.robot_reward[:] = shaper.after(self.reward, self.block_pos, self.robot_attached)
        t3 = clock()
        self.sense(stepped)
        if self.timings is not None:
            t4 = clock()
            for phase, seconds in (("drive", t1 - t0), ("physics", t2 - t1), ("settle", t3 - t2),
                                   ("sensing", t4 - t3)):
                self.timings[phase] = self.timings.get(phase, 0.0) + seconds

    def _apply_events(self, count: int) -> None:
        """The pymunk joints of this step's attachments and releases (arrays are up to date)."""
        for (kind, w, robot, block, slot), front in zip(self._events[:count].tolist(),
                                                        self._weld_points[:count]):
            if kind == kernels.EV_ATTACH:
                self.worlds[w].weld(robot, block, slot, front)
            else:
                self.worlds[w].unweld(robot)

    # ------------------------------------------------------------------ pickling
    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state.pop("_vel_rows", None)
        return state

    def __setstate__(self, state: dict) -> None:
        """Views do not survive pickling: make the worlds' arrays views of ours again."""
        self.__dict__.update(state)
        if hasattr(self, "raw"):
            self._vel_rows = list(self.vel)
            for w in range(self.num_worlds):
                self._bind(w)
