"""Collective gathering: a PettingZoo environment with pymunk physics and configurable sensors.

Public names::

    parallel_env, env, raw_env          env factories (ParallelEnv, AEC with wrappers, raw AEC)
    SensorSpec, Morphology, SENSOR_TYPES  sensor suite description and per-type bounds
    morphological_complexity            paper eq. 2 (higher = simpler)
    WorldConfig, ENVIRONMENT_PRESETS    every world parameter, paper Table 2 presets
    VectorSimulation                    W independent worlds stepped together (gathering_env.vector)
    __version__                         the version of the gathering-evolution distribution

Importing the package registers ``gathering_env/CollectiveGathering-v0`` in PettingZoo's
registry: ``pettingzoo.make("parallel", "gathering_env/CollectiveGathering-v0", environment=2)``
(and ``"aec"``), and the centralised single-agent form in Gymnasium's:
``gymnasium.make("gathering_env/GatheringTeam-v0", environment=2)``.
"""

# The one place of the package version: pyproject.toml reads it (setuptools dynamic version).
__version__ = "0.1.0"

import gymnasium as _gymnasium
from pettingzoo import register as _register

from .config import ENVIRONMENT_PRESETS, WorldConfig
from .env import GatheringEnv, env, parallel_env, raw_env
from .sensors import SENSOR_TYPES, Morphology, SensorSpec, morphological_complexity
from .vector import VectorSimulation

ENV_ID = "gathering_env/CollectiveGathering-v0"
TEAM_ENV_ID = "gathering_env/GatheringTeam-v0"

_register("parallel", ENV_ID, entry_point="gathering_env.env:parallel_env")
_register("aec", ENV_ID, entry_point="gathering_env.env:env")
if TEAM_ENV_ID not in _gymnasium.registry:
    _gymnasium.register(TEAM_ENV_ID, entry_point="gathering_env.team_env:GatheringTeamEnv")

__all__ = [
    "__version__",
    "ENVIRONMENT_PRESETS",
    "ENV_ID",
    "TEAM_ENV_ID",
    "SENSOR_TYPES",
    "GatheringEnv",
    "Morphology",
    "SensorSpec",
    "VectorSimulation",
    "WorldConfig",
    "env",
    "morphological_complexity",
    "parallel_env",
    "raw_env",
]
