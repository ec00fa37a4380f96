"""How wheel commands move a robot: the two drive models (``WorldConfig.drive_model``).

Both act through each robot's *control body*, a kinematic body tied to the robot by a pivot
and a gear joint with ``max_bias = 0`` (pymunk's tank example): the joints pull the robot's
velocity and spin towards the control body's with at most their ``max_force`` /
``max_torque``.

``'velocity'`` (the default, paper protocol)
    The control body moves at the differential-drive velocity along the robot's heading
    (wheel speeds ``command * robot_max_speed``, after ``drive_dead_band``) and the joints
    exert at most ``robot_drive_force`` / ``robot_drive_torque``. The robot has no side
    slip, brakes when its wheels stop, and pushes with at most its drive force.

``'force'`` (the original code's robot, ``RobotObject`` of 2018 on Box2D)
    The wheels push and the floor holds, each step:

    * each wheel, ``WHEEL_OFFSET`` radii to either side of the centre, pushes along the
      heading with ``WHEEL_FORCE * command``: full while the robot's velocity *along world
      x* (sic: the original reads ``velocity.x``, not the velocity along the heading) is
      below ``FADE_START`` or opposes the command, fading linearly to nothing at
      ``FADE_END``;
    * an impulse removes ``TRACTION`` (80 %) of the robot's *forward* momentum, at most
      ``TRACTION * IMPULSE_CAP`` (the original meant the sideways one: its bug, kept), and
      ``TRACTION * SPIN_TRACTION`` of its spin;
    * the control body stays at rest, so its joints are the robot's ground friction:
      ``ROBOT_FRICTION * m * g`` and ``ROBOT_TORQUE_FRICTION * m * g`` (the original's kinetic
      coefficients of its friction joint); sideways this is the robot's only grip;
    * spin is capped at ``MAX_ROTATION`` per step (Box2D's ``b2_maxRotation``), after the
      friction (``spin_limit``).

    ``robot_max_speed``, ``robot_drive_force``, ``robot_drive_torque`` and
    ``drive_dead_band`` do not apply: the top speed (0.64 units/s heading north or south,
    slower heading east or west), the push at a standstill (5 less the friction 1.37) and the
    dead band follow from the forces. Wheel forces and impulses enter as pymunk body forces,
    which it integrates into the velocities before it solves contacts and joints, as Box2D
    does; so positions move with the solved velocities (setting the velocities instead would
    move each robot a step with its unsolved velocity, ignoring its friction).

``schedule = 'shuffled'`` (the original's MASON schedule, force drive only)
    MASON steps the robots and the physics world as agents of one ordering and shuffles
    them every step. A robot that acts before the physics step drives it; one that acts
    after drives the next one. So each physics step receives a robot's drive ``times`` =
    0, 1 or 2 times (``shuffled_times``): once for acting before it in this step, once for
    having acted after the previous one. Both actions sense the same positions (nothing
    moves between them), so the same command is applied twice in a row, the second time on
    the velocity the first impulse left (``force_drive``'s ``times``). Measured on the
    original's own classes, this makes a free robot faster (0.84 against 0.64 units/s) and
    a lone pusher push further; ``examples/physics_scenes.py`` has the figures. Under
    'fixed' every robot acts once, before the physics step.

The numpy functions here are the reference; ``gathering_env.compiled.kernels.drive`` does
the same for a batch of worlds.
"""

from __future__ import annotations

import math

import numpy as np

from .config import GRAVITY, WorldConfig

