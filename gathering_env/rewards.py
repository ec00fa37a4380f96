"""Rewards for learners: the task reward, potential-based shaping, team or local credit.

One place for the reward options of ``WorldConfig`` (``reward``, ``attach_reward``,
``reward_scope``); both kernels (``NumpySimulation.step`` and ``CompiledWorlds.step``) call
``RewardShaper.before`` and ``RewardShaper.after`` around a step, over arrays with a leading
world axis (W = 1 for a single episode). The task performance ``ft`` (paper eq. 1) never
depends on these options.

* ``reward="task"``: the team reward ``100 * (change in gathered value) / total value``.
* ``reward="shaped"``: the task reward plus ``F = Phi(s') - Phi(s)`` with the potential

      Phi(s) = -100 * sum_b value_b * d_b(s) / (total value * arena diagonal)
               + attach_reward * (number of robots attached to a block)

  where ``d_b`` is the distance from block b's centre to the part of the zone its centre
  must reach for the (unrotated) block to lie wholly inside (0 for a gathered block), so the
  distance part lies in [-100, 0]. A robot thus earns ``attach_reward`` when it attaches and
  gives it back when it is released (its block gathered): the bonus cannot be farmed by
  gathering, pushing out and re-attaching. With discount 1 the shaped return of an episode
  is the task return plus ``Phi(end) - Phi(start)``, so the shaping leaves the optimal
  policies unchanged (Ng, Harada & Russell 1999).
* ``reward_scope="team"``: every robot receives the team reward. ``"local"``: the distance
  term of a block goes to the robots attached to it at the start of the step (split
  equally; to everyone equally if none), a robot's attachment term to that robot, and the
  task reward equally to all N robots, so the robots' rewards sum to the team reward.
"""

from __future__ import annotations

import math

import numpy as np

from .config import WorldConfig


def potential_scale(config: WorldConfig) -> float:
    """Normaliser of Phi: ``total value * arena diagonal / 100`` (Phi in [-100, 0])."""
    return config.total_value * math.hypot(config.arena_width, config.arena_height) / 100.0


def block_potentials(config: WorldConfig, block_pos: np.ndarray, block_half: np.ndarray,
                     block_value: np.ndarray) -> np.ndarray:
    """Each block's term of Phi, ``-value * distance to the zone / potential_scale``.

    Args:
        block_pos: (..., B, 2) centres. block_half: (B,) half sides. block_value: (B,).
    Returns:
        (..., B) float64, <= 0; 0 when the block's centre is at least its half side inside
        every edge of the zone.
    """
    x0, y0, x1, y1 = config.zone_rect
    x, y = block_pos[..., 0], block_pos[..., 1]
    dx = np.maximum(np.maximum(x0 + block_half - x, x - (x1 - block_half)), 0.0)
    dy = np.maximum(np.maximum(y0 + block_half - y, y - (y1 - block_half)), 0.0)
    return -block_value * np.hypot(dx, dy) / potential_scale(config)


def potential(config: WorldConfig, block_pos: np.ndarray, block_half: np.ndarray,
              block_value: np.ndarray, robot_attached: np.ndarray) -> np.ndarray:
    """Phi of each world: (..., B, 2) block centres and (..., N) attachments -> (...)."""
    return (block_potentials(config, block_pos, block_half, block_value).sum(axis=-1)
            + config.attach_reward * (np.asarray(robot_attached) >= 0).sum(axis=-1))


class RewardShaper:
    """Per-robot and team rewards of a step from the state before and after it.

    ``active`` is False for the default (``reward="task"``, ``reward_scope="team"``): the
    kernels then skip the shaper and the team reward is the task reward as before.
    """

    def __init__(self, config: WorldConfig, block_half: np.ndarray, block_value: np.ndarray) -> None:
        self.config = config
        self.shaped = config.reward == "shaped"
        self.local = config.reward_scope == "local"
        self.active = self.shaped or self.local
        self.block_half = np.asarray(block_half, dtype=np.float64)
        self.block_value = np.asarray(block_value, dtype=np.float64)

    def before(self, block_pos: np.ndarray, robot_attached: np.ndarray) -> None:
        """Remember Phi's terms (W, B) and the attachments (W, N) before the step."""
        if self.shaped:
            self._phi = block_potentials(self.config, block_pos, self.block_half, self.block_value)
        self._attached = robot_attached.copy()

    def after(self, task_reward: np.ndarray, block_pos: np.ndarray,
              robot_attached: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(team reward (W,), robot rewards (W, N)) of the step just taken.

        Args:
            task_reward: (W,) the task reward of the step (0 for worlds not stepped).
            block_pos: (W, B, 2) and robot_attached: (W, N) after the step.
        """
        before = self._attached
        worlds, n = before.shape
        team = np.asarray(task_reward, dtype=np.float64).copy()
        robot = np.repeat(team[:, None] / n, n, axis=1) if self.local else None
        if self.shaped:
            change = block_potentials(self.config, block_pos, self.block_half, self.block_value) - self._phi
            holds = (np.asarray(robot_attached) >= 0).astype(np.float64) - (before >= 0)
            team += change.sum(axis=1) + self.config.attach_reward * holds.sum(axis=1)
            if self.local:
                blocks = change.shape[1]
                holding = before >= 0
                flat = (np.arange(worlds)[:, None] * blocks + np.where(holding, before, 0))
                counts = np.bincount(flat[holding], minlength=worlds * blocks).reshape(worlds, blocks)
                share = np.where(counts > 0, change / np.maximum(counts, 1), 0.0)
                robot += np.where(holding, np.take_along_axis(share, np.where(holding, before, 0), axis=1), 0.0)
                robot += (change * (counts == 0)).sum(axis=1)[:, None] / n
                robot += self.config.attach_reward * holds
        if robot is None:
            robot = np.repeat(team[:, None], n, axis=1)
        return team, robot


__all__ = ["RewardShaper", "block_potentials", "potential", "potential_scale"]
