"""Evaluate one genome: decode it, run its team for several trials, return its objectives.

A genome's trials run as one batch of worlds (``gathering_env.vector.VectorSimulation``):
every step, the team controller acts once on the readings of all trials' robots, stacked
``(trials * N, S)``, and one compiled call steps every trial still running. Each trial's
episode is exactly the one ``parallel_env(**env_config)`` gives for its seed.

Trial seeds are derived from (run seed, generation, trial index) only, so every genome of
a generation meets the same worlds and a result does not depend on which process ran it.
With ``layout = "per_run"`` (the original code) every trial of every generation has the
seed of (run seed, 0, 0): the simulation is deterministic, so the trials would be the same
episode, and it is run once (``episode_seeds``). Under the shuffled schedule (``schedule =
"shuffled"``) episodes of one layout differ, as the original's trials did: the run's layout is
then fixed by the world's ``layout_seed`` (the seed of (run seed, 0, 0); ``training_environment``)
and trial t runs with the seed of (run seed, 0, t), which drives only its schedule.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from gathering_env import SENSOR_TYPES, Morphology, morphological_complexity
from gathering_env.vector import VectorSimulation

_SIM_CACHE: dict[str, VectorSimulation] = {}


def trial_seed(run_seed: int, generation: int, trial: int) -> int:
    """The episode seed of ``trial`` in ``generation`` of a run (a 32-bit integer)."""
    return int(np.random.SeedSequence([int(run_seed), int(generation), int(trial)]).generate_state(1)[0])


def varied_episodes(environment: dict[str, Any] | None) -> bool:
    """Whether two episodes of one layout can differ in this world: only under the shuffled
    schedule (everything else in the simulator is deterministic)."""
    return (environment or {}).get("schedule", "fixed") == "shuffled"


def episode_seeds(run_seed: int, generation: int, trials: int, layout: str = "per_trial",
                  environment: dict[str, Any] | None = None) -> list[int]:
    """The seeds of the episodes a genome of ``generation`` runs: one per trial, or with
    ``layout = "per_run"`` the run's single layout, once (its trials would be identical), unless
    the world's episodes vary (``varied_episodes``): then one per trial, of generation 0."""
    if layout == "per_run":
        return [trial_seed(run_seed, 0, trial) for trial in range(trials if varied_episodes(environment) else 1)]
    if layout != "per_trial":
        raise ValueError(f"layout={layout!r}; allowed: 'per_trial', 'per_run'")
    return [trial_seed(run_seed, generation, trial) for trial in range(trials)]


def training_environment(environment: dict[str, Any], run_seed: int, layout: str) -> dict[str, Any]:
    """The world a run's genomes are evaluated in: ``environment``, and with ``layout =
    "per_run"`` in a world whose episodes vary, ``layout_seed`` fixed to the run's layout, so
    the trials share it and differ by their schedules."""
    if layout == "per_run" and varied_episodes(environment):
        return {**environment, "layout_seed": trial_seed(run_seed, 0, 0)}
    return dict(environment)


def decode_genome(method: str, genome: Any, config: Any, substrate: Any = None):
    """(TeamController, Morphology) of a genome for the given method."""
    if method == "hyperneat-m":
        from evolution.encodings.substrate import Substrate, decode

        return decode(genome, config, substrate if substrate is not None else Substrate())
    if method == "neat-m":
        from evolution.encodings.direct import decode_neat_m

        return decode_neat_m(genome, config)
    raise ValueError(f"method={method!r}; allowed: 'hyperneat-m', 'neat-m'")


def sensor_statistics(morphology: Morphology) -> dict[str, float]:
    """Flat per-type statistics: ``count_<type>``, ``range_<type>``, ``fov_<type>`` (means, NaN if absent)."""
    stats: dict[str, float] = {"num_sensors": float(len(morphology))}
    for kind in SENSOR_TYPES:
        members = [s for s in morphology if s.type == kind]
        stats[f"count_{kind}"] = float(len(members))
        if SENSOR_TYPES[kind].configurable:
            stats[f"range_{kind}"] = float(np.mean([s.range for s in members])) if members else float("nan")
            stats[f"fov_{kind}"] = float(np.mean([s.fov for s in members])) if members else float("nan")
    return stats


