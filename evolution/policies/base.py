"""The ``Policy`` record every team policy is: a name, a morphology, ``act`` and ``reset``."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from gathering_env import Morphology


@dataclass
class Policy:
    """A named team policy: ``act(obs (N, S)) -> wheels (N, 2)`` for its morphology."""

    name: str
    morphology: Morphology
    act: Any
    reset: Any = field(default=lambda seed: None)


__all__ = ["Policy"]
