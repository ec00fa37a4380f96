"""Attachments: a robot welded to an anchor of a block's sticky side (the pickup heuristic).

A block needing k robots has k anchor points spread evenly along each side. The first robot
to grip a block fixes its *sticky side*; later robots may only take that side's free anchors.
A grip is a pymunk ``PivotJoint`` and ``GearJoint`` between robot and block (the weld), made
where the robot stands or, with ``weld_seat`` (the default, as in the original), after seating
the robot's front on the anchor, square to the side. With ``weld_spin = "free"`` a welded robot's
ground-friction torque lets go until it is released. When to try a grip and when to let go
is the simulation's business (``gathering_env.simulation``); ``GatheringWorld`` keeps the
arrays (``robot_attached``, ``block_sticky_side``, ``anchor_owner``) and the bodies.
"""

from __future__ import annotations

import math

import numpy as np
import pymunk

from .drive import control_limits

# Block sides in the block frame: outward normal and tangent of side 0..3 (E, N, W, S).
_SIDE_NORMALS = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
_SIDE_TANGENTS = np.array([[0.0, 1.0], [-1.0, 0.0], [0.0, -1.0], [1.0, 0.0]])


class Attachments:
    """The attachment methods of ``gathering_env.world.GatheringWorld`` (a mixin: it reads the
    world's config, arrays, bodies and space)."""

    def anchor_points(self, block: int, side: int) -> np.ndarray:
        """(k, 2) world positions of the k anchor points on one side of a block."""
        k = int(self.block_need[block])
        half = self.block_half[block]
        offsets = ((np.arange(k) + 0.5) / k * 2.0 - 1.0) * half
        local = _SIDE_NORMALS[side] * half + offsets[:, None] * _SIDE_TANGENTS[side]
        c, s = math.cos(self.block_angle[block]), math.sin(self.block_angle[block])
        rot = np.array([[c, -s], [s, c]])
        return self.block_pos[block] + local @ rot.T

    def try_attach(self, robot: int, block: int) -> bool:
        """Weld ``robot`` to the nearest free anchor of ``block`` if one is within reach.

        The first robot fixes the block's sticky side; later ones may only use that side.
        Returns True if the robot was attached.
        """
        cfg = self.config
        heading = np.array([math.cos(self.robot_angle[robot]), math.sin(self.robot_angle[robot])])
        front = self.robot_pos[robot] + cfg.robot_radius * heading
        sticky = int(self.block_sticky_side[block])
        sides = range(4) if sticky < 0 else (sticky,)
        best = None
        for side in sides:
            points = self.anchor_points(block, side)
            for slot, point in enumerate(points):
                if sticky >= 0 and self.anchor_owner[block, slot] >= 0:
                    continue
                dist = float(np.hypot(*(point - front)))
                if best is None or dist < best[0]:
                    best = (dist, side, slot, point)
        if best is None or best[0] > cfg.pickup_reach * cfg.robot_radius:
            return False
        _, side, slot, _ = best
        self.block_sticky_side[block] = side
        self.anchor_owner[block, slot] = robot
        self.robot_attached[robot] = block
        self.weld(robot, block, slot, front)
        return True

    def weld(self, robot: int, block: int, slot: int, front: np.ndarray) -> None:
        """The pymunk side of an attachment already recorded in the arrays (``robot`` owns
        anchor ``slot`` of the block's sticky side): weld the robot to the block at its front
        point where it stands, or, with ``weld_seat`` (the default, as in the original), first seat
        it with its front on the anchor, facing the block square to the sticky side."""
        cfg = self.config
        robot_body = self.robot_bodies[robot]
        block_body = self.block_bodies[block]
        if cfg.weld_seat:
            side = int(self.block_sticky_side[block])
            point = self.anchor_points(block, side)[slot]
            normal_angle = self.block_angle[block] + math.atan2(*_SIDE_NORMALS[side][::-1])
            outward = np.array([math.cos(normal_angle), math.sin(normal_angle)])
            robot_body.position = tuple(point + outward * cfg.robot_radius)
            robot_body.angle = math.remainder(normal_angle + math.pi, 2 * math.pi)
            robot_body.velocity = (0.0, 0.0)
            robot_body.angular_velocity = 0.0
            self.space.reindex_shapes_for_body(robot_body)
            weld_point = tuple(point)
        else:
            weld_point = (float(front[0]), float(front[1]))
        pivot = pymunk.PivotJoint(robot_body, block_body, weld_point)
        pivot.collide_bodies = False
        gear = pymunk.GearJoint(robot_body, block_body, block_body.angle - robot_body.angle, 1.0)
        gear.collide_bodies = False
        self.space.add(pivot, gear)
        self._welds[robot] = (pivot, gear)
        if cfg.weld_spin == "free":  # the robot's friction torque lets go while it is welded
            self.control_gears[robot].max_force = 0.0
        if cfg.weld_seat:
            self.read_state()

    def unweld(self, robot: int) -> None:
        """Remove the pymunk weld of ``robot`` (the arrays are the caller's business)."""
        self.space.remove(*self._welds.pop(int(robot)))
        if self.config.weld_spin == "free":
            self.control_gears[int(robot)].max_force = control_limits(self.config)[1]

    def detach_block(self, block: int) -> None:
        """Release every robot welded to ``block`` and clear its sticky side."""
        for robot in np.flatnonzero(self.robot_attached == block):
            self.unweld(int(robot))
            self.robot_attached[robot] = -1
        self.anchor_owner[block] = -1
        self.block_sticky_side[block] = -1
