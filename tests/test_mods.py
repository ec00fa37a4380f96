"""MODSReproduction: selection by hand, elitism, species bound, population size, in neat-python."""

from __future__ import annotations

import random
from types import SimpleNamespace

import neat
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evolution.reproduction.mods import MODSReproduction
from evolution.reproduction.operators import BreedingGenome
from evolution.reproduction.pareto import non_dominated_fronts

NEAT_CFG = """
[NEAT]
fitness_criterion     = max
fitness_threshold     = 1e9
pop_size              = {pop}
reset_on_extinction   = False
no_fitness_termination = True

[BreedingGenome]
variation = one_operator
parent_fraction = 0.3
crossover_prob = 0.5
weight_mutate_prob = 0.5
num_inputs = 2
num_outputs = 1
num_hidden = 0
feed_forward = True
initial_connection = full_direct
activation_default = tanh
activation_mutate_rate = 0.0
activation_options = tanh
aggregation_default = sum
aggregation_mutate_rate = 0.0
aggregation_options = sum
bias_init_mean = 0.0
bias_init_stdev = 1.0
bias_init_type = gaussian
bias_max_value = 5.0
bias_min_value = -5.0
bias_mutate_power = 0.5
bias_mutate_rate = 0.7
bias_replace_rate = 0.1
compatibility_disjoint_coefficient = 1.0
compatibility_weight_coefficient = 0.5
conn_add_prob = 0.3
conn_delete_prob = 0.1
enabled_default = True
enabled_mutate_rate = 0.01
enabled_rate_to_false_add = 0.0
enabled_rate_to_true_add = 0.0
node_add_prob = 0.2
node_delete_prob = 0.1
response_init_mean = 1.0
response_init_stdev = 0.0
response_init_type = gaussian
response_max_value = 1.0
response_min_value = 1.0
response_mutate_power = 0.0
response_mutate_rate = 0.0
response_replace_rate = 0.0
weight_init_mean = 0.0
weight_init_stdev = 1.0
weight_init_type = gaussian
weight_max_value = 5
weight_min_value = -5
weight_mutate_power = 0.5
weight_mutate_rate = 0.8
weight_replace_rate = 0.1
single_structural_mutation = False
structural_mutation_surer = default

[DefaultSpeciesSet]
compatibility_threshold = {threshold}

[DefaultStagnation]
species_fitness_func = max
max_stagnation = 15
species_elitism = 0

[MODSReproduction]
species_bound = 0.5
progression = {progression}
"""


def make_config(tmp_path, pop=20, threshold=1.0, progression="by_front"):
    path = tmp_path / "mods.cfg"
    path.write_text(NEAT_CFG.format(pop=pop, threshold=threshold, progression=progression))
    return neat.Config(BreedingGenome, MODSReproduction, neat.DefaultSpeciesSet, neat.DefaultStagnation, str(path))


def genome(key, *objectives):
    return SimpleNamespace(key=key, objectives=tuple(objectives), fitness=objectives[0])


def make_reproduction(fraction=0.5):
    cfg = SimpleNamespace(species_bound=str(fraction), progression="by_front")
    return MODSReproduction(cfg, reporters=None, stagnation=None)


def test_selection_by_hand():
    # (task, simplicity); species: a = {1, 2, 3}, b = {4, 5}, c = {6}.
    pool = {1: genome(1, 90, 10), 2: genome(2, 80, 5), 3: genome(3, 10, 1),
            4: genome(4, 50, 60), 5: genome(5, 40, 50), 6: genome(6, 20, 20)}
    species_of = {1: "a", 2: "a", 3: "a", 4: "b", 5: "b", 6: "c"}
    # Fronts: F0 = {1, 4}; F1 = {2, 5}; F2 = {6}... (6 is dominated by 5 only) -> F2 = {6};
    # F3 = {3}. Crowding: two-point fronts are all inf -> ties broken by id.
    # Sorted pool: 1, 4, 2, 5, 6, 3 -> rank scores 6, 5, 4, 3, 2, 1.
    # N = 4 parents, bound = floor(0.5 * 4) = 2 species: a (from 1) and b (from 4).
    # Serial progression, front by front: F0 -> 1 (a), 4 (b); F1 -> 2 (a), 5 (b).
    parents, score, selected = make_reproduction().select(pool, species_of, 4)
    assert parents == [1, 4, 2, 5]
    assert selected == ["a", "b"]
    assert score == {1: 6.0, 4: 5.0, 2: 4.0, 5: 3.0, 6: 2.0, 3: 1.0}
    # Offspring counts proportional to summed rank scores: a = 6 + 4 = 10, b = 5 + 3 = 8 -> 4 * 10/18, 4 * 8/18.
    assert MODSReproduction.offspring_counts({"a": 10.0, "b": 8.0}, 4) == {"a": 2, "b": 2}
    assert MODSReproduction.offspring_counts({"a": 10.0, "b": 8.0}, 9) == {"a": 5, "b": 4}


