"""The pymunk world: arena walls, robots, blocks and ground friction (attachments: ``gathering_env.attachments``).

Top-down 2D without gravity. Ground friction, which pymunk lacks top-down, is modelled
the usual pymunk way: each block is tied to the static body by a ``PivotJoint`` and a
``GearJoint`` with ``max_bias = 0`` whose ``max_force``/``max_torque`` equal the friction
force/torque (``WorldConfig.block_ground_friction``). By default (``ground_friction =
"threshold"``) a block needing k robots gets the friction ``(k - margin) * F_drive``, so
k - 1 robots pushing at full drive cannot move it and k robots can; ``"mass"`` gives the
original code's kinetic friction 0.1 * m * g instead. Contact restitution is mixed as Box2D
mixes it (``gathering_env.contacts``).

Each robot is driven through a kinematic *control body* (pymunk's tank example): a pivot
and a gear joint with ``max_bias = 0`` pull the robot's velocity towards the control
body's velocity. By default (``drive_model = "velocity"``) the control velocity is the
differential-drive velocity along the robot's heading and the joints exert at most
``robot_drive_force`` / ``robot_drive_torque``, so the robot has no side-slip, brakes when
its wheels stop, and can push with at most its drive force; ``"force"`` is the original
code's robot (wheel forces, a traction impulse and the robot's own ground friction).
Both are in ``gathering_env.drive``.

State is exchanged with pymunk in bulk through ``pymunk.batch`` (one call to read every
body's pose and velocity, one to set all velocities); the rest of the package works on the
numpy arrays ``robot_pos``, ``robot_angle``, ``block_pos`` and ``block_angle``. These arrays
are updated in place, so a batch of worlds (``gathering_env.compiled.engine``) can own them as views
of its own (W, ...) arrays (``adopt``).
"""

from __future__ import annotations

import math

import numpy as np
import pymunk
import pymunk.batch as pbatch

from .attachments import Attachments
from .config import WorldConfig
from .contacts import apply_restitution
from .drive import BlockDraws, control_limits, force_drive, shuffled_times, substep_keep, velocity_drive
from .placement import check_placement, lay_out

_VEL = pbatch.BodyFields.VELOCITY | pbatch.BodyFields.ANGULAR_VELOCITY
_VEL_FORCE = _VEL | pbatch.BodyFields.FORCE | pbatch.BodyFields.TORQUE
"""What ``set_drive`` writes: velocities, and under the force drive also forces and torques."""
_STATE = pbatch.BodyFields.POSITION | pbatch.BodyFields.ANGLE | _VEL
"""What ``fetch_raw`` reads: per body x, y, angle, vx, vy, angular velocity."""
STATE_ARRAYS = ("robot_pos", "robot_angle", "block_pos", "block_angle", "robot_attached",
                "block_sticky_side", "anchor_owner", "raw")
"""The per-world arrays a batch may own (see ``adopt``)."""
_WALL_RADIUS = 0.5


