"""Co-evolution of robot-team controllers and sensor morphologies on neat-python.

Modules: ``substrate`` (HyperNEAT-M substrate and decoding), ``genome`` (the CPPN genome),
``direct`` (NEAT-M: direct encoding with sensor genes), ``controller`` (the batched team
controller), ``evaluate`` (a genome's trials through the env's public API), ``backends``
(serial / process-pool evaluation), ``breeding`` (the breeding routine shared by the SO and MO arms), ``mods`` and
``pareto`` (NEAT-MODS multi-objective reproduction, NSGA-II sorting), ``trainer`` (the generation loop, statistics, checkpoints,
champions), ``experiment`` (TOML experiment files), ``analysis``, ``reevaluate`` and ``report``
(fronts, selection points, held-out re-evaluation, statistical tests, figures), ``cli`` (console scripts).
"""

from gathering_env import __version__

__all__ = ["__version__"]
