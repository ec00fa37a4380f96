"""The gathering environments as BenchMARL tasks: ``gathering/env1``, ``gathering/env2``, ``gathering/env3``.

Python API (any BenchMARL algorithm for continuous actions: IPPO, MAPPO, IDDPG, MADDPG, ISAC, MASAC)::

    from benchmarl.algorithms import MappoConfig
    from benchmarl.experiment import Experiment, ExperimentConfig
    from benchmarl.models.mlp import MlpConfig
    from gathering_env.rl.benchmarl_task import GatheringTask

    task = GatheringTask.ENV1.get_from_yaml()            # conf/task/gathering/env1.yaml
    task.config.update(reward="shaped", reward_scope="local")
    Experiment(task=task, algorithm_config=MappoConfig.get_from_yaml(), model_config=MlpConfig.get_from_yaml(),
               critic_model_config=MlpConfig.get_from_yaml(), seed=0,
               config=ExperimentConfig.get_from_yaml()).run()

BenchMARL's own config system (hydra): ``python -m gathering_env.rl.benchmarl_hydra
algorithm=mappo task=gathering/env1 task.reward_scope=team experiment.max_n_frames=480000``
(``benchmarl_hydra`` registers these tasks and adds their yaml files to hydra's search path).

The env of a task is ``GatheringTorchEnv`` with BenchMARL's ``num_envs`` as its number of worlds
(one compiled call steps them all), one group ``"robot"`` of N agents and the global state
(``gathering_env.state``) for centralised critics. Task config: every ``WorldConfig`` field
(``environment``, ``num_robots``, ``max_cycles``, ``reward``, ``reward_scope``, ``attach_reward``,
...) plus ``reward_scale`` (rewards are multiplied by it, TorchRL's ``RewardScaling``). The
episodes' ft is logged as ``ft_mean`` (``log_info``) over the episodes that ended in a batch.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from pathlib import Path
from typing import Any

from benchmarl.environments import Task, TaskClass, task_config_registry
from benchmarl.utils import _read_yaml_config
from torchrl.data import Composite
from torchrl.envs import EnvBase, RewardScaling, Transform

from ..config import WorldConfig
from .torchrl_env import GROUP, GatheringTorchEnv

CONFIG_DIR = Path(__file__).parent / "conf"
"""Hydra search-path root holding ``task/gathering/env{1,2,3}.yaml``."""

TASK_ONLY_KEYS = ("reward_scale", "route")
ROUTES = ("batched", "wrapper")
"""``route``: ``batched`` (default) GatheringTorchEnv, all worlds in one call; ``wrapper``: TorchRL's
``PettingZooWrapper`` around the PettingZoo env, one world each, BenchMARL stacks them in a ``SerialEnv``."""


def check_task_config(config: dict[str, Any]) -> dict[str, Any]:
    """The world part of a task config, checked (``ValueError`` naming a bad key or value)."""
    world = {k: v for k, v in config.items() if k not in TASK_ONLY_KEYS}
    scale = config.get("reward_scale", 1.0)
    if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not scale > 0:
        raise ValueError(f"reward_scale={scale!r}; allowed: a number > 0")
    if config.get("route", "batched") not in ROUTES:
        raise ValueError(f"route={config.get('route')!r}; allowed: {', '.join(ROUTES)}")
    WorldConfig.from_kwargs(**world)
    return world


class GatheringClass(TaskClass):
    """BenchMARL's task class for the gathering environments (see the module docstring)."""

    def get_env_fun(self, num_envs: int, continuous_actions: bool, seed: int | None,
                    device: Any) -> Callable[[], EnvBase]:
        if not continuous_actions:
            raise ValueError("gathering tasks have continuous wheel commands only; allowed: algorithms with "
                             "continuous actions (ippo, mappo, iddpg, maddpg, isac, masac)")
        world = check_task_config(copy.deepcopy(self.config))
        if self.config.get("route", "batched") == "wrapper":
            return lambda: _wrapped_env(world, seed, device)
        return lambda: GatheringTorchEnv(num_worlds=num_envs, seed=seed, device=device, **world)

    def supports_continuous_actions(self) -> bool:
        return True

    def supports_discrete_actions(self) -> bool:
        return False

    def has_render(self, env: EnvBase) -> bool:
        return False

    def max_steps(self, env: EnvBase) -> int:
        return int(self.config.get("max_cycles", WorldConfig.max_cycles))

    def group_map(self, env: EnvBase) -> dict[str, list[str]]:
        return env.group_map

    def observation_spec(self, env: EnvBase) -> Composite:
        group = env.full_observation_spec_unbatched[GROUP]
        return Composite({GROUP: Composite(observation=group["observation"].clone(), shape=group.shape)})

    def info_spec(self, env: EnvBase) -> Composite | None:
        return None

    def state_spec(self, env: EnvBase) -> Composite | None:
        spec = env.full_observation_spec_unbatched
        return Composite({"state": spec["state"].clone()}) if "state" in spec.keys() else None

    def action_spec(self, env: EnvBase) -> Composite:
        return env.full_action_spec_unbatched

    def action_mask_spec(self, env: EnvBase) -> Composite | None:
        return None

    def get_env_transforms(self, env: EnvBase) -> list[Transform]:
        scale = float(self.config.get("reward_scale", 1.0))
        if scale == 1.0:
            return []
        return [RewardScaling(loc=0.0, scale=scale, in_keys=[(GROUP, "reward")])]

    @staticmethod
    def log_info(batch) -> dict[str, float]:
        done = batch.get(("next", "done")).squeeze(-1)
        if not done.any():
            return {}
        key = ("next", "task_performance")
        if key not in batch.keys(True):                                     # the wrapper route
            ft = batch.get(("next", GROUP, "info", "task_performance"))[..., 0][done]
        else:
            ft = batch.get(key)[done]
        return {"ft_mean": float(ft.float().mean()), "episodes": float(done.sum())}

    @staticmethod
    def env_name() -> str:
        return "gathering"


def _wrapped_env(world: dict[str, Any], seed: int | None, device: Any) -> EnvBase:
    from torchrl.envs import PettingZooWrapper

    from ..env import parallel_env

    return PettingZooWrapper(parallel_env(**world), return_state=True, categorical_actions=False, seed=seed,
                             device=device)


class GatheringTask(Task):
    """BenchMARL's enum of the gathering tasks: environments 1, 2 and 3 (paper Table 2)."""

    ENV1 = None
    ENV2 = None
    ENV3 = None

    @staticmethod
    def associated_class():
        return GatheringClass

    def get_from_yaml(self, path: str | None = None) -> TaskClass:
        """The task with its config from ``conf/task/gathering/<task>.yaml`` (or ``path``)."""
        path = path or str(CONFIG_DIR / "task" / "gathering" / f"{self.name.lower()}.yaml")
        return self.get_task(config=dict(_read_yaml_config(path)))


def register() -> None:
    """Make ``task=gathering/env1`` (2, 3) known to BenchMARL's hydra loader."""
    for task in GatheringTask:
        task_config_registry[f"gathering/{task.name.lower()}"] = task


register()

__all__ = ["CONFIG_DIR", "GatheringClass", "GatheringTask", "check_task_config", "register"]