class GatheringWorld(Attachments):
    """The physical world of one episode. Call ``reset(rng)`` before use.

    Array state (valid after ``reset`` and after every ``step``):
        robot_pos (N, 2), robot_angle (N,), block_pos (B, 2), block_angle (B,) in units/rad;
        block_type (B,) 0/1/2, block_half (B,) half side, block_need (B,), block_value (B,);
        robot_attached (N,) index of the block a robot is welded to, or -1;
        block_sticky_side (B,) side (0..3) robots attach to, or -1;
        anchor_owner (B, 3) robot holding each anchor of the sticky side, or -1.
    """

    def __init__(self, config: WorldConfig) -> None:
        self.config = config
        self.space: pymunk.Space | None = None

    def __getstate__(self) -> dict:
        """Picklable (pymunk spaces pickle; the batch buffers are recreated)."""
        state = dict(self.__dict__)
        state.pop("_buf", None)
        state.pop("_set_buf", None)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        if self.space is not None:
            self._buf = pbatch.Buffer()
            self._set_buf = pbatch.Buffer()

    # ------------------------------------------------------------------ construction
    def reset(self, rng: np.random.Generator) -> None:
        """Build a fresh world with positions and headings drawn from ``rng`` (or, if the
        config sets ``layout_seed``, from that seed) and the shuffled schedule from ``rng``."""
        cfg = self.config
        space = pymunk.Space()
        space.gravity = (0.0, 0.0)
        # pymunk keeps damping ** h of every velocity a sub-step of h
        space.damping = substep_keep(cfg) ** (cfg.physics_substeps / cfg.dt)
        space.iterations = cfg.physics_iterations
        # pymunk's default allowed overlap (0.1) is two thirds of a robot radius at our scale.
        space.collision_slop = 0.005
        self.space = space
        walls = self._add_walls()

        types = np.repeat(np.arange(3), cfg.block_counts)
        self.block_type = types
        self.block_half = 0.5 * np.asarray(cfg.block_sizes, dtype=float)[types]
        self.block_need = np.asarray(cfg.robots_needed, dtype=np.int64)[types]
        self.block_value = np.asarray(cfg.block_values, dtype=float)[types]
        layout_rng = rng if cfg.layout_seed is None else np.random.default_rng(cfg.layout_seed)
        block_xy, robot_xy = lay_out(cfg, self.block_half, layout_rng)
        block_angles = layout_rng.uniform(-math.pi, math.pi, size=len(types))
        robot_angles = layout_rng.uniform(-math.pi, math.pi, size=cfg.num_robots)

        self.robot_bodies: list[pymunk.Body] = []
        robot_shapes: list[pymunk.Shape] = []
        block_shapes: list[pymunk.Shape] = []
        moment = pymunk.moment_for_circle(cfg.robot_mass, 0.0, cfg.robot_radius)
        for (x, y), a in zip(robot_xy, robot_angles):
            body = pymunk.Body(cfg.robot_mass, moment)
            body.position = (float(x), float(y))
            body.angle = float(a)
            shape = pymunk.Circle(body, cfg.robot_radius)
            shape.friction = cfg.robot_friction
            space.add(body, shape)
            self.robot_bodies.append(body)
            robot_shapes.append(shape)

        self.block_bodies: list[pymunk.Body] = []
        for t, (x, y), a in zip(types, block_xy, block_angles):
            size = cfg.block_sizes[t]
            mass = cfg.block_masses[t]
            body = pymunk.Body(mass, pymunk.moment_for_box(mass, (size, size)))
            body.position = (float(x), float(y))
            body.angle = float(a)
            shape = pymunk.Poly.create_box(body, (size, size))
            shape.friction = cfg.block_friction
            space.add(body, shape)
            block_shapes.append(shape)
            self._add_ground_friction(body, *cfg.block_ground_friction(int(t)))
            self.block_bodies.append(body)

        apply_restitution(space, {"robot": robot_shapes, "block": block_shapes, "wall": walls}, cfg)

        self.control_bodies: list[pymunk.Body] = []
        self.control_gears: list[pymunk.GearJoint] = []  # under the force drive: the robot's friction torque
        max_force, max_torque = control_limits(cfg)
        for body in self.robot_bodies:
            control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            control.position = body.position
            pivot = pymunk.PivotJoint(control, body, (0, 0), (0, 0))
            pivot.max_bias = 0.0
            pivot.max_force = max_force
            gear = pymunk.GearJoint(control, body, 0.0, 1.0)
            gear.max_bias = 0.0
            gear.max_force = max_torque
            space.add(control, pivot, gear)
            self.control_bodies.append(control)
            self.control_gears.append(gear)

        self._index_bodies()
        n, b = cfg.num_robots, len(types)
        self.robot_pos = np.zeros((n, 2))
        self.robot_angle = np.zeros(n)
        self.block_pos = np.zeros((b, 2))
        self.block_angle = np.zeros(b)
        self.raw = np.zeros((self._num_rows, 6))
        self.robot_attached = np.full(n, -1, dtype=np.int64)
        self.block_sticky_side = np.full(b, -1, dtype=np.int64)
        self.anchor_owner = np.full((b, self.anchor_slots), -1, dtype=np.int64)
        self._welds: dict[int, tuple[pymunk.Constraint, pymunk.Constraint]] = {}
        # The shuffled schedule's own generator: a child of rng's seed, so it does not depend on
        # the layout's draws (the same with and without layout_seed) and leaves them alone.
        self._schedule_rng = BlockDraws(rng.spawn(1)[0], n + 1) if cfg.schedule == "shuffled" else None
        self._acted_after = np.zeros(n, dtype=bool)
        self.read_state()

    @property
    def anchor_slots(self) -> int:
        """Columns of ``anchor_owner``: the most robots any block needs."""
        return int(np.max(self.config.robots_needed))

    def adopt(self, arrays: dict[str, np.ndarray]) -> None:
        """Keep the state in the given arrays (same shapes and dtypes as ``STATE_ARRAYS``),
        copying the current values into them; from now on they are updated in place."""
        for name in STATE_ARRAYS:
            target = arrays[name]
            target[...] = getattr(self, name)
            setattr(self, name, target)

    def _add_walls(self) -> list[pymunk.Shape]:
        cfg, r = self.config, _WALL_RADIUS
        w, h = cfg.arena_width, cfg.arena_height
        corners = [(-r, -r), (w + r, -r), (w + r, h + r), (-r, h + r)]
        walls = []
        for a, b in zip(corners, corners[1:] + corners[:1]):
            seg = pymunk.Segment(self.space.static_body, a, b, r)
            seg.friction = cfg.robot_friction
            self.space.add(seg)
            walls.append(seg)
        return walls

    def _add_ground_friction(self, body: pymunk.Body, force: float, torque: float) -> None:
        pivot = pymunk.PivotJoint(self.space.static_body, body, (0, 0), (0, 0))
        pivot.max_bias = 0.0
        pivot.max_force = force
        gear = pymunk.GearJoint(self.space.static_body, body, 0.0, 1.0)
        gear.max_bias = 0.0
        gear.max_force = torque
        self.space.add(pivot, gear)

    @classmethod
    def check_placement(cls, config: WorldConfig, seed: int = 0) -> None:
        """Raise ``ValueError`` unless the robots and blocks of ``config`` can be laid out once
        (``gathering_env.placement.check_placement``)."""
        check_placement(config, seed)

    def _index_bodies(self) -> None:
        """Row of every robot, block and control body in pymunk's batch arrays."""
        buf = pbatch.Buffer()
        pbatch.get_space_bodies(self.space, pbatch.BodyFields.BODY_ID, buf)
        ids = np.frombuffer(buf.int_buf(), dtype=np.uintp)
        row_of = {int(body_id): row for row, body_id in enumerate(ids)}
        self._robot_rows = np.array([row_of[b.id] for b in self.robot_bodies], dtype=np.intp)
        self._block_rows = np.array([row_of[b.id] for b in self.block_bodies], dtype=np.intp)
        self._control_rows = np.array([row_of[b.id] for b in self.control_bodies], dtype=np.intp)
        self._num_rows = len(ids)
        self._buf = pbatch.Buffer()
        self._set_buf = pbatch.Buffer()

    # ------------------------------------------------------------------ stepping
    def fetch_raw(self) -> None:
        """Copy every body's pose and velocity from pymunk into ``raw`` (one batch call)."""
        buf = self._buf
        buf.clear()
        pbatch.get_space_bodies(self.space, _STATE, buf)
        self.raw[...] = np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(self._num_rows, 6)

    def read_state(self) -> None:
        """Refresh ``raw``, ``robot_pos/angle`` and ``block_pos/angle`` from pymunk."""
        self.fetch_raw()
        robots = self.raw[self._robot_rows]
        blocks = self.raw[self._block_rows]
        self.robot_pos[...] = robots[:, :2]
        self.robot_angle[...] = robots[:, 2]
        self.block_pos[...] = blocks[:, :2]
        self.block_angle[...] = blocks[:, 2]

    @property
    def drive_columns(self) -> int:
        """Columns of the array ``set_drive`` takes: vx, vy, spin (3), then, under the force
        drive, force x, force y and torque (6)."""
        return 6 if self.config.drive_model == "force" else 3

    def set_drive(self, drive: np.ndarray) -> None:
        """Set every body's velocity (and, under the force drive, force and torque) from
        ``drive`` (rows, ``drive_columns``) in pymunk's body order. The array is read in place
        (no copy) and stays registered: later calls with the same array only repeat the pymunk
        call."""
        if self._set_buf._float_buf is not drive:
            self._set_buf.set_float_buf(drive)
        pbatch.set_space_bodies(self.space, _VEL_FORCE if drive.shape[1] == 6 else _VEL, self._set_buf)

    def schedule_times(self) -> np.ndarray | None:
        """How often each robot's drive reaches the next physics step under ``schedule =
        'shuffled'`` ((N,) in {0, 1, 2}; ``gathering_env.drive.shuffled_times``), advancing the
        schedule by one step; None under 'fixed' (once each)."""
        if self._schedule_rng is None:
            return None
        times, self._acted_after = shuffled_times(self._schedule_rng, self._acted_after)
        return times

    def apply_drive(self, wheels: np.ndarray) -> None:
        """Set each robot's wheel drive for the next physics step (``gathering_env.drive``).

        Args:
            wheels: (N, 2) left/right wheel commands in [-1, 1].
        """
        cfg = self.config
        drive = np.zeros((self._num_rows, self.drive_columns))
        drive[:, :3] = self.raw[:, 3:6]   # every body's velocity as last read
        if cfg.drive_model == "force":
            rows = self._robot_rows
            drive[rows, 3:] = force_drive(wheels, self.robot_angle, drive[rows, :3], cfg, self.schedule_times())
            drive[self._control_rows, :3] = 0.0   # at rest: their joints are the robots' ground friction
        else:
            drive[self._control_rows] = velocity_drive(wheels, self.robot_angle, cfg)
        self.set_drive(drive)

    def step_physics(self) -> None:
        """Advance pymunk by ``dt`` (in ``physics_substeps`` equal sub-steps) and refresh the arrays.

        Contacts are discrete: a robot hitting a wall at top speed can overlap it by up to one
        sub-step's travel (``robot_max_speed * dt / physics_substeps``, 0.05 units by default)
        for one step before the contact pushes it out.
        """
        substeps = self.config.physics_substeps
        h = self.config.dt / substeps
        for _ in range(substeps):
            self.space.step(h)
        self.read_state()

    def place_robot(self, robot: int, x: float, y: float, angle: float) -> None:
        """Move a robot to (x, y) with heading ``angle`` at rest (scripted scenes, tests)."""
        self._place_body(self.robot_bodies[robot], x, y, angle)
        self.control_bodies[robot].position = (float(x), float(y))

    def place_block(self, block: int, x: float, y: float, angle: float) -> None:
        """Move a block to (x, y) with rotation ``angle`` at rest (scripted scenes, tests)."""
        self._place_body(self.block_bodies[block], x, y, angle)

    def _place_body(self, body: pymunk.Body, x: float, y: float, angle: float) -> None:
        values = (float(x), float(y), float(angle))
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"pose {values} must be finite")
        body.position = values[:2]
        body.angle = values[2]
        body.velocity = (0.0, 0.0)
        body.angular_velocity = 0.0
        self.space.reindex_shapes_for_body(body)
        self.read_state()
