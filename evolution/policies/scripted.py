"""Scripted team policies that need no training: baselines and benchmark workloads.

``WanderTeam`` is the explorer of the speed benchmark matched with the original Java
simulator, and the scripted baseline of every learning comparison: every robot drives forward
at 0.8 of top speed with a turning drift, redrawn uniformly in [-0.3, 0.3] every 50 steps; a
robot whose front ultrasonic has read >= 0.999 (an obstacle within 5 % of its range) for 20
consecutive steps spins on the spot for 10 steps, in a direction drawn at random (left or right,
each 1/2) when the spin starts; the blocked counter is frozen (not counted) while it spins. It
works on any number of robots at once (a team, or W teams stacked), so it is also a cheap,
moving baseline for comparisons.
"""

from __future__ import annotations

import math

import numpy as np

from evolution.policies.base import Policy
from gathering_env.sensors import Morphology

FORWARD = 0.8
DRIFT = 0.3
DRIFT_PERIOD = 50
BLOCKED_READING = 0.999
BLOCKED_STEPS = 20
SPIN_STEPS = 10


def front_ultrasonic(morphology: Morphology) -> int | None:
    """Column of the ultrasonic sensor looking most nearly straight ahead, or None."""
    best, best_angle = None, math.inf
    for column, sensor in enumerate(morphology):
        if sensor.type == "ultrasonic":
            angle = abs(math.remainder(sensor.bearing + sensor.orientation, 2 * math.pi))
            if angle < best_angle:
                best, best_angle = column, angle
    return best


class WanderTeam:
    """Forward with drift, spin when blocked (see the module docstring).

    Args:
        morphology: the robots' sensor suite (its front ultrasonic triggers the spin;
            without an ultrasonic sensor the robots never spin).
        seed: seeds the drifts.

    ``act(obs (M, S)) -> wheels (M, 2)``; ``reset(seed)`` restarts the pattern.
    """

    def __init__(self, morphology: Morphology | None = None, seed: int | None = 0) -> None:
        self.morphology = Morphology.khepera_iii() if morphology is None else morphology
        self.front = front_ultrasonic(self.morphology)
        self.reset(seed)

    def reset(self, seed: int | None = None) -> None:
        self.rng = np.random.default_rng(seed)
        self.t = 0
        self.drift = self.blocked = self.spin = self.spin_sign = None

    def act(self, obs: np.ndarray) -> np.ndarray:
        m = obs.shape[0]
        if self.drift is None or self.drift.shape[0] != m:
            self.drift = np.zeros(m)
            self.blocked = np.zeros(m, dtype=np.int64)
            self.spin = np.zeros(m, dtype=np.int64)
            self.spin_sign = np.ones(m)
            self.t = 0
        if self.t % DRIFT_PERIOD == 0:
            self.drift = self.rng.uniform(-DRIFT, DRIFT, m)
        self.t += 1
        wheels = np.empty((m, 2))
        wheels[:, 0] = FORWARD - self.drift
        wheels[:, 1] = FORWARD + self.drift
        spinning = self.spin > 0
        if self.front is not None:
            close = obs[:, self.front] >= BLOCKED_READING
            # frozen while spinning: a spinning robot neither counts nor resets its counter
            self.blocked = np.where(spinning, self.blocked, np.where(close, self.blocked + 1, 0))
            start = self.blocked >= BLOCKED_STEPS
            if start.any():
                self.spin[start] = SPIN_STEPS
                self.spin_sign[start] = np.where(self.rng.random(int(start.sum())) < 0.5, 1.0, -1.0)
                self.blocked[start] = 0
            spinning = self.spin > 0
        wheels[spinning, 0] = self.spin_sign[spinning]
        wheels[spinning, 1] = -self.spin_sign[spinning]
        self.spin[spinning] -= 1
        return wheels


def random_policy() -> Policy:
    state = {"rng": np.random.default_rng(0)}

    def act(obs):
        return state["rng"].uniform(-1.0, 1.0, (obs.shape[0], 2))

    def reset(seed):
        state["rng"] = np.random.default_rng(seed)

    return Policy("random", Morphology.khepera_iii(), act, reset)


def heuristic_policy() -> Policy:
    """Search pattern on Khepera III readings (bottom, IR +40, IR -40, US 0, US +90, US -90)."""

    def act(obs):
        wheels = np.tile([1.0, 0.85], (obs.shape[0], 1))
        blocked = (obs[:, 3] > 0.75) | (obs[:, 1] > 0.0) | (obs[:, 2] > 0.0)
        wheels[blocked] = [1.0, -1.0]
        return wheels

    return Policy("heuristic", Morphology.khepera_iii(), act)


def wander_policy() -> Policy:
    """The benchmark's explorer (``evolution.policies.scripted.WanderTeam``) on Khepera III."""
    team = WanderTeam(Morphology.khepera_iii())
    return Policy("wander", team.morphology, team.act, team.reset)


__all__ = ["WanderTeam", "front_ultrasonic", "random_policy", "heuristic_policy", "wander_policy"]