def test_front_by_front_progression_keeps_the_front():
    # Species a holds three first-front genomes; species b one first-front and two dominated ones.
    pool = {1: genome(1, 10, 1), 2: genome(2, 9, 2), 3: genome(3, 8, 3), 4: genome(4, 1, 10),
            5: genome(5, 0, 9), 6: genome(6, 0, 8)}
    species_of = {1: "a", 2: "a", 3: "a", 4: "b", 5: "b", 6: "b"}
    by_front, _, _ = make_reproduction().select(pool, species_of, 4)
    assert sorted(by_front) == [1, 2, 3, 4]
    plain = make_reproduction()
    plain.reproduction_config.progression = "round_robin"
    round_robin, _, _ = plain.select(pool, species_of, 4)
    assert 5 in round_robin and len(set(round_robin) & {1, 2, 3}) == 2  # the original drops a front genome


@settings(max_examples=100, deadline=None)
@given(st.integers(2, 30), st.integers(1, 8), st.integers(0, 10_000))
def test_selection_invariants(n, num_species, seed):
    rng = np.random.default_rng(seed)
    size = 2 * n
    objectives = rng.integers(0, 5, size=(size, 2)).astype(float)
    pool = {k: genome(k, *objectives[k]) for k in range(size)}
    species_of = {k: int(rng.integers(num_species)) for k in range(size)}
    parents, _, selected = make_reproduction().select(pool, species_of, n)
    assert len(parents) == n and len(set(parents)) == n                      # exactly N parents
    front = set(non_dominated_fronts(objectives)[0].tolist())
    bound = max(1, n // 2)
    in_bound = [s for s in selected[:bound]]
    members = sum(1 for k in pool if species_of[k] in in_bound)
    if members >= n:                                                         # species bound respected
        assert len({species_of[k] for k in parents}) <= bound
        assert len(selected) <= bound
    if len(front) < n and members >= n and len({species_of[k] for k in front}) <= bound:
        assert front <= set(parents)                                         # elitism


def test_runs_inside_neat_population(tmp_path):
    config = make_config(tmp_path, pop=20, threshold=1.5)
    population = neat.Population(config, seed=3)
    best_front_seen = []

    def fitness(genomes, cfg):
        for _, g in genomes:
            # Two conflicting objectives of the network's weights.
            w = sum(c.weight for c in g.connections.values())
            g.objectives = (w, -abs(w - 1.0) - len(g.connections))
            g.fitness = g.objectives[0]

    for _ in range(6):
        population.run(fitness, 1)
        repro = population.reproduction
        assert len(population.population) == 20          # N offspring to evaluate next
        assert len(repro.parents) == 20                  # N parents kept with their objectives
        assert all(g.objectives is not None for g in repro.parents.values())
        front_keys = {k for k, _ in repro.front}
        front_species = {repro.species_of[k] for k in front_keys}
        if len(front_keys) < 20 and len(front_species) <= 10:  # bound = 0.5 * N
            assert front_keys <= set(repro.parents)      # no first-front genome lost
        # Offspring are new genomes: nothing is evaluated twice.
        assert not set(population.population) & set(repro.parents)
        best_front_seen.append(max(o[0] for _, o in repro.front))
    assert best_front_seen == sorted(best_front_seen)    # elitism: the best task never drops


def test_missing_objectives_is_an_error(tmp_path):
    config = make_config(tmp_path, pop=6)
    population = neat.Population(config, seed=1)

    def fitness(genomes, cfg):
        for _, g in genomes:
            g.fitness = 1.0

    with pytest.raises(RuntimeError, match="objectives"):
        population.run(fitness, 1)


def test_bad_parameter_named(tmp_path):
    path = tmp_path / "bad.cfg"
    path.write_text(NEAT_CFG.format(pop=6, threshold=1.0, progression="by_front").replace(
        "species_bound = 0.5", "species_bound = 1.5"))
    with pytest.raises(ValueError, match="species_bound"):
        neat.Config(BreedingGenome, MODSReproduction, neat.DefaultSpeciesSet, neat.DefaultStagnation, str(path))


def test_deterministic_for_a_seed(tmp_path):
    def run():
        random.seed(0)
        population = neat.Population(make_config(tmp_path, pop=12), seed=5)

        def fitness(genomes, cfg):
            for _, g in genomes:
                w = sum(c.weight for c in g.connections.values())
                g.objectives = (w, -len(g.connections))
                g.fitness = w

        population.run(fitness, 3)
        return sorted(population.population)

    assert run() == run()
