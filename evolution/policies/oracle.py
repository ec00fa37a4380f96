"""A privileged scripted team: it reads the world's state, not its sensors, and pushes every
block to the gathering zone with as many robots as the block needs.

No robot could run it (its robots know where every block is); it is an upper reference for
what a world allows: if this team gathers every block in S steps, a controller that needs
2 S is slow, not stopped by the physics. ``gathering-compare --policy oracle`` runs it beside
other teams on the same seeds.

Every step, for each robot (r the robot radius; c, h, need the block's centre, half side and
robots needed):

* **Assignment** (at the first step, every ``REASSIGN`` steps and whenever a block is gathered):
  each block not yet gathered offers ``need`` push slots, offsets along its rear face of 0
  (one robot), ±0.7 h (two) or -0.7 h, 0, 0.7 h (three); robots left over add slots on the
  blocks, those needing most robots first, at offsets 0, +0.5 h, -0.5 h in turn. Robots take
  slots greedily, the nearest robot-block pair first. A robot without a slot heads for the
  arena's centre.
* **Goal** of a block: the zone's middle line (half its depth from the south wall), at the
  block's x clipped to 1 + h inside the zone's ends. u is the unit vector from c to the goal, n
  its left normal, (a, l) the robot's position relative to c along u and n.
* **Target**: *through the block*, c + 2 u + o n, once the robot is behind it (a < -(h + r) +
  0.3) within 0.25 of its slot's line (|l - o| < 0.25); else *round it*, c ± (h + r + 0.5)(n -
  u) on the robot's side, while it is level with or ahead of the rear face (a > -(h + r)); else
  *to the slot*, c - (h + r + 0.1) u + o n. Targets are kept r + 0.05 inside the walls.
* **Steering**: heading error e to the target; |e| > 0.7 rad turns on the spot (wheels -1, 1
  towards it); otherwise full speed, wheels (1 - 2 e, 1 + 2 e) clipped to [-1, 1].

It draws no random numbers: an episode depends only on the world's seed.
"""

from __future__ import annotations

import math

import numpy as np

from evolution.policies.base import Policy
from gathering_env.sensors import Morphology

REASSIGN = 50
"""Steps between reassignments (also on every gathered block)."""
SPIN_ABOVE = 0.7
"""Heading error (rad) above which a robot turns on the spot."""
GAIN = 2.0
"""Steering gain: wheels 1 -/+ GAIN * error."""


