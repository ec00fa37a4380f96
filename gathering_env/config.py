"""Every world parameter of the collective gathering task in one validated dataclass.

Units: lengths in world units (the arena is 40 x 40 by default, docs/model.md §1),
time in seconds, angles in radians, masses in mass units, forces in force units
(the pymunk solver's units; only their ratios matter).

``WorldConfig.from_kwargs(environment=2, num_robots=20, ...)`` builds a config from an
environment preset (paper Table 2) and keyword overrides of any field; every field is
range-checked and a bad value raises ``ValueError`` naming the field, the value and the
allowed range.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass, field, fields
from typing import Any

#: Paper Table 2: (small, medium, large) block counts per environment preset.
ENVIRONMENT_PRESETS: dict[int, tuple[int, int, int]] = {
    1: (10, 5, 0),  # low cooperation
    2: (5, 5, 5),
    3: (0, 5, 10),  # high cooperation
}

#: Implementations of the step (``WorldConfig.kernel``).
KERNELS: tuple[str, str] = ("compiled", "numpy")

#: Reward signals (``WorldConfig.reward``): the task's own, or the task's plus shaping.
REWARDS: tuple[str, str] = ("task", "shaped")

#: Who receives which reward (``WorldConfig.reward_scope``).
REWARD_SCOPES: tuple[str, str] = ("team", "local")

#: Where the pickup box sits (``WorldConfig.pickup_box``).
PICKUP_BOXES: tuple[str, str] = ("front", "centre")
GROUND_FRICTIONS: tuple[str, str] = ("threshold", "mass")
#: How wheel commands move a robot (``WorldConfig.drive_model``, ``gathering_env.drive``).
DRIVE_MODELS: tuple[str, str] = ("velocity", "force")
#: When robots act relative to the physics step (``WorldConfig.schedule``, ``gathering_env.drive``).
SCHEDULES: tuple[str, str] = ("fixed", "shuffled")
#: Every field that takes one of a few names -> the names it takes (its default is on the field).
CHOICES: dict[str, tuple[str, ...]] = {
    "kernel": KERNELS, "reward": REWARDS, "reward_scope": REWARD_SCOPES, "pickup_box": PICKUP_BOXES,
    "ground_friction": GROUND_FRICTIONS, "drive_model": DRIVE_MODELS, "schedule": SCHEDULES,
    "ir_response": ("linear", "gamma", "khepera"), "bottom_response": ("linear", "khepera"),
    "wall_distance": ("nearest", "original"), "block_sighting": ("cone", "rays"),
    "colour_response": ("nearer", "farther"), "attached_steering": ("sharp", "original"),
    "weld_spin": ("held", "free"),
}
INT_RANGES: dict[str, tuple[int, int]] = {
    "num_robots": (1, 1000), "max_cycles": (1, 10**9),
    "physics_iterations": (1, 1000), "physics_substeps": (1, 100),
}
"""Integer fields -> their allowed [low, high]; command-line flags that set them take the same range."""

GRAVITY = 9.81
"""Acceleration of gravity (units/s^2) that turns mass into ground friction ('mass')."""
MASS_FRICTION = 0.1
"""'mass' ground friction: the original code's kinetic coefficient (force = 0.1 * m * g)."""
MASS_TORQUE_FRICTION = 0.01
"""'mass' ground friction: the original's kinetic torque coefficient (torque = 0.01 * m * g,
the same for every shape, as the original's)."""
THRESHOLD_TORQUE_ARM = 0.38
"""'threshold' ground friction: torque = force * this * block side."""

#: Names of the three block types, index = type id.
BLOCK_TYPE_NAMES: tuple[str, str, str] = ("small", "medium", "large")


