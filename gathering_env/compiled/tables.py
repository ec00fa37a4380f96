"""Layouts shared by the compiled kernels: the sensor table, the world's parameter and flag
vectors, and the event codes ``settle`` reports (``gathering_env.compiled.kernels``)."""

from __future__ import annotations

import math

import numpy as np

from ..drive import robot_moment, spin_limit, substep_keep
from ..sensors import TYPE_CODES

IR, US, COLOUR, CAMERA, BOTTOM = (TYPE_CODES[t] for t in ("infrared", "ultrasonic", "colour", "camera", "bottom"))

# Columns of the sensor table (one row per sensor, see ``sensor_table``).
T_TYPE, T_BEARING, T_OFFSET, T_RANGE, T_COS_HALF, T_SIN_HALF, T_INV_RANGE = range(7)
# Entries of the float parameter vector (see ``world_params``).
(P_RADIUS, P_ARENA_W, P_ARENA_H, P_ZX0, P_ZY0, P_ZX1, P_ZY1, P_FALLOFF, P_IR_GAMMA, P_DT,
 P_MAX_SPEED, P_ZONE_CX, P_ZONE_CY, P_AVOID_DIST, P_BOX_W, P_BOX_D, P_REACH, P_TOTAL_VALUE,
 P_MAX_CYCLES, P_BOX_OFFSET, P_DEAD_BAND, P_MASS, P_MOMENT, P_SUBSTEPS, P_KEEP, P_SPIN_LIMIT) = range(26)
# Entries of the integer flag vector.
(F_IR_GAMMA, F_AVOIDANCE, F_PICKUP, F_FORCE_DRIVE, F_COLOUR_FARTHER, F_BLOCK_RAYS, F_IR_KHEPERA,
 F_BOTTOM_KHEPERA, F_WALL_ORIGINAL, F_STEER_ORIGINAL) = range(10)
# Event kinds reported by ``settle`` (rows of the int event table: kind, world, robot, block, slot).
EV_ATTACH, EV_RELEASE = 1, 2


def sensor_table(morphology) -> np.ndarray:
    """(S, 7) float64 table of a morphology for ``sense``: type code, bearing, axis offset
    (bearing + orientation), range, cos and sin of half the FOV, 1 / range (0 if no range)."""
    table = np.zeros((len(morphology), 7))
    for row, s in enumerate(morphology):
        half = 0.5 * s.fov
        table[row] = (TYPE_CODES[s.type], s.bearing, s.bearing + s.orientation, s.range,
                      math.cos(half), math.sin(half), 1.0 / s.range if s.range > 0 else 0.0)
    return table


def world_params(config) -> tuple[np.ndarray, np.ndarray]:
    """(float parameters, integer flags) of a ``WorldConfig`` for the kernels."""
    x0, y0, x1, y1 = config.zone_rect
    cx, cy = config.zone_centre
    params = np.array([
        config.robot_radius, config.arena_width, config.arena_height, x0, y0, x1, y1,
        config.bottom_falloff, config.ir_gamma, config.dt, config.robot_max_speed, cx, cy,
        config.collision_avoidance_distance, config.pickup_box_width, config.pickup_box_depth,
        config.pickup_reach, config.total_value, config.max_cycles, config.pickup_box_offset,
        config.drive_dead_band, config.robot_mass, robot_moment(config), config.physics_substeps, substep_keep(config),
        spin_limit(config),
    ], dtype=np.float64)
    flags = np.array([config.ir_response == "gamma", config.collision_avoidance, config.pickup_heuristic,
                      config.drive_model == "force", config.colour_response == "farther",
                      config.block_sighting == "rays", config.ir_response == "khepera",
                      config.bottom_response == "khepera", config.wall_distance == "original",
                      config.attached_steering == "original"], dtype=np.int64)
    return params, flags