class OracleTeam:
    """The privileged team (see the module docstring).

    ``bind(sim)`` gives it the episode's ``GatheringSimulation`` after each reset;
    ``act(obs) -> wheels (N, 2)`` ignores ``obs`` and reads ``sim``'s world.
    """

    def __init__(self) -> None:
        self.sim = None
        self.slot_block = self.slot_offset = None
        self.t = 0

    def reset(self, seed=None) -> None:
        self.sim, self.slot_block, self.t = None, None, 0

    def bind(self, sim) -> None:
        self.sim, self.slot_block, self.t = sim, None, 0

    def _slots(self, world, open_blocks: np.ndarray, n: int) -> tuple[list[int], list[float]]:
        blocks, offsets = [], []
        for b in open_blocks:
            need, h = int(world.block_need[b]), float(world.block_half[b])
            for o in ([0.0] if need == 1 else np.linspace(-0.7 * h, 0.7 * h, need)):
                blocks.append(int(b))
                offsets.append(float(o))
        spare = sorted(open_blocks, key=lambda b: (-int(world.block_need[b]), int(b)))
        k = 0
        while len(blocks) < n and spare:
            b = spare[k % len(spare)]
            blocks.append(int(b))
            offsets.append((0.0, 0.5, -0.5)[(k // len(spare)) % 3] * float(world.block_half[b]))
            k += 1
        return blocks, offsets

    def _assign(self, world, gathered: np.ndarray) -> None:
        n = len(world.robot_pos)
        blocks, offsets = self._slots(world, np.flatnonzero(~gathered), n)
        self.slot_block = np.full(n, -1)
        self.slot_offset = np.zeros(n)
        if not blocks:
            return
        dist = np.hypot(*(world.robot_pos[:, None, :] - world.block_pos[blocks][None, :, :]).transpose(2, 0, 1))
        robot_free, slot_free = np.ones(n, bool), np.ones(len(blocks), bool)
        for flat in np.argsort(dist, axis=None, kind="stable"):
            i, s = divmod(int(flat), len(blocks))
            if robot_free[i] and slot_free[s]:
                robot_free[i] = slot_free[s] = False
                self.slot_block[i], self.slot_offset[i] = blocks[s], offsets[s]

    def act(self, obs: np.ndarray) -> np.ndarray:
        if self.sim is None:
            raise RuntimeError("oracle: reads the world's state; bind(sim) after each reset "
                               "(gathering-compare and gathering-replay do)")
        world = self.sim.world
        gathered = np.asarray(self.sim.gathered, dtype=bool)
        if (self.slot_block is None or self.t % REASSIGN == 0
                or gathered[self.slot_block[self.slot_block >= 0]].any()):
            self._assign(world, gathered)
        self.t += 1
        return steer(world.robot_pos, world.robot_angle, self.targets())

    def targets(self) -> np.ndarray:
        """(N, 2) where each robot heads this step, from the current assignment."""
        world, cfg = self.sim.world, self.sim.config
        pos, r = world.robot_pos, cfg.robot_radius
        has = self.slot_block >= 0
        b = np.where(has, self.slot_block, 0)
        c, h, o = world.block_pos[b], world.block_half[b], self.slot_offset
        x0, y0, x1, y1 = cfg.zone_rect
        goal = np.stack((np.clip(c[:, 0], x0 + h + 1.0, np.maximum(x1 - h - 1.0, x0 + h + 1.0)),
                         np.full(len(b), 0.5 * (y0 + y1))), axis=1)
        u = goal - c
        u /= np.maximum(np.linalg.norm(u, axis=1), 1e-9)[:, None]
        nrm = np.stack((-u[:, 1], u[:, 0]), axis=1)
        a = np.einsum("ij,ij->i", pos - c, u)
        lat = np.einsum("ij,ij->i", pos - c, nrm)
        reach = (h + r)[:, None]
        push = (a < -(h + r) + 0.3) & (np.abs(lat - o) < 0.25)
        ahead = ~push & (a > -(h + r))
        side = np.where(lat >= 0, 1.0, -1.0)[:, None]
        target = np.where(push[:, None], c + 2.0 * u + o[:, None] * nrm,
                          np.where(ahead[:, None], c + side * (reach + 0.5) * nrm - (reach + 0.5) * u,
                                   c - (reach + 0.1) * u + o[:, None] * nrm))
        target[~has] = (0.5 * cfg.arena_width, 0.5 * cfg.arena_height)
        margin = r + 0.05
        return np.clip(target, margin, (cfg.arena_width - margin, cfg.arena_height - margin))


def steer(pos: np.ndarray, angle: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Wheels (N, 2) that turn each robot towards its target: on the spot beyond ``SPIN_ABOVE``,
    else at full speed with (1 - GAIN e, 1 + GAIN e) clipped to [-1, 1]."""
    d = target - pos
    error = np.remainder(np.arctan2(d[:, 1], d[:, 0]) - angle + math.pi, 2 * math.pi) - math.pi
    turn = np.sign(error)
    wheels = np.stack((np.clip(1 - GAIN * error, -1, 1), np.clip(1 + GAIN * error, -1, 1)), axis=1)
    spin = np.abs(error) > SPIN_ABOVE
    wheels[spin] = np.stack((-turn[spin], turn[spin]), axis=1)
    return wheels


def oracle_policy() -> Policy:
    """The privileged team (``OracleTeam``); its robots carry Khepera III sensors, unread."""
    team = OracleTeam()
    return Policy("oracle", Morphology.khepera_iii(), team.act, team.reset, bind=team.bind)


__all__ = ["OracleTeam", "oracle_policy", "steer", "REASSIGN", "SPIN_ABOVE", "GAIN"]
