"""NEAT-MODS: multi-objective reproduction for neat-python (Abramovich & Moshaiov, 2016).

``MODSReproduction`` is a neat-python reproduction class: pass it as ``reproduction_type``
to ``neat.Config`` and put its parameters in a ``[MODSReproduction]`` section::

    [MODSReproduction]
    species_bound = per_objective  # at most floor(N / objectives) species (the original);
                                   # or a fraction f in (0, 1]: floor(f * N) species
    progression   = round_robin    # the published serial progression; or by_front

neat-python's loop evaluates the population and then calls ``reproduce``. This class keeps
the previous parents with their objectives, so each call (docs/model.md §6):

1. pools the previous N parents with the N offspring just evaluated (2N, elitist: parents
   are never evaluated twice);
2. speciates the pool with the run's species set and sorts it by NSGA-II (non-dominated
   fronts, crowding distance within a front; ties by genome id); each genome gets a rank
   score, descending from the pool size in sort order;
3. walks the sorted pool and selects each genome's species the first time it appears, up
   to the species bound;
4. serial progression: each selected species' members sorted by rank score, one genome
   per species per row, row after row, until N parents are chosen (``round_robin``, the
   paper's and the original's scan). ``by_front`` runs the rows front by front instead
   (every member of a better front of the selected species before any member of a worse
   one), which keeps NSGA-II's elitism. (Only if the selected species hold fewer than N
   genomes altogether are further species admitted, in sort order, so that exactly N
   parents are always returned);
5. gives each selected species offspring in proportion to its parents' summed rank scores
   (largest remainder) and breeds them with ``evolution.reproduction.breeding.breed``, the same routine
   as the single-objective arm (truncation to the best parents by rank score, one operator
   per offspring; in crossover the better-ranked parent gives the disjoint genes).

Genomes must carry ``genome.objectives``, a tuple of floats, all maximised (the trainer
sets it; ``genome.fitness`` stays the task objective for neat-python's reporters). After
``reproduce`` the attributes ``parents`` (the N selected genomes) and ``front`` (first
front of the pool: list of (genome id, objectives)) describe the generation.
"""

from __future__ import annotations

import math
from itertools import count
from typing import Any

import numpy as np
from neat.config import ConfigParameter, DefaultClassConfig
from neat.innovation import InnovationTracker

from evolution.reproduction.breeding import breed
from evolution.reproduction.pareto import nsga2_order

PROGRESSIONS = ("round_robin", "by_front")
REMOVED_KEYS = {
    "species_bound_fraction": "use species_bound (per_objective, or a fraction in (0, 1])",
    "tournament_size": "parents are chosen by truncation (the genome section's parent_fraction), as in the SO arm",
    "crossover_rate": "set crossover_prob in the genome section (shared with the SO arm)",
}


