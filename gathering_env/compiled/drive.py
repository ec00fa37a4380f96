"""Compiled ``drive`` kernel: wheel commands -> control-body (or, in the 'force' drive, robot)
velocities, operation for operation as the numpy reference (``gathering_env.drive`` and
``GatheringWorld``); see ``gathering_env.compiled.kernels``."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..drive import (
    FADE_END,
    FADE_START,
    IMPULSE_CAP,
    SPIN_TRACTION,
    TRACTION,
    WHEEL_FORCE,
    WHEEL_OFFSET,
)
from .tables import (
    F_AVOIDANCE,
    F_FORCE_DRIVE,
    F_STEER_ORIGINAL,
    P_ARENA_H,
    P_ARENA_W,
    P_AVOID_DIST,
    P_DEAD_BAND,
    P_DT,
    P_KEEP,
    P_MASS,
    P_MAX_SPEED,
    P_MOMENT,
    P_RADIUS,
    P_SPIN_LIMIT,
    P_SUBSTEPS,
    P_ZONE_CX,
    P_ZONE_CY,
)


@njit(cache=True)
def _dead_band(command, band):
    """A wheel command after the dead band (``WorldConfig.drive_dead_band``)."""
    if band == 0.0:
        return command
    magnitude = max(abs(command) - band, 0.0) / (1.0 - band)
    return magnitude if command >= 0.0 else -magnitude


@njit(cache=True)
def _wheel_force(command, vx):
    """'force' drive: the push of a wheel at ``command`` (``gathering_env.drive.wheel_force``)."""
    along = abs(vx) if np.sign(vx) == np.sign(command) else 0.0
    fade = min(max((FADE_END - along) / (FADE_END - FADE_START), 0.0), 1.0)
    return command * WHEEL_FORCE * fade


@njit(cache=True)
def _wrap(angle):
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True)
def drive(wheels, robot_pos, robot_angle, robot_attached, robot_rows, control_rows, raw, params, flags,
          active, times, vel):
    """Wheel commands -> control-body (and, in the 'force' drive, robot) velocities for the next
    physics step (``gathering_env.drive``).

    Args:
        wheels: (W, N, 2) finite controller commands (clipped here to [-1, 1]).
        robot_pos (W, N, 2), robot_angle (W, N), robot_attached (W, N): current state.
        robot_rows, control_rows: (W, N) row of each robot and of its control body in pymunk's
            body order.
        raw: (W, rows, 6) bodies as last read (x, y, angle, vx, vy, angular velocity).
        active: (W,) bool. times: (W, N) int, how often each robot's force drive acts before
            this step (1 under the fixed schedule; ``gathering_env.drive.shuffled_times``). vel: (W, rows, 3 or 6) written in place: every body's velocity,
            the control bodies' replaced by the drive, and under the force drive the robots'
            forces and torques (what ``GatheringWorld.set_drive`` reads).
    """
    n_worlds, n = robot_angle.shape
    n_rows = raw.shape[1]
    r = params[P_RADIUS]
    max_speed = params[P_MAX_SPEED]
    band = params[P_DEAD_BAND]
    half_dt = 0.5 * params[P_DT]
    dt = params[P_DT]
    force_drive = flags[F_FORCE_DRIVE] != 0
    mass, moment = params[P_MASS], params[P_MOMENT]
    arm = WHEEL_OFFSET * r
    spin_cap = params[P_SPIN_LIMIT]
    h = dt / params[P_SUBSTEPS]
    keep = params[P_KEEP]
    avoidance = flags[F_AVOIDANCE] != 0
    steer_original = flags[F_STEER_ORIGINAL] != 0
    reach = r + params[P_AVOID_DIST]
    cx, cy = params[P_ZONE_CX], params[P_ZONE_CY]
    left = np.empty(n)
    right = np.empty(n)
    for w in range(n_worlds):
        if not active[w]:
            continue
        for i in range(n):
            left[i] = min(max(wheels[w, i, 0], -1.0), 1.0)
            right[i] = min(max(wheels[w, i, 1], -1.0), 1.0)
        if avoidance:
            for i in range(n):
                if robot_attached[w, i] >= 0:
                    continue
                hx = math.cos(robot_angle[w, i])
                hy = math.sin(robot_angle[w, i])
                side = 0.0
                ahead_any = False
                for j in range(n):
                    if j == i:
                        continue
                    dx = robot_pos[w, j, 0] - robot_pos[w, i, 0]
                    dy = robot_pos[w, j, 1] - robot_pos[w, i, 1]
                    along = dx * hx + dy * hy
                    across = -dx * hy + dy * hx
                    if along > 0 and along < reach + r and abs(across) < 2 * r:
                        ahead_any = True
                        side += across
                fx = robot_pos[w, i, 0] + reach * hx
                fy = robot_pos[w, i, 1] + reach * hy
                wall = fx < 0 or fx > params[P_ARENA_W] or fy < 0 or fy > params[P_ARENA_H]
                if ahead_any or wall:
                    turn = -1.0 if side < 0 else 1.0
                    left[i] = turn
                    right[i] = -turn
        for i in range(n):
            if robot_attached[w, i] < 0:
                continue
            bearing = math.atan2(cy - robot_pos[w, i, 1], cx - robot_pos[w, i, 0])
            error = _wrap(bearing - robot_angle[w, i])
            direction = 1.0
            if steer_original:
                if error >= 0.5 * math.pi or error < -0.5 * math.pi:
                    direction = -1.0
                    error = _wrap(error - math.pi)
                inner = direction * (1.0 - abs(error) / (0.5 * math.pi))
                if error * direction >= 0.0:
                    left[i] = inner
                    right[i] = direction
                else:
                    left[i] = direction
                    right[i] = inner
                continue
            if abs(error) > 0.5 * math.pi:
                direction = -1.0
                error = _wrap(error - math.pi)
            turn = min(max(2.0 * error / (0.5 * math.pi), -1.0), 1.0)
            lw = direction - turn
            rw = direction + turn
            scale = max(max(abs(lw), abs(rw)), 1.0)
            left[i] = lw / scale
            right[i] = rw / scale
        for row in range(n_rows):
            vel[w, row, 0] = raw[w, row, 3]
            vel[w, row, 1] = raw[w, row, 4]
            vel[w, row, 2] = raw[w, row, 5]
        if force_drive:
            for i in range(n):
                row = robot_rows[w, i]
                vx, vy, spin = raw[w, row, 3], raw[w, row, 4], raw[w, row, 5]
                hx, hy = math.cos(robot_angle[w, i]), math.sin(robot_angle[w, i])
                wheel_sum = 0.0
                wheel_diff = 0.0
                removed = 0.0
                for _ in range(times[w, i]):
                    f_left = _wheel_force(left[i], vx)
                    f_right = _wheel_force(right[i], vx)
                    taken = TRACTION * min(max(mass * (vx * hx + vy * hy), -IMPULSE_CAP), IMPULSE_CAP)
                    wheel_sum = wheel_sum + (f_left + f_right)
                    wheel_diff = wheel_diff + (f_right - f_left)
                    removed = removed + taken
                    vx = vx - taken / mass * hx
                    vy = vy - taken / mass * hy
                    spin = (1.0 - TRACTION * SPIN_TRACTION) * spin
                push = keep * (dt * wheel_sum - removed) / h
                new_spin = spin + dt * arm * wheel_diff / moment
                vel[w, row, 3] = push * hx
                vel[w, row, 4] = push * hy
                vel[w, row, 5] = keep * moment * (min(max(new_spin, -spin_cap), spin_cap) - raw[w, row, 5]) / h
                row = control_rows[w, i]
                vel[w, row, 0] = 0.0
                vel[w, row, 1] = 0.0
                vel[w, row, 2] = 0.0
            continue
        for i in range(n):
            v_left = _dead_band(left[i], band) * max_speed
            v_right = _dead_band(right[i], band) * max_speed
            forward = 0.5 * (v_left + v_right)
            spin = (v_right - v_left) / (2.0 * r)
            heading = robot_angle[w, i] + half_dt * spin
            row = control_rows[w, i]
            vel[w, row, 0] = forward * math.cos(heading)
            vel[w, row, 1] = forward * math.sin(heading)
            vel[w, row, 2] = spin
