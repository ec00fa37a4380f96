"""Evolved teams as policies: a champion file's controller and morphology."""

from __future__ import annotations

from pathlib import Path

from evolution.policies.base import Policy


def champion_policy(path: str) -> Policy:
    from evolution.run.champion import load_champion

    champion = load_champion(path)
    return Policy(f"champion:{Path(path).parent.name or path}", champion.morphology, champion.controller.act,
                  environment=dict(champion.environment))


__all__ = ["champion_policy"]