@dataclass(frozen=True)
class WorldConfig:
    """All parameters of the arena, robots, blocks, heuristics and scoring.

    Defaults follow docs/model.md §1-4 (the original implementation's numbers where the
    paper is silent). Every field can be overridden through ``parallel_env(**kwargs)``.
    """

    # --- arena and simulation -------------------------------------------------------
    arena_width: float = 40.0
    """Arena extent along x (units); walls enclose [0, arena_width] x [0, arena_height]."""
    arena_height: float = 40.0
    dt: float = 0.1
    """Physics time step per environment step (s)."""
    physics_iterations: int = 10
    """pymunk solver iterations per step."""
    physics_substeps: int = 1
    """pymunk steps per environment step (each of dt / substeps); more = smaller contact
    overlaps at a proportional cost."""
    max_cycles: int = 10_000
    """Steps per trial before truncation (docs/model.md §1: 10 000)."""

    # --- team ----------------------------------------------------------------------
    num_robots: int = 20
    robot_radius: float = 0.15
    robot_mass: float = 0.7
    robot_friction: float = 0.7
    """Contact (Coulomb) friction of robot shapes."""
    robot_max_speed: float = 0.5
    """Top wheel speed (units/s); the robot's top speed when both wheels drive at 1."""
    drive_dead_band: float = 0.0
    """Wheel commands of magnitude up to this do nothing; above it a wheel's speed rises linearly
    to top speed at 1 (the original robot: about 0.28, from its own ground friction). In [0, 1)."""
    robot_drive_force: float = 1.0
    """Maximum traction force a robot's wheels exert on the ground (force units)."""
    robot_drive_torque: float = 0.1
    """Maximum turning torque of a robot's wheels."""
    drive_model: str = "velocity"
    """How wheel commands move a robot (``gathering_env.drive``): 'velocity' (wheel speeds
    ``command * robot_max_speed``, reached with at most ``robot_drive_force``; no side slip)
    or 'force' (the original code's robot: wheel forces that fade with speed, an impulse that
    removes 80 % of the forward velocity each step, and its own ground friction as its only
    grip; the four fields above do not apply)."""
    damping: float = 0.0
    """Box2D-style damping of every robot and block: velocity and spin shrink by the factor
    1 / (1 + damping * dt) each step (the original code: 0.1)."""
    schedule: str = "fixed"
    """When each robot's drive acts, relative to the physics step: 'fixed' (every robot, then
    the physics step) or 'shuffled' (the original code's MASON schedule, which shuffles the
    robots and the physics step every step, so a robot's drive reaches a physics step 0, 1 or
    2 times; drawn from the reset seed, apart from the layout's draws; ``drive_model = 'force'`` only;
    ``gathering_env.drive.shuffled_times``)."""
    layout_seed: int | None = None
    """If set, every episode lays out its robots and blocks (positions and headings) from this
    seed, whatever the reset seed; the reset seed then drives only the rest (the shuffled
    schedule). One layout, several schedules: how the original's trials of one run differ
    (``layout = "per_run"`` with ``schedule = "shuffled"``). None (default): the reset seed
    draws the layout."""

    # --- blocks (index 0/1/2 = small/medium/large) ------------------------------------
    block_counts: tuple[int, int, int] = ENVIRONMENT_PRESETS[2]
    block_sizes: tuple[float, float, float] = (0.4, 0.6, 0.8)
    """Side length of the square blocks (units)."""
    block_masses: tuple[float, float, float] = (1.0, 3.0, 6.0)
    block_values: tuple[float, float, float] = (1.0, 2.0, 3.0)
    robots_needed: tuple[int, int, int] = (1, 2, 3)
    block_friction_margin: float = 0.5
    """A block needing k robots has ground friction (k - margin) * robot_drive_force,
    so k - 1 robots at full drive cannot move it and k robots can. In (0, 1)."""
    block_friction: float = 0.7
    """Contact (Coulomb) friction of block shapes."""
    ground_friction: str = "threshold"
    """Blocks' friction with the floor: 'threshold' (a block needing k robots resists with
    (k - block_friction_margin) * robot_drive_force, so k - 1 robots cannot move it and k can)
    or 'mass' (the original code: kinetic Coulomb friction 0.1 * m * g, torque 0.01 * m * g,
    whatever the robots needed; ``block_ground_friction``)."""
    robot_restitution: float = 0.0
    """Restitution (bounciness) of robots; a contact takes the larger of its two shapes' (as
    Box2D does). 0: contacts absorb the approach speed; the original code: 1 (fully elastic)."""
    block_restitution: float = 0.0
    """Restitution of blocks (the original code: 0.4)."""
    wall_restitution: float = 0.0
    """Restitution of the arena walls (the original code: 1)."""

    # --- gathering zone --------------------------------------------------------------
    zone_width: float = 20.0
    """Width of the gathering zone along the south wall (units), centred in x."""
    zone_depth: float = 8.0
    """Depth of the zone from the south wall (units); the paper's 0.5 x 0.2 arena."""

    # --- heuristics ------------------------------------------------------------------
    pickup_heuristic: bool = True
    pickup_box: str = "front"
    """Where the pickup box lies: 'front' (the paper: just ahead of the rim, its near edge on
    the rim) or 'centre' (the original code: centred on the robot's centre, so a block must
    touch the robot's body to be gripped)."""
    pickup_box_width: float = 0.1
    """Extent of the pickup box across the heading (units)."""
    pickup_box_depth: float = 0.2
    """Extent of the pickup box along the heading (units)."""
    pickup_reach: float = 2.5
    """A robot attaches only within this many robot radii of a free anchor point."""
    weld_seat: bool = True
    """The weld seats the robot (as every weld of the original does): an attaching robot is
    put with its front on the anchor point, facing the block square to the sticky side, and
    welded there; off, it is welded where it stands, at whatever angle (then the robots on one
    block push in different directions: a scripted team gathers 35-80 % less)."""
    attached_steering: str = "sharp"
    """How a robot welded to a block steers towards the zone centre (it ignores its controller
    while welded), from its heading error e, folded to [-pi/2, pi/2] by driving backwards (pulling
    the block) when the centre lies behind it. The outer wheel runs at full power. 'sharp': the
    inner one at (1 - t) / (1 + t) of it, t = min(4 |e| / pi, 1), so stopped from 45 degrees off;
    'original': the 2018 code's ``Heuristic``, the inner one at 1 - 2 |e| / pi, stopped only at
    90 degrees (``gathering_env.reference.heuristics.attached_wheels``)."""
    weld_spin: str = "held"
    """Under the force drive, whether a welded robot's ground friction holds its spin. 'held':
    as when it is free (the robot and its block turn only if the steering's torque beats both
    their friction torques, which it never does at one robot per block). 'free': the robot's
    friction torque is released while it is welded, so the pair turns against the block's
    friction torque, its sliding friction and the robot's traction impulse. Measured on the
    original's own classes, the pair arcs its block into the zone from up to ~66 degrees off,
    an artefact of Box2D's unconverged solver (its position pass turns the pair past the
    friction; with 20 velocity iterations or no position pass it holds, as 'held' does).
    'free' lets the pair turn somewhat more readily than the original's
    (docs/fidelity.md, "The welded robot")."""
    collision_avoidance: bool = False
    """Turn away from robots/walls just ahead, overriding the controller (original option, off)."""
    collision_avoidance_distance: float = 0.3
    """Clearance ahead (units) that triggers the collision-avoidance turn."""

    # --- sensing ---------------------------------------------------------------------
    ir_response: str = "linear"
    """'linear': 1 - d/range; 'gamma': (1 - d/range) ** ir_gamma (a steeper proximity curve);
    'khepera': the original's, a Gamma density over 200 d/range (``gathering_env.khepera``),
    0 at contact, 1 at 1.3-1.8 % of the range, below 0.01 beyond 8.8 %."""
    ir_gamma: float = 3.0
    colour_response: str = "nearer"
    """'nearer': a block reads 0.5 + 0.5 (1 - d/range), a wall 0.5 (1 - d/range) (nearer =
    higher); 'farther': the original's, 0.5 + 0.5 d/range and 0.5 d/range (rising with distance,
    so a wall at contact reads 0, as nothing does)."""
    block_sighting: str = "cone"
    """How a cone sensor sees a block. 'cone': where the block's nearest point to the mount lies
    inside the cone and within range, at that distance. 'rays': the original's three rays, the
    axis (length range) and the two cone edges (to x = range): the first of them that enters the
    block, in that order, gives the distance (its projection on the axis), else the block is
    unseen unless the mount lies inside it (distance 0); a block whose nearest point is out of
    range is unseen either way. Robots and walls are seen over the whole cone in both."""
    wall_distance: str = "nearest"
    """The distance at which a cone sensor reads a wall it sees (one whose nearest point in the
    cone lies within range). 'nearest': that nearest point's. 'original': the 2018 simulator's
    line formulas (``gathering_env.reference.sensing.original_wall_distance``), which mix the
    sensor's frame with the world's and so give another distance, often beyond the range."""
    bottom_falloff: float = 1.0
    """Distance outside the zone (units) over which the bottom sensor falls from 1 to 0."""
    bottom_response: str = "linear"
    """'linear': the bottom sensor reads under the robot's centre, 1 over the zone, falling to 0
    over ``bottom_falloff``; 'khepera': the original's, a disc 0.95 radii ahead of the centre
    read through the Khepera curve (``gathering_env.khepera``): on over the zone, off within
    about 0.01 of it."""

    # --- scoring ---------------------------------------------------------------------
    time_bonus: float = 20.0
    """Bonus for gathering every block, scaled by the unused fraction of steps (paper: 20,
    original code: 10)."""

    # --- reward (for learners; ft of eq. 1 does not depend on it) ---------------------
    reward: str = "task"
    """'task': 100 * (change in gathered value) / total value per step (sums to eq. 1's
    value part). 'shaped': the task reward plus potential-based shaping Phi(s') - Phi(s)
    (blocks' distance to the zone, ``attach_reward`` per attached robot); see
    ``gathering_env.rewards`` and docs/rl/."""
    attach_reward: float = 1.0
    """reward='shaped' only: each robot attached to a block adds this to the potential, so a
    robot earns it when it attaches and gives it back when released (its block gathered);
    in the units of the task reward (gathering everything is worth 100)."""
    reward_scope: str = "team"
    """'team': every robot receives the team reward. 'local': a block's distance term goes to
    the robots attached to it (split equally), a robot's attachment term to that robot, the
    rest equally to all robots, so the robots' rewards sum to the team reward."""

    # --- implementation ----------------------------------------------------------------
    kernel: str = "compiled"
    """Which implementation computes everything of a step but pymunk's physics: 'compiled'
    (numba kernels, ``gathering_env.compiled.kernels``) or 'numpy' (the vectorised reference).
    Both give the same episodes; see docs/performance.md."""

    environment: int | None = field(default=2, compare=False)
    """Preset the block counts came from (informational; None if counts were overridden)."""

    # ---------------------------------------------------------------------------------
    @classmethod
    def from_kwargs(cls, environment: int | None = 2, **overrides: Any) -> WorldConfig:
        """Build a config from an environment preset (1, 2 or 3) and field overrides."""
        if environment is not None:
            if isinstance(environment, bool) or environment not in ENVIRONMENT_PRESETS:
                raise ValueError(
                    f"environment={environment!r} is not a preset; allowed: "
                    f"{sorted(ENVIRONMENT_PRESETS)} (or None with block_counts=...)"
                )
        allowed = {f.name for f in fields(cls)} - {"environment"}
        unknown = sorted(set(overrides) - allowed)
        if unknown:
            raise ValueError(
                f"unknown world parameter(s) {unknown}; allowed: {sorted(allowed)}"
            )
        values = dict(overrides)
        if "block_counts" not in values:
            if environment is None:
                raise ValueError("environment=None needs block_counts=(small, medium, large)")
            values["block_counts"] = ENVIRONMENT_PRESETS[environment]
        for name in ("block_counts", "block_sizes", "block_masses", "block_values", "robots_needed"):
            if name in values:
                values[name] = _triple(name, values[name])
        return cls(environment=environment, **values)

    def __post_init__(self) -> None:
        _validate(self)

    # --- derived quantities -----------------------------------------------------------
    @property
    def zone_rect(self) -> tuple[float, float, float, float]:
        """Gathering zone as (x_min, y_min, x_max, y_max), along the south wall (y = 0)."""
        x0 = 0.5 * (self.arena_width - self.zone_width)
        return (x0, 0.0, x0 + self.zone_width, self.zone_depth)

    @property
    def zone_centre(self) -> tuple[float, float]:
        x0, y0, x1, y1 = self.zone_rect
        return (0.5 * (x0 + x1), 0.5 * (y0 + y1))

    @property
    def pickup_box_offset(self) -> float:
        """Distance from the robot's centre to the pickup box's centre, along the heading."""
        return self.robot_radius + 0.5 * self.pickup_box_depth if self.pickup_box == "front" else 0.0

    @property
    def num_blocks(self) -> int:
        return int(sum(self.block_counts))

    @property
    def total_value(self) -> float:
        """Sum of the values of all blocks in the world (v_t of eq. 1)."""
        return float(sum(c * v for c, v in zip(self.block_counts, self.block_values)))

    def block_ground_friction(self, block_type: int) -> tuple[float, float]:
        """Ground friction (force, torque) of a block of the given type (``ground_friction``)."""
        if self.ground_friction == "mass":
            weight = self.block_masses[block_type] * GRAVITY
            return MASS_FRICTION * weight, MASS_TORQUE_FRICTION * weight
        need = self.robots_needed[block_type]
        force = (need - self.block_friction_margin) * self.robot_drive_force
        return force, force * THRESHOLD_TORQUE_ARM * self.block_sizes[block_type]

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dict of every field (tuples become lists)."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}