@dataclass
class Evaluation:
    """Outcome of one genome's trials. All objectives are to be maximised."""

    task: float
    """Mean task performance ft over the trials (paper eq. 1)."""
    morphology: float
    """Morphological simplicity C (paper eq. 2)."""
    controller: float
    """Controller simplicity, 100 - number of links (the original's definition)."""
    trial_ft: list[float] = field(default_factory=list)
    sensors: dict[str, float] = field(default_factory=dict)
    steps: int = 0
    seconds_env: float = 0.0
    seconds_controller: float = 0.0
    seconds_decode: float = 0.0

    failed: bool = False
    error: str = ""

    @classmethod
    def failure(cls, error: str) -> Evaluation:
        """The worst outcome, for a genome whose evaluation kept failing: every objective 0
        (ft's minimum, the simplicity of ten full sensors, a controller of 100 links)."""
        return cls(task=0.0, morphology=0.0, controller=0.0, sensors=sensor_statistics(Morphology()),
                   failed=True, error=error)

    def objectives(self, names: tuple[str, ...]) -> tuple[float, ...]:
        return tuple(float(getattr(self, n)) for n in names)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _worlds_for(env_config: dict[str, Any], trials: int) -> VectorSimulation:
    """The process's batch of ``trials`` worlds for ``env_config`` (built once, reused)."""
    key = repr((sorted(env_config.items()), trials))
    sims = _SIM_CACHE.get(key)
    if sims is None:
        sims = VectorSimulation(trials, **env_config)
        _SIM_CACHE.clear()  # one live batch per process
        _SIM_CACHE[key] = sims
    return sims


def run_trials(sims: VectorSimulation, controller, morphology: Morphology,
               seeds: list[int]) -> tuple[np.ndarray, int, float, float]:
    """One episode per world, all stepped together.

    Returns (ft per world, total steps over the worlds, seconds in the simulation,
    seconds in the controller)."""
    obs = sims.reset(seeds, morphology)
    worlds, robots, width = obs.shape
    t_env = t_ctrl = 0.0
    clock = time.perf_counter
    while True:
        t0 = clock()
        wheels = controller.act(obs.reshape(worlds * robots, width)).reshape(worlds, robots, 2)
        t1 = clock()
        obs, _, _, _ = sims.step(wheels)
        t_env += clock() - t1
        t_ctrl += t1 - t0
        if not sims.active.any():
            break
    return sims.task_performance(), int(sims.steps.sum()), t_env, t_ctrl


def evaluate(genome: Any, config: Any, env_config: dict[str, Any], trials: int = 5, seed: int = 0,
             generation: int = 0, method: str = "hyperneat-m", substrate: Any = None,
             layout: str = "per_trial", complexity: str = "paper") -> Evaluation:
    """Decode ``genome`` and run its team for ``trials`` episodes.

    Args:
        genome: a neat-python genome of the method's genome class. config: its ``neat.Config``.
        env_config: keyword arguments of ``gathering_env.parallel_env`` (a run's
            ``training_environment``).
        trials: episodes; the task objective is the mean ft. seed: the run seed.
        generation: used with ``seed`` to derive the trial seeds. layout: ``episode_seeds``.
        complexity: the formula of eq. 2 (``gathering_env.morphological_complexity``).

    Returns:
        An ``Evaluation`` with the three objectives, per-trial ft and sensor statistics.
    """
    t0 = time.perf_counter()
    controller, morphology = decode_genome(method, genome, config, substrate)
    t_decode = time.perf_counter() - t0
    seeds = episode_seeds(seed, generation, trials, layout, env_config)
    sims = _worlds_for(env_config, len(seeds))
    fts, total_steps, t_env, t_ctrl = run_trials(sims, controller, morphology, seeds)
    return scored(controller, morphology, fts, complexity, steps=total_steps, seconds_env=t_env,
                  seconds_controller=t_ctrl, seconds_decode=t_decode)


def scored(controller, morphology: Morphology, fts, complexity: str = "paper", **work: Any) -> Evaluation:
    """The ``Evaluation`` of a decoded genome whose trials scored ``fts``: the task objective is
    their mean; the others, and the sensor statistics, follow from the decoded genome.
    ``work``: ``steps`` and the ``seconds_*`` of the evaluation."""
    return Evaluation(
        task=float(np.mean(fts)),
        morphology=morphological_complexity(morphology, complexity),
        controller=100.0 - float(controller.num_links),
        trial_ft=[float(f) for f in fts],
        sensors=sensor_statistics(morphology),
        **work,
    )
