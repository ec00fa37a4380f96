"""Encog's single-objective selection and link weights, which the original protocol uses.

The 2018 code ran NEAT through Encog; with ``speciation = "original"`` in an SO run,
``evolution.reproduction.breeding.NEATReproduction`` selects as Encog's ``ThresholdSpeciation``
and ``SingleObjectiveEA`` did. This module holds the pieces of that rule that are Encog's own:
its constants, the offspring counts per species (``original_spawn``, with Java's rounding) and
the species leader after a generation (``original_leader``). The speciation itself (distance,
threshold) is ``evolution.reproduction.species``; docs/model.md and docs/fidelity.md say which
runs use it.

With ``weights = "encog"`` (``use_encog_weights``) link weights and biases follow the 2018 code's
Encog populations: drawn uniformly in [-5, 5] (its ``getWeightRange()``, for both methods) and
clamped there, and a weight operation is one of Encog's twelve (``ENCOG_WEIGHT_OPERATIONS``):
perturb 1, 2, 3 links or each link with probability 0.02 (at least one) by a Gaussian of the
method's small or large deviation, or reset them uniformly in the range.
"""

from __future__ import annotations

import math
from typing import Any

#: Encog's species elitism in the original's single-objective runs (``SingleObjectiveEA``'s
#: elite rate: the best fraction of every species of more than 5 genomes survives as it is). The
#: 2018 code that has the paper's convergence stop, time bonus 20 and 5 trials sets it to 0 (only
#: the ratchet's best genome survives); the commit that removed the stop (2018-12-03) set 0.2.
#: ``[NEATReproduction] original_elite_rate`` overrides it.
ORIGINAL_ELITE_RATE, ORIGINAL_ELITE_MIN_MEMBERS = 0.0, 5
#: Encog's stagnation in its speciation: a species is removed after more than 15 generations
#: without improvement (neat-python's ``max_stagnation`` counts to 16), except the species of the
#: best genome (``ThresholdSpeciation.removeSpecies``), whatever the other species score: so no
#: species is spared for its fitness (``species_elitism`` 0) and ``NEATReproduction`` spares that one.
ORIGINAL_MAX_STAGNATION, ORIGINAL_SPECIES_ELITISM = 16, 0


#: Encog's link-weight range in the 2018 code (its ``NEATPopulation.getWeightRange()`` returns 5.0
#: for HyperNEAT-M's CPPN and NEAT-M's network alike): initial, added and reset weights are uniform
#: in [-5, 5], and a perturbed weight is clamped to it.
ENCOG_WEIGHT_RANGE = 5.0
#: ``[experiment] weights``: the neat config's weight keys, or the original's (``use_encog_weights``).
WEIGHT_SCHEMES = ("neat", "encog")
#: The Gaussian deviations of the original's weight perturbation, small and large, per method
#: (``HyperNEATMUtil``: 0.02 and 1; ``NEATMUtil``: 0.004 and 0.2).
ENCOG_PERTURB_SIGMAS = {"hyperneat-m": (0.02, 1.0), "neat-m": (0.004, 0.2)}
#: The original's weight operation (a ``CompoundOperator``): (links, deviation index or None for a
#: reset, probability). Links: a count of distinct links, or a float p: each link with probability
#: p, one at random if none was drawn (``SelectProportion``).
ENCOG_WEIGHT_OPERATIONS = tuple(
    [(links, sigma, 0.1125) for sigma in (0, 1) for links in (1, 2, 3, 0.02)]
    + [(1, None, 0.03), (2, None, 0.03), (3, None, 0.03), (0.02, None, 0.01)])


def use_encog_weights(genome_config: Any, method: str) -> None:
    """Set a neat-python genome config to the original's link weights (see the module docstring):
    weights and biases initialised uniformly in +-``ENCOG_WEIGHT_RANGE`` and clamped there; the
    weight operator (``BreedingGenome.mutate_weights``) draws from ``ENCOG_WEIGHT_OPERATIONS``
    with the method's deviations. neat-python's ``uniform`` init draws in mean +- 2 stdev."""
    for gene in ("weight", "bias"):
        setattr(genome_config, f"{gene}_init_type", "uniform")
        setattr(genome_config, f"{gene}_init_mean", 0.0)
        setattr(genome_config, f"{gene}_init_stdev", ENCOG_WEIGHT_RANGE / 2)
        setattr(genome_config, f"{gene}_min_value", -ENCOG_WEIGHT_RANGE)
        setattr(genome_config, f"{gene}_max_value", ENCOG_WEIGHT_RANGE)
    genome_config.encog_sigmas = ENCOG_PERTURB_SIGMAS[method]


def original_leader(members: dict[int, Any], incumbent: int) -> int:
    """Encog's species leader after a generation (``ThresholdSpeciation.addSpeciesMember``).

    The species starts from its leader (``incumbent``: the one it was speciated against, or its
    founder), members join in key order, and a member takes over only when it scores *strictly*
    higher than the leader so far: the incumbent keeps the place on a tie, else the lowest key of
    the best score wins. (Ranking by score alone hands a tie to a new offspring; with elite rate
    0 that offspring is not carried, so the species is disbanded at the next speciation.)
    """
    top = max(g.fitness for g in members.values())
    if incumbent in members and members[incumbent].fitness >= top:
        return incumbent
    return min(k for k, g in members.items() if g.fitness >= top)


def java_round(x: float) -> int:
    """Java's ``Math.round`` (halves round up), as Encog rounds offspring shares."""
    return int(math.floor(x + 0.5))


def original_spawn(means: list[float], bests: list[float], best: int | None, places: int) -> list[int]:
    """Encog's offspring counts per species (``ThresholdSpeciation``), 0 for a species that dies.

    ``means``: each species' mean score (its share; negative counts as 0), ``bests``: its best
    score, ``best``: index of the best species (the one holding the best genome; with Encog's
    books the one it points at, None if that is not among them), ``places``: offspring to
    place. Each species gets ``round(share / total * places)``; a species whose count rounds to 0
    dies (not the best one, which gets at least 1); with every share 0 each gets
    ``round(places / n)``. Then *level off*: species ordered by best score, the first gets at
    least 1; a surplus is taken from the last species backwards (never the first), a shortfall
    goes to the first.
    """
    n = len(means)
    shares = [max(0.0, m) for m in means]
    total = sum(shares)
    if total < 1e-7:  # Encog.DEFAULT_DOUBLE_EQUAL
        counts = [java_round(places / n)] * n
    else:
        counts = [java_round(share / total * places) for share in shares]
        if best is not None:
            counts[best] = max(counts[best], 1)
    order = sorted((i for i in range(n) if counts[i] > 0), key=lambda i: (-bests[i], i))
    counts[order[0]] = max(counts[order[0]], 1)
    diff = places - sum(counts)
    if diff < 0:
        for i in reversed(order[1:]):
            take = min(counts[i], -diff)
            counts[i] -= take
            diff += take
            if diff == 0:
                break
    counts[order[0]] += max(diff, 0)
    return counts
