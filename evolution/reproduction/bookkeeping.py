"""Encog's species bookkeeping, as the 2018 code ran it (``species_bookkeeping = "encog"``).

With ``speciation = "original"`` in a single-objective run with the ratchet, versions 1-9 of the
original protocol name species by who is in them: the best species is the one that holds the
best genome, a species whose leader did not survive is disbanded, the initial population is one
species and its best genome is the best. Encog 3.3 (``ThresholdSpeciation``, ``BasicSpecies``,
``NEATGenome``) and the 2018 ``SingleObjectiveEA`` keep different books, and with
``species_bookkeeping = "encog"`` (protocol version 10) this module keeps them the same way:

* **A genome points at a species** (``species_pointer``, a species id or None). The pointer is
  set only when the genome *joins* a species in a speciation; a genome that founds a species
  keeps the pointer it had, a leader keeps its own. A child made by mutation inherits its
  parent's pointer (Encog copies the genome), one made by crossover has none, and so have the
  genomes of the initial population (``inherit_pointer``).
* **The best species is the best genome's pointer**, not the species that holds it. It is
  never disbanded: when its leader did not survive, it lives on with that dead leader as its
  only member (``BasicSpecies.purge``), new genomes join it when they are within the threshold
  of the dead leader, and the dead leader still breeds in it. Nor is the last species disbanded.
  Every other species whose leader did not survive is.
* **The threshold counts what survived**, zombies included: when the best genome founded its
  species, its pointer keeps another species alive, two species survive, and the threshold does
  not move (with the membership books it falls by 0.01 every generation).
* **Speciation follows scoring.** Encog speciates a generation after scoring it, so leaders
  change *during* the pass (a joining genome that scores strictly higher than the leader
  becomes the leader the later genomes are compared with) and the species a genome may join
  are in the order the last levelling sorted them: by their leaders' scores, best first, then
  the new ones in the order they were founded. ``GatheringSpeciesSet`` keeps the population that
  ``speciate`` hands it and ``NEATReproduction`` speciates it here, once it has been scored.
* **Generation 0.** The initial population is one species led by its first genome; Encog
  speciates it after scoring, with the threshold already lowered once (0.99). Its random link
  weights put nearly every genome beyond that from every leader, so nearly every genome founds
  a species of its own and breeds in proportion to its score, by mutation alone. The "best
  genome" the ratchet starts from is the *first* genome with a finite score, whatever it
  scored (``first_best``): it is carried into generation 1 and the fittest of generation 0 is not.

Encog's stagnation is left to ``NEATReproduction`` as in the earlier versions (it spares the
best species, here the pointer's).
"""

from __future__ import annotations

import math
from typing import Any

BOOKKEEPING = ("membership", "encog")


def pointer(genome: Any) -> int | None:
    """A genome's species pointer (None: it never joined a species)."""
    return getattr(genome, "species_pointer", None)


def inherit_pointer(child: Any, parents: tuple[Any, ...]) -> None:
    """A child's pointer: its parent's after a mutation (one parent), none after a crossover."""
    child.species_pointer = pointer(parents[0]) if len(parents) == 1 else None


def first_best(population: dict[int, Any]) -> Any:
    """Encog's best genome before the first generation is bred: the first genome (lowest key)
    whose score is finite, else the last one (``SingleObjectiveEA.preIteration``)."""
    keys = sorted(population)
    for key in keys:
        if math.isfinite(population[key].fitness):
            return population[key]
    return population[keys[-1]]


def speciate_scored(species_set: Any, config: Any, population: dict[int, Any], generation: int,
                    best: Any) -> tuple[float, int]:
    """Speciate a scored ``population`` with Encog's books (see the module docstring).

    ``species_set``: the ``GatheringSpeciesSet`` (its species, in Encog's list order, hold their
    leaders as ``representative``); ``best``: the ratchet's best genome. Returns (the threshold
    used, the number of species).
    """
    cfg = species_set.species_set_config
    if not species_set.species:  # generation 0: one species, led by the first genome
        sid = next(species_set.indexer)
        species_set.species[sid] = _species(sid, generation, population[min(population)])
    best_species = pointer(best)
    order = list(species_set.species)
    leaders = {sid: species_set.species[sid].representative for sid in order}
    for sid in list(order):  # Encog's resetSpecies, in list order
        if leaders[sid].key not in population and sid != best_species and len(order) > 1:
            order.remove(sid)
    # adjustCompatibilityThreshold, from the species that survived (zombies included)
    if len(order) > cfg.max_species:
        species_set.threshold += cfg.threshold_step
    elif len(order) < cfg.min_species:
        species_set.threshold -= cfg.threshold_step
    threshold = species_set.threshold
    members = {sid: {leaders[sid].key: leaders[sid]} for sid in order}
    leading = {g.key for g in leaders.values()}  # every leader keeps its place (dead ones: no place)
    for key in sorted(population):
        if key in leading:
            continue
        genome = population[key]
        for sid in order:
            if species_set._original(leaders[sid], genome, config) <= threshold:
                members[sid][key] = genome
                if genome.fitness > leaders[sid].fitness:
                    leaders[sid] = genome  # the leader changes mid-pass
                genome.species_pointer = sid
                break
        else:  # a founder keeps its pointer
            sid = next(species_set.indexer)
            order.append(sid)
            leaders[sid], members[sid] = genome, {key: genome}
    kept = {}
    species_set.genome_to_species = {}
    for sid in order:
        species = species_set.species.get(sid) or _species(sid, generation, leaders[sid])
        species.update(leaders[sid], members[sid])
        kept[sid] = species
        for key in members[sid]:
            species_set.genome_to_species[key] = sid
    species_set.species = kept
    return threshold, len(order)


def levelled_order(species: dict[int, Any]) -> dict[int, Any]:
    """The species in the order Encog's ``levelOff`` leaves them for the next speciation: by
    their leaders' scores, best first, ties in their present order."""
    return dict(sorted(species.items(), key=lambda item: -item[1].representative.fitness))


def _species(sid: int, generation: int, leader: Any) -> Any:
    import neat

    species = neat.species.Species(sid, generation)
    species.update(leader, {leader.key: leader})
    return species


__all__ = ["BOOKKEEPING", "first_best", "inherit_pointer", "levelled_order", "pointer", "speciate_scored"]
