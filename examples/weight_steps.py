"""What one weight mutation does to the phenotype, in a run's latest population and a fresh one.

For each run folder given, the population of its latest checkpoint (``RUN_DIR/checkpoints``)
and a fresh initial population of the same neat config each get ``--mutations`` copies of
every genome put through one weight mutation, the run's own operation (``mutate_weights``:
neat-python-style steps, or Encog's with ``weights = "encog"``). Each copy is decoded and
compared with its parent's decoding. Printed per population (a markdown table):

* **unchanged**: the share of mutations after which controller and morphology are identical
  (a step on a CPPN output already clipped at +-1, or on a link below the threshold, does nothing);
* **types changed**: the share after which the list of sensor types differs;
* **links at the bound** (HyperNEAT-M): the share of the parents' controller weights and biases
  at +-``max_weight`` (5), i.e. decoded from a CPPN weight output clipped at +-1;
* **median step**: over the mutations that change the controller, the median of the largest
  change of one controller weight or bias.

Reads checkpoints only; writes nothing. A few seconds per run (decoding, no simulation)::

    python examples/weight_steps.py runs/S1-original-v4 runs/S1-original-v4-neat-weights
"""

from __future__ import annotations

import copy
import random
from pathlib import Path
from typing import Any

import neat
import numpy as np

from evolution.guard import ArgumentParser, UsageError, command, int_arg
from evolution.run.evaluate import decode_genome
from evolution.run.experiment import experiment_from_run
from evolution.run.neat_setup import substrate_for
from evolution.run.rundir import find_checkpoint


def phenotype(method: str, genome: Any, config: Any, substrate: Any) -> tuple[np.ndarray, list[Any], tuple]:
    """(every controller weight and bias as one vector, the sensors, the layers' shapes)."""
    controller, morphology = decode_genome(method, genome, config, substrate)
    values = [np.concatenate([layer.weights.ravel(), layer.bias.ravel()]) for layer in controller.layers]
    shapes = tuple(layer.weights.shape for layer in controller.layers)
    return (np.concatenate(values) if values else np.zeros(0)), list(morphology), shapes


def weight_steps(method: str, genomes: list[Any], config: Any, substrate: Any, mutations: int,
                 seed: int) -> dict[str, float]:
    """The figures of the module docstring for one population (``random`` seeded with ``seed``)."""
    random.seed(seed)
    bound = substrate.max_weight if substrate is not None else None
    n = unchanged = retyped = 0
    at_bound: list[float] = []
    steps: list[float] = []
    for genome in genomes:
        w0, sensors0, shape0 = phenotype(method, genome, config, substrate)
        if bound is not None and w0.size:
            at_bound.append(float(np.mean(np.abs(w0) >= bound - 1e-9)))
        for _ in range(mutations):
            child = copy.deepcopy(genome)
            child.mutate_weights(config.genome_config)
            w1, sensors1, shape1 = phenotype(method, child, config, substrate)
            n += 1
            same_controller = shape1 == shape0 and np.array_equal(w1, w0)
            unchanged += same_controller and sensors1 == sensors0
            retyped += [s.type for s in sensors1] != [s.type for s in sensors0]
            if not same_controller and shape1 == shape0:
                steps.append(float(np.max(np.abs(w1 - w0))))
    return {
        "mutations": n,
        "unchanged": unchanged / n,
        "types changed": retyped / n,
        "links at the bound": float(np.mean(at_bound)) if at_bound else float("nan"),
        "median step": float(np.median(steps)) if steps else float("nan"),
    }


def latest_population(run_dir: Path) -> tuple[Any, Any]:
    """(the run's experiment, the population of its newest readable checkpoint), as --resume finds it."""
    if not run_dir.is_dir():
        raise UsageError(f"{run_dir}: run folder not found; allowed: a gathering-evolve run folder")
    path, state = find_checkpoint(run_dir, None)
    return experiment_from_run(state["experiment"], str(path)), state["population"]


@command
def main(argv: list[str] | None = None) -> int:
    parser = ArgumentParser(prog="weight_steps.py", description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path, metavar="RUN_DIR")
    parser.add_argument("--mutations", type=int_arg(1, 1000), default=10, help="copies of each genome (default 10)")
    parser.add_argument("--seed", type=int_arg(0, 2**32 - 1), default=0, help="seeds the mutations and fresh populations")
    args = parser.parse_args(argv)
    loaded = [(run_dir, *latest_population(run_dir)) for run_dir in args.runs]  # every error before output
    keys = ("unchanged", "types changed", "links at the bound", "median step")
    print("| population | weights | mutations | " + " | ".join(keys) + " |")
    print("|---|---|---|" + "---|" * len(keys))
    for run_dir, experiment, population in loaded:
        method, substrate = experiment.method, substrate_for(experiment)
        config = population.config
        random.seed(args.seed)
        fresh = neat.Population(config)
        for label, genomes in ((f"{run_dir.name}, generation {population.generation}", population.population),
                               (f"{run_dir.name}, a fresh population", fresh.population)):
            figures = weight_steps(method, list(genomes.values()), config, substrate, args.mutations, args.seed)
            cells = ["–" if np.isnan(figures[k]) else f"{figures[k]:.3g}" if k == "median step" else f"{figures[k]:.0%}"
                     for k in keys]
            print(f"| {label} | {experiment.weights} | {figures['mutations']} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