WHEEL_FORCE = 2.5
"""'force': push of one wheel at command 1 and full torque (the original's engine torque
2.5 * 0.03 over its wheel radius 0.03)."""
WHEEL_OFFSET = 0.75
"""'force': wheels sit this fraction of the robot's radius to either side of its centre."""
FADE_START, FADE_END = 0.2, 0.5
"""'force': the wheel torque is full below FADE_START units/s and nothing above FADE_END."""
TRACTION = 0.8
"""'force': fraction of the forward momentum (at most ``IMPULSE_CAP``) removed every step."""
IMPULSE_CAP = 1.0
"""'force': the largest momentum the traction impulse removes, before ``TRACTION``."""
SPIN_TRACTION = 0.1
"""'force': the spin impulse is ``TRACTION * SPIN_TRACTION * I * spin``."""
ROBOT_FRICTION = 0.2
"""'force': the robot's kinetic ground friction coefficient (force = 0.2 * m * g)."""
ROBOT_TORQUE_FRICTION = 0.06
"""'force': the robot's kinetic ground-friction torque coefficient (torque = 0.06 * m * g)."""
MAX_ROTATION = 0.5 * math.pi
"""'force': the most a robot turns in one step (radians; Box2D's b2_maxRotation)."""


def robot_moment(config: WorldConfig) -> float:
    """Moment of inertia of a robot (a solid disc, as pymunk's ``moment_for_circle``)."""
    return 0.5 * config.robot_mass * config.robot_radius ** 2


def substep_keep(config: WorldConfig) -> float:
    """Fraction of its velocity and spin a body keeps each physics sub-step under
    ``WorldConfig.damping`` (Box2D's 1 / (1 + damping * dt) over the whole step)."""
    return (1.0 + config.damping * config.dt) ** (-1.0 / config.physics_substeps)


def spin_limit(config: WorldConfig) -> float:
    """'force': the largest spin the drive aims a robot at before its ground friction acts.

    Box2D caps the turn a step (``MAX_ROTATION``) *after* the friction joint has slowed the
    spin, so the target is the cap plus the spin the friction removes in a step (the joint
    then runs at its ``max_torque``), undamped."""
    friction = ROBOT_TORQUE_FRICTION * config.robot_mass * GRAVITY * config.dt / robot_moment(config)
    return (MAX_ROTATION / config.dt + friction) * (1.0 + config.damping * config.dt)


def control_limits(config: WorldConfig) -> tuple[float, float]:
    """(max_force, max_torque) of the joints between a robot and its control body."""
    if config.drive_model == "force":
        weight = config.robot_mass * GRAVITY
        return ROBOT_FRICTION * weight, ROBOT_TORQUE_FRICTION * weight
    return config.robot_drive_force, config.robot_drive_torque


def dead_band(wheels: np.ndarray, band: float) -> np.ndarray:
    """Wheel commands after the drive's dead band: 0 up to ``band``, then rising linearly to
    full at 1 (``WorldConfig.drive_dead_band``)."""
    if band == 0.0:
        return wheels
    return np.sign(wheels) * np.maximum(np.abs(wheels) - band, 0.0) / (1.0 - band)


def velocity_drive(wheels: np.ndarray, angle: np.ndarray, config: WorldConfig) -> np.ndarray:
    """'velocity': (N, 3) control-body velocities (vx, vy, spin) for (N, 2) wheel commands."""
    wheels = dead_band(wheels, config.drive_dead_band)
    v_left = wheels[:, 0] * config.robot_max_speed
    v_right = wheels[:, 1] * config.robot_max_speed
    forward = 0.5 * (v_left + v_right)
    spin = (v_right - v_left) / (2.0 * config.robot_radius)
    heading = angle + 0.5 * config.dt * spin  # mid-step heading: arcs, not polygons
    return np.stack([forward * np.cos(heading), forward * np.sin(heading), spin], axis=1)


def wheel_force(command: np.ndarray, vx: np.ndarray) -> np.ndarray:
    """'force': the push of wheels at ``command`` on robots whose world-x velocity is ``vx``."""
    along = np.where(np.sign(vx) == np.sign(command), np.abs(vx), 0.0)
    fade = np.clip((FADE_END - along) / (FADE_END - FADE_START), 0.0, 1.0)
    return command * WHEEL_FORCE * fade