class MODSReproduction(DefaultClassConfig):
    """NSGA-II selection over parents + offspring with NEAT speciation (see module docstring)."""

    @classmethod
    def parse_config(cls, param_dict: dict[str, str]) -> DefaultClassConfig:
        for key, hint in REMOVED_KEYS.items():
            if key in param_dict:
                raise ValueError(f"[MODSReproduction] {key}: no longer used; {hint}")
        config = DefaultClassConfig(param_dict, [
            ConfigParameter("species_bound", str, "per_objective"),
            ConfigParameter("progression", str, "round_robin"),
        ], "MODSReproduction")
        if config.progression not in PROGRESSIONS:
            raise ValueError(f"[MODSReproduction] progression={config.progression!r}; allowed: {list(PROGRESSIONS)}")
        species_bound_value(config.species_bound, 2, 1)  # validates
        return config

    def __init__(self, config: DefaultClassConfig, reporters: Any, stagnation: Any) -> None:
        # pylint: disable=super-init-not-called
        self.reproduction_config = config
        self.reporters = reporters
        self.stagnation = stagnation  # unused: MODS has no stagnation, species die by selection
        self.genome_indexer = count(1)
        self.ancestors: dict[int, tuple[int, ...]] = {}
        self.innovation_tracker = InnovationTracker()
        self.parents: dict[int, Any] = {}
        self.front: list[tuple[int, tuple[float, ...]]] = []
        self.front_genomes: dict[int, Any] = {}
        self.species_of: dict[int, int] = {}

    def create_new(self, genome_type: type, genome_config: Any, num_genomes: int) -> dict[int, Any]:
        genome_config.innovation_tracker = self.innovation_tracker
        genomes = {}
        for _ in range(num_genomes):
            key = next(self.genome_indexer)
            g = genome_type(key)
            g.configure_new(genome_config)
            genomes[key] = g
            self.ancestors[key] = ()
        return genomes

    # ------------------------------------------------------------------ selection
    def select(self, pool: dict[int, Any], species_of: dict[int, int], n: int
               ) -> tuple[list[int], dict[int, float], list[int]]:
        """NSGA-II sort, species selection and serial progression over ``pool``.

        Args:
            pool: genome id -> genome with ``objectives``. species_of: genome id -> species id.
            n: number of parents to select.

        Returns:
            (parent ids in selection order, rank score of every pool genome, selected species).
        """
        keys = sorted(pool)
        objectives = np.array([_objectives(pool[k]) for k in keys], dtype=float)
        order, front_of, _ = nsga2_order(objectives)
        ranked = [keys[i] for i in order]
        index = {k: i for i, k in enumerate(keys)}
        score = {k: float(len(keys) - pos) for pos, k in enumerate(ranked)}
        self.front = [(keys[i], tuple(objectives[i])) for i in order if front_of[i] == 0]

        bound = species_bound_value(self.reproduction_config.species_bound, n, objectives.shape[1])
        selected: list[int] = []
        for k in ranked:
            sid = species_of[k]
            if sid not in selected:
                selected.append(sid)
                if len(selected) == bound:
                    break
        members = {sid: [k for k in ranked if species_of[k] == sid] for sid in selected}
        if sum(len(m) for m in members.values()) < n:
            for k in ranked:  # too few genomes in the bounded species: admit more, in order
                sid = species_of[k]
                if sid not in members:
                    selected.append(sid)
                    members[sid] = [g for g in ranked if species_of[g] == sid]
                    if sum(len(m) for m in members.values()) >= n:
                        break
        parents: list[int] = []
        if self.reproduction_config.progression == "by_front":
            # Serial progression front by front: all of a better front before any of a worse
            # one (NSGA-II elitism), species taking turns within each front.
            levels = sorted({int(front_of[index[k]]) for sid in selected for k in members[sid]})
            queues = [[[k for k in members[sid] if front_of[index[k]] == level] for sid in selected]
                      for level in levels]
        else:
            queues = [[members[sid] for sid in selected]]  # the original's plain round robin
        for rows in queues:
            depth = 0
            while len(parents) < n and any(depth < len(r) for r in rows):
                for row in rows:
                    if depth < len(row) and len(parents) < n:
                        parents.append(row[depth])
                depth += 1
            if len(parents) >= n:
                break
        return parents, score, selected

    @staticmethod
    def offspring_counts(species_scores: dict[int, float], n: int) -> dict[int, int]:
        """Split ``n`` offspring over species in proportion to their summed rank scores."""
        total = sum(species_scores.values())
        sids = list(species_scores)
        exact = {sid: n * species_scores[sid] / total for sid in sids}
        counts = {sid: int(math.floor(exact[sid])) for sid in sids}
        leftover = n - sum(counts.values())
        by_remainder = sorted(sids, key=lambda s: (-(exact[s] - counts[s]), sids.index(s)))
        for sid in by_remainder[:leftover]:
            counts[sid] += 1
        return counts

    # ------------------------------------------------------------------ reproduction
    def reproduce(self, config: Any, species: Any, pop_size: int, generation: int) -> dict[int, Any]:
        """Select N parents from parents + evaluated offspring and breed N new offspring."""
        config.genome_config.innovation_tracker = self.innovation_tracker
        self.innovation_tracker.reset_generation()
        offspring = {gid: g for s in species.species.values() for gid, g in s.members.items()}
        pool = {**self.parents, **offspring}
        for gid, g in pool.items():
            if getattr(g, "objectives", None) is None:
                raise RuntimeError(f"genome {gid} has no 'objectives': the fitness function must set them")
        getattr(species, "speciate_pool", species.speciate)(config, pool, generation)
        species_of = dict(species.genome_to_species)
        self.species_of = species_of
        parent_ids, score, selected = self.select(pool, species_of, pop_size)
        self.parents = {k: pool[k] for k in parent_ids}
        self.front_genomes = {k: pool[k] for k, _ in self.front}

        by_species: dict[int, list[int]] = {sid: [] for sid in selected}
        for k in parent_ids:
            by_species[species_of[k]].append(k)
        by_species = {sid: ks for sid, ks in by_species.items() if ks}
        counts = self.offspring_counts({sid: sum(score[k] for k in ks) for sid, ks in by_species.items()},
                                       pop_size)
        # Keep only the surviving species (with their parents as members) in the species set.
        for sid in list(species.species):
            if sid not in by_species:
                del species.species[sid]
            else:
                species.species[sid].members = {k: pool[k] for k in by_species[sid]}

        new_population: dict[int, Any] = {}
        for sid, ks in by_species.items():
            ranked = sorted(ks, key=lambda k: -score[k])  # best first
            new_population.update(breed(ranked, pool, score, counts[sid], config, lambda: next(self.genome_indexer),
                                        self.ancestors))
        return new_population


def species_bound_value(setting: str, n: int, num_objectives: int) -> int:
    """The species bound for N parents: floor(N / objectives) or floor(fraction * N), at least 1."""
    if setting == "per_objective":
        return max(1, n // num_objectives)
    try:
        fraction = float(setting)
    except ValueError:
        fraction = float("nan")
    if not 0.0 < fraction <= 1.0:
        raise ValueError(f"[MODSReproduction] species_bound={setting!r}; allowed: 'per_objective' or a fraction in (0, 1]")
    return max(1, math.floor(fraction * n))


def _objectives(genome: Any) -> tuple[float, ...]:
    values = tuple(float(v) for v in genome.objectives)
    if any(math.isnan(v) for v in values):
        raise RuntimeError(f"genome {genome.key} has NaN objectives {values}")
    return values
