"""From an experiment to neat-python: the genome class, the checked config, the substrate.

``make_neat_config`` loads the experiment's neat-python config file with the method's genome
class and the arm's reproduction, and ``check_neat_config`` rejects what neat-python accepts
blindly (rates outside [0, 1], negative powers, unknown functions), naming file, section and key.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import neat

from evolution.reproduction.species import GatheringSpeciesSet, target_count, use_original_rule
from evolution.run.experiment import Experiment, ExperimentError


def genome_class(method: str) -> type:
    """The neat-python genome class of a method."""
    if method == "hyperneat-m":
        from evolution.encodings.genome import CPPNGenome

        return CPPNGenome
    from evolution.encodings.direct import NEATMGenome

    return NEATMGenome


def make_neat_config(experiment: Experiment) -> neat.Config:
    """Load the experiment's neat-python config; the population size comes from the experiment.

    Single-objective runs use ``NEATReproduction`` (neat-python's ``DefaultReproduction``
    selection, its ``[NEATReproduction]`` section); multi-objective runs use
    ``MODSReproduction`` (its ``[MODSReproduction]`` section in the same file). Both breed
    with ``evolution.reproduction.breeding.breed``.
    """
    path = experiment.neat_config
    if experiment.multi_objective:
        from evolution.reproduction.mods import MODSReproduction

        reproduction: type = MODSReproduction
    else:
        from evolution.reproduction.breeding import NEATReproduction

        reproduction = NEATReproduction
    try:
        config = neat.Config(genome_class(experiment.method), reproduction,
                             GatheringSpeciesSet, neat.DefaultStagnation, str(path))
    except Exception as err:  # neat raises several error types for broken files
        hint = ""
        if "GatheringSpeciesSet" in str(err) and "[DefaultSpeciesSet]" in Path(path).read_text(errors="replace"):
            hint = " (rename the section [DefaultSpeciesSet] to [GatheringSpeciesSet]: evolution.reproduction.species)"
        raise ExperimentError(f"{path}: invalid neat-python config: {err}{hint}") from None
    check_neat_config(config, path)
    if not experiment.multi_objective:
        # the experiment's elitism: "ratchet" carries the best-ever genome, unscored (NEATReproduction)
        config.reproduction_config.ratchet = experiment.elitism == "ratchet"
    config.pop_size = experiment.population
    config.genome_config.truncation = experiment.truncation  # read by breeding.breed, both arms
    if experiment.weights == "encog":
        from evolution.reproduction.encog import use_encog_weights

        use_encog_weights(config.genome_config, experiment.method)
    species = config.species_set_config
    if experiment.speciation is not None:
        species.species_mode = experiment.speciation
        if experiment.speciation == "original":
            use_original_rule(species, experiment.multi_objective, experiment.population)
            species.bookkeeping = experiment.species_bookkeeping  # SO: evolution.reproduction.bookkeeping
            if not experiment.multi_objective:  # Encog's stagnation (NEATReproduction's Encog selection)
                from evolution.reproduction.encog import ORIGINAL_MAX_STAGNATION, ORIGINAL_SPECIES_ELITISM

                config.stagnation_config.max_stagnation = ORIGINAL_MAX_STAGNATION
                config.stagnation_config.species_elitism = ORIGINAL_SPECIES_ELITISM
    if species.species_mode == "adaptive":
        try:
            target_count(species.target_species, experiment.population)
        except ValueError as err:
            raise ExperimentError(f"{path}: [GatheringSpeciesSet] {err} (the population)") from None
    return config


MAX_HIDDEN = 100
"""Upper bound of ``num_hidden`` (initial hidden nodes of every genome; the configs use 0)."""


def _cppn_genome() -> type:
    return genome_class("hyperneat-m")


def check_neat_config(config: neat.Config, path: Path) -> None:
    """Rates, bounds and sizes of a neat-python config that neat-python itself accepts blindly.

    Probabilities and rates must lie in [0, 1] (a negative rate silently switches a mutation
    off), powers, deviations and coefficients must be >= 0, every ``*_min_value`` <= its
    ``*_max_value``, ``num_hidden`` <= ``MAX_HIDDEN``. Raises ``ExperimentError`` naming the
    file, section and key.
    """
    def bad(section: str, key: str, value: Any, allowed: str) -> ExperimentError:
        return ExperimentError(f"{path}: [{section}] {key} = {value}; allowed: {allowed}")

    def number(value: Any) -> bool:
        return isinstance(value, (int, float)) and not isinstance(value, bool)

    genome, section = config.genome_config, config.genome_type.__name__
    for key, value in sorted(vars(genome).items()):
        if not number(value):
            continue
        if key.endswith("_add") and key.startswith("enabled_rate_to_"):
            total = genome.enabled_mutate_rate + value
            if not 0.0 <= total <= 1.0:
                raise bad(section, key, value, "enabled_mutate_rate + this in [0, 1]")
        elif key.endswith(("_rate", "_prob")):
            if not 0.0 <= value <= 1.0:
                raise bad(section, key, value, "a probability in [0, 1]")
        elif key.endswith(("_mutate_power", "_init_stdev", "_coefficient")):
            if not 0.0 <= value < float("inf"):
                raise bad(section, key, value, "a finite number >= 0")
        elif key.endswith(("_min_value", "_max_value", "_init_mean")) and value != value:
            raise bad(section, key, value, "a number")
        if key.endswith("_min_value"):
            high = getattr(genome, key[: -len("_min_value")] + "_max_value", None)
            if number(high) and value > high:
                raise bad(section, key, value, f"<= {key[: -len('_min_value')]}_max_value ({high})")
    for gene, defs in (("activation", genome.activation_defs), ("aggregation", genome.aggregation_function_defs)):
        options, default = getattr(genome, f"{gene}_options"), getattr(genome, f"{gene}_default")
        if not options:
            raise bad(section, f"{gene}_options", "(empty)", "one or more function names")
        unknown = [name for name in options if not defs.is_valid(name)]
        if unknown:
            raise bad(section, f"{gene}_options", " ".join(options), f"names neat-python knows (not {unknown})")
        if default not in options and default not in ("random", "none"):
            raise bad(section, f"{gene}_default", default, f"random, none or one of {gene}_options")
    if config.genome_type is not _cppn_genome():  # NEAT-M networks run on the team controller
        from evolution.encodings.controller import ACTIVATIONS

        unknown = [name for name in genome.activation_options if name not in ACTIVATIONS]
        if unknown:
            raise bad(section, "activation_options", " ".join(genome.activation_options),
                      f"functions of the team controller ({sorted(ACTIVATIONS)})")
    for key, value in sorted(vars(genome).items()):
        if key.endswith("_init_type") and value not in ("gaussian", "normal", "uniform"):
            raise bad(section, key, value, "gaussian, normal or uniform")
    if not 0 <= genome.num_hidden <= MAX_HIDDEN:
        raise bad(section, "num_hidden", genome.num_hidden, f"0..{MAX_HIDDEN}")
    stagnation = config.stagnation_config
    if stagnation.species_fitness_func not in ("max", "min", "mean", "median"):
        raise bad("DefaultStagnation", "species_fitness_func", stagnation.species_fitness_func,
                  "max, min, mean or median")
    if stagnation.max_stagnation < 1:
        raise bad("DefaultStagnation", "max_stagnation", stagnation.max_stagnation, "an integer >= 1")
    if stagnation.species_elitism < 0:
        raise bad("DefaultStagnation", "species_elitism", stagnation.species_elitism, "an integer >= 0")
    reproduction = config.reproduction_config
    if issubclass(config.reproduction_type, neat.DefaultReproduction):
        name = config.reproduction_type.__name__
        if reproduction.elitism < 0:
            raise bad(name, "elitism", reproduction.elitism, "an integer >= 0")
        if hasattr(reproduction, "survival_threshold") and not 0.0 < reproduction.survival_threshold <= 1.0:
            raise bad(name, "survival_threshold", reproduction.survival_threshold, "(0, 1]")
        if reproduction.min_species_size < 1:
            raise bad(name, "min_species_size", reproduction.min_species_size, "an integer >= 1")
        if hasattr(reproduction, "original_elite_rate") and not 0.0 <= reproduction.original_elite_rate <= 1.0:
            raise bad(name, "original_elite_rate", reproduction.original_elite_rate, "[0, 1]")


def substrate_for(experiment: Experiment) -> Any:
    if experiment.method != "hyperneat-m":
        return None
    from evolution.encodings.substrate import Substrate

    try:
        return Substrate(**experiment.substrate)
    except TypeError as err:
        raise ExperimentError(f"{experiment.source}: [substrate] {err}") from None


__all__ = ["MAX_HIDDEN", "check_neat_config", "genome_class", "make_neat_config", "substrate_for"]