def _validate(config: WorldConfig) -> None:
    """Raise ``ValueError`` naming the first field of ``config`` that is out of range."""
    for name, (low, high) in INT_RANGES.items():
        _check_int(name, getattr(config, name), low, high)
    for name in (
        "arena_width", "arena_height", "dt", "robot_radius", "robot_mass",
        "robot_max_speed", "robot_drive_force", "robot_drive_torque",
        "zone_width", "zone_depth", "pickup_box_width", "pickup_box_depth",
        "pickup_reach", "collision_avoidance_distance", "ir_gamma", "bottom_falloff",
    ):
        _check_float(name, getattr(config, name), 0.0, math.inf, low_open=True)
    for name in ("robot_friction", "block_friction", "time_bonus", "attach_reward"):
        _check_float(name, getattr(config, name), 0.0, math.inf)
    _check_float("drive_dead_band", config.drive_dead_band, 0.0, 1.0, high_open=True)
    for name in ("robot_restitution", "block_restitution", "wall_restitution"):
        _check_float(name, getattr(config, name), 0.0, 1.0)
    _check_float("damping", config.damping, 0.0, 100.0)
    _check_float("block_friction_margin", config.block_friction_margin, 0.0, 1.0,
                 low_open=True, high_open=True)
    for i, count in enumerate(config.block_counts):
        _check_int(f"block_counts[{i}] ({BLOCK_TYPE_NAMES[i]})", count, 0, 10_000)
    for i in range(3):
        label = BLOCK_TYPE_NAMES[i]
        _check_float(f"block_sizes[{i}] ({label})", config.block_sizes[i], 0.0, math.inf, low_open=True)
        _check_float(f"block_masses[{i}] ({label})", config.block_masses[i], 0.0, math.inf, low_open=True)
        _check_float(f"block_values[{i}] ({label})", config.block_values[i], 0.0, math.inf, low_open=True)
        _check_int(f"robots_needed[{i}] ({label})", config.robots_needed[i], 1, 100)
    if config.zone_width > config.arena_width:
        raise ValueError(
            f"zone_width={config.zone_width} must be <= arena_width={config.arena_width}"
        )
    if config.zone_depth >= config.arena_height:
        raise ValueError(
            f"zone_depth={config.zone_depth} must be < arena_height={config.arena_height}"
        )
    for name, value in (("pickup_heuristic", config.pickup_heuristic),
                        ("weld_seat", config.weld_seat),
                        ("collision_avoidance", config.collision_avoidance)):
        if not isinstance(value, bool):
            raise ValueError(f"{name}={value!r} must be a bool (True or False)")
    for name, allowed in CHOICES.items():
        if getattr(config, name) not in allowed:
            raise ValueError(f"{name}={getattr(config, name)!r}; allowed: {', '.join(map(repr, allowed))}")
    if config.drive_model == "force" and config.drive_dead_band != 0.0:
        raise ValueError(f"drive_dead_band={config.drive_dead_band!r} with drive_model='force': "
                         "the force drive has its own dead band; allowed: 0")
    if config.weld_spin == "free" and config.drive_model != "force":
        raise ValueError(f"weld_spin='free' with drive_model={config.drive_model!r}: it releases the force drive's "
                         "friction torque; allowed: drive_model='force', or weld_spin='held'")
    if config.layout_seed is not None:
        _check_int("layout_seed", config.layout_seed, 0, 2 ** 63 - 1)
    if config.schedule == "shuffled" and config.drive_model != "force":
        raise ValueError(f"schedule='shuffled' with drive_model={config.drive_model!r}: the shuffled "
                         "schedule acts on wheel forces; allowed: drive_model='force', or schedule='fixed'")
    if sum(config.block_counts) == 0:
        raise ValueError("block_counts=(0, 0, 0): the world needs at least one block")


def _triple(name: str, value: Any) -> tuple:
    try:
        items = tuple(value)
    except TypeError:
        raise ValueError(f"{name}={value!r} must be a sequence of 3 values (small, medium, large)") from None
    if len(items) != 3:
        raise ValueError(f"{name}={value!r} must have exactly 3 entries (small, medium, large)")
    return items


def _check_int(name: str, value: Any, low: int, high: int) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name}={value!r} must be an integer in [{low}, {high}]")
    if not low <= int(value) <= high:
        raise ValueError(f"{name}={value!r} out of range; allowed: [{low}, {high}]")


def _check_float(name: str, value: Any, low: float, high: float, *,
                 low_open: bool = False, high_open: bool = False) -> None:
    allowed = f"{'(' if low_open else '['}{low}, {high}{')' if high_open else ']'}"
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name}={value!r} must be a number in {allowed}")
    x = float(value)
    if not math.isfinite(x):
        raise ValueError(f"{name}={value!r} must be finite, in {allowed}")
    if x < low or x > high or (low_open and x == low) or (high_open and x == high):
        raise ValueError(f"{name}={value!r} out of range; allowed: {allowed}")
