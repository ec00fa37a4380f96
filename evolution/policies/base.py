"""The ``Policy`` record every team policy is: a name, a morphology, ``act``, ``reset`` and, where
the policy knows it, the world it was made for."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from gathering_env import Morphology


@dataclass
class Policy:
    """A named team policy: ``act(obs (N, S)) -> wheels (N, 2)`` for its morphology.

    ``environment``: world parameters it was evolved or trained in (``WorldConfig`` keywords,
    e.g. ``{"environment": 1, "max_cycles": 2000}``), the defaults of ``gathering-replay``; None if unknown.
    ``bind``: for a privileged policy that reads the world's state (``oracle``), called with the
    episode's ``GatheringSimulation`` after each reset (``evolution.compare.run_episode`` and
    ``evolution.replay`` do); None for policies that read only their observations.
    """

    name: str
    morphology: Morphology
    act: Any
    reset: Any = field(default=lambda seed: None)
    environment: dict[str, Any] | None = None
    bind: Any = None


__all__ = ["Policy"]
