"""Team policies by name: scripted, evolved and learned, one home for every tool that runs a team.

``make_policy(name)`` builds a ``Policy`` (a morphology and ``act(obs (N, S)) -> wheels (N, 2)``)
from a name, as ``gathering-compare --policy`` takes it. Policies (each carries the morphology it was made for):

* ``random``: uniform random wheel commands (Khepera III morphology).
* ``heuristic``: the pickup heuristic with a fixed search pattern on Khepera III readings:
  drive forward on a slight curve, turn on the spot while the front ultrasonic or either
  infrared sensor reports an obstacle close ahead.
* ``wander``: the speed benchmark's explorer (``evolution.policies.scripted.WanderTeam``): forward
  at 0.8 of top speed with a drift redrawn every 50 steps, spin on the spot when the front
  ultrasonic has read an obstacle very close for 20 steps (Khepera III morphology).
* ``oracle``: a privileged scripted team (``evolution.policies.oracle``) that reads the world's
  state, not its sensors, and pushes every block to the zone with the robots it needs: an upper
  reference for what a world allows, not a controller a robot could run.
* ``champion:PATH``: an evolved team from a champion JSON (its own morphology).
* ``ppo:PATH``: a Stable-Baselines3 PPO model (``examples/rl_ppo.py``) with the morphology
  saved next to it (``PATH`` with suffix ``.morphology.json``), Khepera III if absent; its
  deterministic actions (the policy's mean; with discrete wheel commands, ``wheel_levels``,
  each wheel's most likely command).
* ``ppo-sample:PATH``: the same model with actions sampled from its distribution, as in
  training (torch's generator seeded by the episode seed).
* ``benchmarl:PATH``: a BenchMARL / TorchRL actor (IPPO, MAPPO, ...) exported by
  ``examples/benchmarl_run.py`` (``policy.pt``, with its morphology inside); its deterministic
  action. ``benchmarl-sample:PATH``: actions sampled as in training.

Modules: ``scripted`` (random, heuristic, ``WanderTeam``), ``evolved`` (champion files),
``oracle`` (the privileged team), ``learned`` (Stable-Baselines3 models), ``marl`` (BenchMARL / TorchRL policy files).
"""

from __future__ import annotations

from evolution.policies import evolved, learned, marl, oracle, scripted
from evolution.policies.base import Policy

KINDS = ("random", "heuristic", "wander", "oracle", "champion", "ppo", "ppo-sample", "benchmarl", "benchmarl-sample")
"""The kinds of policy name: ``KIND`` or ``KIND:PATH``."""


def is_policy_name(spec: str) -> bool:
    """Whether ``spec`` is written as a policy name (``wander``, ``ppo:PATH``, ...) rather than a file path."""
    return spec.partition(":")[0] in KINDS


def make_policy(spec: str) -> Policy:
    """The policy a name stands for (see the module docstring); ``ValueError`` naming the allowed names."""
    kind, _, arg = spec.partition(":")
    if kind == "random" and not arg:
        return scripted.random_policy()
    if kind == "heuristic" and not arg:
        return scripted.heuristic_policy()
    if kind == "wander" and not arg:
        return scripted.wander_policy()
    if kind == "oracle" and not arg:
        return oracle.oracle_policy()
    if kind == "champion" and arg:
        return evolved.champion_policy(arg)
    if kind in ("ppo", "ppo-sample") and arg:
        return learned.ppo_policy(arg, sample=kind == "ppo-sample")
    if kind in ("benchmarl", "benchmarl-sample") and arg:
        return marl.benchmarl_policy(arg, sample=kind == "benchmarl-sample")
    raise ValueError(f"--policy {spec}: unknown policy; allowed: {POLICY_NAMES}")


POLICY_NAMES = ("random, heuristic, wander, oracle, champion:PATH, ppo:PATH, ppo-sample:PATH, benchmarl:PATH, "
                "benchmarl-sample:PATH")
"""The names ``make_policy`` takes (for help texts and errors)."""


__all__ = ["KINDS", "POLICY_NAMES", "Policy", "is_policy_name", "make_policy", "evolved", "learned", "marl", "oracle", "scripted"]
