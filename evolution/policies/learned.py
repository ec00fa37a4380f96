"""Learned teams as policies: Stable-Baselines3 models saved by ``examples/rl_ppo.py``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from evolution.policies.base import Policy
from gathering_env import Morphology


def ppo_policy(path: str, sample: bool = False) -> Policy:
    """A saved SB3 model (continuous or discrete wheel commands, as its action space says);
    deterministic actions (the policy's mean / most likely command), or with ``sample`` actions
    drawn from the policy's distribution (torch's generator seeded by the episode seed)."""
    try:
        from stable_baselines3 import PPO
    except ImportError:
        raise ValueError("ppo policies need Stable-Baselines3: pip install 'gathering-evolution[rl]'") from None
    from evolution.run.champion import read_json

    model_path = Path(path)
    if not model_path.is_file():
        raise ValueError(f"{model_path}: PPO model not found; allowed: a model .zip saved by Stable-Baselines3")
    morph_path = model_path.with_suffix(".morphology.json")
    morphology = Morphology.khepera_iii()
    if morph_path.exists():
        try:
            morphology = Morphology.coerce(read_json(morph_path, "morphology file"))
        except ValueError as err:
            raise ValueError(f"{morph_path}: {err}") from None
    try:
        model = PPO.load(str(model_path), device="cpu")
    except Exception as err:  # noqa: BLE001 - SB3/zipfile/torch raise many types for a broken file
        raise ValueError(f"{model_path}: not a readable Stable-Baselines3 PPO model ({type(err).__name__}: "
                         f"{err}); allowed: a model .zip saved by PPO.save") from None
    expected = model.observation_space.shape
    if expected != (len(morphology),):
        raise ValueError(f"{model_path}: the policy expects observations of shape {expected}, but its morphology "
                         f"has {len(morphology)} sensors; save the morphology as {morph_path.name}")

    from gathering_env.rl.sb3 import wheel_commands

    def act(obs):
        action, _ = model.predict(obs.astype(np.float32), deterministic=not sample)
        return wheel_commands(action, model.action_space).reshape(obs.shape[0], 2)

    def reset(seed):
        if sample:
            import torch

            torch.manual_seed(seed)

    # SB3 saves "model.zip" by default: name such a model after its run directory instead, and
    # a snapshot of rl_ppo.py (model-ENV_STEPS.zip) after its run and budget.
    label = model_path.stem
    if model_path.parent.name and (label == "model" or label.startswith("model-")):
        label = model_path.parent.name + label[len("model"):].replace("-", "@", 1)
    return Policy(f"{'ppo-sample' if sample else 'ppo'}:{label}", morphology, act, reset)


__all__ = ["ppo_policy"]
