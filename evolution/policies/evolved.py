"""Evolved teams as policies: a champion file's controller and morphology."""

from __future__ import annotations

from pathlib import Path

from evolution.policies.base import Policy


def champion_name(path: str) -> str:
    """``champion:<run folder>`` for a run's ``champion.json``; ``champion:<folder>/<stem>`` for a
    file of another name (``champion-gen55.json``), so two champions of one run stay apart."""
    p = Path(path)
    if p.name == "champion.json":
        return f"champion:{p.parent.name or path}"
    return f"champion:{p.parent.name}/{p.stem}" if p.parent.name else f"champion:{p.stem}"


def champion_policy(path: str) -> Policy:
    from evolution.run.champion import load_champion

    champion = load_champion(path)
    return Policy(champion_name(path), champion.morphology, champion.controller.act,
                  environment=dict(champion.environment))


__all__ = ["champion_name", "champion_policy"]
