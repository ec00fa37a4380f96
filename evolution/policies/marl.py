"""BenchMARL / TorchRL policies as team policies: a policy file written by ``examples/benchmarl_run.py``.

The file (``policy.pt``) is one ``torch.save`` of a dict::

    {"format": "gathering-marl-policy", "version": 1, "algorithm": "mappo", "group": "robot",
     "num_robots": 20, "observation_size": 6, "morphology": {...}, "task": {...}, "policy": <module>}

where ``policy`` is the trained actor (BenchMARL's ``ProbabilisticActor`` on
``("robot", "observation")`` -> ``("robot", "action")``), pickled whole, so loading it needs
torch, tensordict and TorchRL (and BenchMARL's model classes: ``pip install
'gathering-evolution[marl]'``) but no BenchMARL experiment, config or checkpoint folder.
BenchMARL's own checkpoints (``checkpoint_*.pt``: the whole experiment's state) are refused
with a message saying how to export one.

``benchmarl:PATH`` takes the actor's deterministic action (the mean of its distribution; with
TanhNormal actions squashed into [-1, 1], with Gaussian ones clipped by the env);
``benchmarl-sample:PATH`` samples actions as in training (torch's generator seeded by the episode seed). Loading runs pickle: only load files you wrote.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from evolution.policies.base import Policy
from gathering_env import Morphology

FORMAT = "gathering-marl-policy"
VERSION = 1
GROUP = "robot"


def save_policy(path: Path, actor: Any, algorithm: str, morphology: Morphology, num_robots: int,
                task: dict[str, Any]) -> Path:
    """Write a policy file (see the module docstring) for ``benchmarl:PATH``."""
    import torch

    torch.save({"format": FORMAT, "version": VERSION, "algorithm": algorithm, "group": GROUP,
                "num_robots": int(num_robots), "observation_size": len(morphology),
                "morphology": morphology.to_dict(), "task": dict(task), "policy": actor}, path)
    return Path(path)


def read_policy_file(path: str | Path) -> dict[str, Any]:
    """The checked contents of a policy file; ``ValueError`` naming the file and what is allowed."""
    allowed = "a policy.pt written by examples/benchmarl_run.py"
    try:
        import torch
        import torchrl  # noqa: F401  (the actor's classes)
    except ImportError:
        raise ValueError("benchmarl policies need TorchRL and BenchMARL: pip install 'gathering-evolution[marl]'") from None
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: policy file not found; allowed: {allowed}")
    try:
        data = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as err:  # noqa: BLE001 - torch/pickle/zipfile raise many types for a foreign file
        raise ValueError(f"{path}: not a readable torch file ({type(err).__name__}); allowed: {allowed}") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        hint = ""
        if isinstance(data, dict) and ("collector" in data or any(str(k).startswith("loss_") for k in data)):
            hint = " (this is a BenchMARL experiment checkpoint; export its policy with examples/benchmarl_run.py --export)"
        raise ValueError(f"{path}: not a gathering MARL policy file{hint}; allowed: {allowed}")
    if data.get("version") != VERSION:
        raise ValueError(f"{path}: policy file version {data.get('version')!r}; allowed: version {VERSION}")
    return data


def worlds_actor(data: dict[str, Any], sample: bool = False, path: Any = "policy file"):
    """``act(obs (W, N, S)) -> wheels (W, N, 2)`` for many worlds at once (one forward pass)."""
    import torch
    from tensordict import TensorDict
    from torchrl.envs.utils import ExplorationType, set_exploration_type

    actor, group, n = data["policy"], data["group"], int(data["num_robots"])
    actor.eval()
    mode = ExplorationType.RANDOM if sample else ExplorationType.DETERMINISTIC

    def act(obs: np.ndarray) -> np.ndarray:
        if obs.shape[1] != n:
            raise ValueError(f"{path}: the policy was trained for {n} robots, the team has {obs.shape[1]}; "
                             f"allowed: --robots {n}")
        w = obs.shape[0]
        td = TensorDict({group: TensorDict({"observation": torch.as_tensor(obs, dtype=torch.float32)},
                                           batch_size=(w, n))}, batch_size=(w,))
        with torch.no_grad(), set_exploration_type(mode):
            action = actor(td).get((group, "action"))
        return action.numpy().astype(np.float64)

    return act


def benchmarl_policy(path: str, sample: bool = False) -> Policy:
    """A policy file's actor as a team policy (deterministic, or sampled with ``sample``)."""
    import torch

    data = read_policy_file(path)
    try:
        morphology = Morphology.coerce(data["morphology"])
    except ValueError as err:
        raise ValueError(f"{path}: bad morphology in the policy file ({err})") from None
    act_worlds = worlds_actor(data, sample, path)

    def act(obs: np.ndarray) -> np.ndarray:
        return act_worlds(obs[None])[0]

    def reset(seed):
        if sample:
            torch.manual_seed(seed)

    label = Path(path).stem
    if Path(path).parent.name and label == "policy":
        label = Path(path).parent.name
    task = data.get("task") or {}
    world = {k: task[k] for k in ("environment", "num_robots", "max_cycles") if k in task}
    return Policy(f"{'benchmarl-sample' if sample else 'benchmarl'}:{label}", morphology, act, reset,
                  environment=world or None)


__all__ = ["FORMAT", "VERSION", "benchmarl_policy", "read_policy_file", "save_policy", "worlds_actor"]
