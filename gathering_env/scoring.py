"""Scoring: which blocks are gathered, and the task performance of paper eq. 1."""

from __future__ import annotations

import numpy as np


def gathered_mask(block_pos: np.ndarray, block_angle: np.ndarray, block_half: np.ndarray,
                  zone_rect: tuple[float, float, float, float]) -> np.ndarray:
    """(B,) bool: the block's axis-aligned bounding box lies wholly inside the zone.

    Args:
        block_pos: (B, 2) centres. block_angle: (B,) rotations (rad). block_half: (B,)
            half side lengths. zone_rect: (x_min, y_min, x_max, y_max).
    """
    extent = block_half * (np.abs(np.cos(block_angle)) + np.abs(np.sin(block_angle)))
    x0, y0, x1, y1 = zone_rect
    x, y = block_pos[:, 0], block_pos[:, 1]
    return (x - extent >= x0) & (x + extent <= x1) & (y - extent >= y0) & (y + extent <= y1)


def task_performance(gathered_value: float, total_value: float, steps_used: int,
                     max_steps: int, time_bonus: float = 20.0) -> float:
    """Paper eq. 1: ``ft = 100 * v_c / v_t + bonus * (1 - s_e / s_t)``.

    The time bonus is paid only when every block is gathered (``v_c == v_t``); ``s_e`` is
    the number of steps used and ``s_t`` the step budget. Range: [0, 100 + time_bonus].
    """
    if total_value <= 0:
        raise ValueError(f"total_value={total_value!r} must be > 0")
    value_part = 100.0 * gathered_value / total_value
    if gathered_value >= total_value - 1e-9:
        return value_part + time_bonus * (1.0 - steps_used / max_steps)
    return value_part
