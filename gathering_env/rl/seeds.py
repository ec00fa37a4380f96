"""Episode seeds of the RL adapters: one generator per env, checked seeds."""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np

SEED_LIMIT = 2**31
"""Episode seeds are drawn uniformly from [0, SEED_LIMIT)."""


def check_seed(seed: Any) -> int | None:
    """``seed`` as an int (or None); ``ValueError`` naming what is allowed otherwise."""
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0):
        raise ValueError(f"seed={seed!r}; allowed: a non-negative integer or None")
    return None if seed is None else int(seed)


def episode_seeds(rng: np.random.Generator, count: int) -> list[int]:
    """``count`` episode seeds drawn from ``rng``."""
    return [int(s) for s in rng.integers(0, SEED_LIMIT, count)]


__all__ = ["SEED_LIMIT", "check_seed", "episode_seeds"]