class BlockDraws:
    """``random(n)`` for a fixed ``n``, served from blocks of ``rows`` draws made at once.

    A numpy ``Generator`` fills an array draw by draw in C order, so row k of a block is exactly
    what the k-th call ``rng.random(n)`` would have returned: the same schedule, for one call to
    the generator every ``rows`` steps instead of every step."""

    def __init__(self, rng: np.random.Generator, n: int, rows: int = 1024) -> None:
        self.rng, self.n, self.rows = rng, int(n), int(rows)
        self.block = np.empty((0, self.n))
        self.row = 0

    def random(self, n: int) -> np.ndarray:
        if n != self.n:
            raise ValueError(f"n={n}; allowed: {self.n} (the width these draws were made for)")
        if self.row == self.block.shape[0]:
            self.block = self.rng.random((self.rows, self.n))
            self.row = 0
        self.row += 1
        return self.block[self.row - 1]


def shuffled_times(rng: np.random.Generator, acted_after: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """'shuffled' schedule: how often each robot's drive reaches this physics step.

    Args:
        rng: the episode's schedule generator, or its ``BlockDraws`` (one uniform draw per
            robot and one for the physics step, every step: their order in MASON's shuffle).
        acted_after: (N,) bool, the robots that acted after the previous physics step.

    Returns:
        ``(times, acted_after)``: (N,) int64 in {0, 1, 2}, and the robots that act after this
        physics step (they drive the next one)."""
    keys = rng.random(acted_after.shape[0] + 1)
    before = keys[:-1] < keys[-1]
    return before.astype(np.int64) + acted_after, ~before


def force_drive(wheels: np.ndarray, angle: np.ndarray, vel: np.ndarray,
                config: WorldConfig, times: np.ndarray | None = None) -> np.ndarray:
    """'force': (N, 3) force (x, y) and torque on each robot for the next physics step, from
    (N, 2) wheel commands and the velocities ``vel`` (N, 3: vx, vy, spin) the robots have now.

    ``times`` (N,) in {0, 1, 2} (default: 1 each): how often each robot's drive acts before
    the step (``shuffled_times``); a second action reads the velocity the first impulse left.

    Forces and impulses enter as the force that changes the velocity as much in one sub-step
    (pymunk clears forces after each), damped as Box2D damps them (``substep_keep``), so a
    robot's position moves with its solved velocity, as in Box2D."""
    m, moment = config.robot_mass, robot_moment(config)
    dt, h = config.dt, config.dt / config.physics_substeps
    vx, vy, spin = vel[:, 0], vel[:, 1], vel[:, 2]
    hx, hy = np.cos(angle), np.sin(angle)
    wheel_sum = np.zeros_like(vx)       # f_left + f_right over the actions
    wheel_diff = np.zeros_like(vx)      # f_right - f_left over the actions
    removed = np.zeros_like(vx)         # forward momentum the impulses removed
    for action in range(1 if times is None else int(times.max(initial=0))):
        acts = True if times is None else times > action
        f_left = wheel_force(wheels[:, 0], vx)
        f_right = wheel_force(wheels[:, 1], vx)
        taken = TRACTION * np.clip(m * (vx * hx + vy * hy), -IMPULSE_CAP, IMPULSE_CAP)
        wheel_sum = np.where(acts, wheel_sum + (f_left + f_right), wheel_sum)
        wheel_diff = np.where(acts, wheel_diff + (f_right - f_left), wheel_diff)
        removed = np.where(acts, removed + taken, removed)
        vx = np.where(acts, vx - taken / m * hx, vx)
        vy = np.where(acts, vy - taken / m * hy, vy)
        spin = np.where(acts, (1.0 - TRACTION * SPIN_TRACTION) * spin, spin)
    keep = substep_keep(config)
    push = keep * (dt * wheel_sum - removed) / h
    arm = WHEEL_OFFSET * config.robot_radius
    new_spin = spin + dt * arm * wheel_diff / moment
    cap = spin_limit(config)
    torque = keep * moment * (np.clip(new_spin, -cap, cap) - vel[:, 2]) / h
    return np.stack([push * hx, push * hy, torque], axis=1)
