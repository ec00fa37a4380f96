"""Encog's species bookkeeping (evolution.reproduction.bookkeeping, protocol version 10): species
pointers, zombie species, speciation after scoring and Encog's generation 0, worked by hand
and against the membership books of versions 1-9 on the same data."""

from __future__ import annotations

from types import SimpleNamespace

import neat
import pytest

from evolution.reproduction.bookkeeping import first_best, inherit_pointer, levelled_order, pointer
from evolution.reproduction.species import GatheringSpeciesSet
from evolution.run.experiment import ExperimentError, load_experiment
from evolution.run.neat_setup import make_neat_config

ENCOG = {"speciation": "original", "elitism": "ratchet", "species_bookkeeping": "encog"}


def species_set(books="encog", threshold=1.0):
    """A species set of Encog's rule (max 40, min 2 species, step 0.01) with the given books."""
    config = make_neat_config(load_experiment(None, {"population": 6, **ENCOG, "species_bookkeeping": books}))
    species = GatheringSpeciesSet(config.species_set_config, neat.reporting.ReporterSet())
    species.threshold = threshold
    species.indexer = iter(range(100, 200))
    return config, species


def genome(key, w, fitness=0.0, pointer=None):
    """A genome of one link (innovation 1) of weight w: the original distance of two is 0.4 |dw|."""
    g = SimpleNamespace(key=key, fitness=fitness, species_pointer=pointer,
                        connections={(-1, 0): SimpleNamespace(key=(-1, 0), innovation=1, weight=w)})
    return g


def with_species(species, leaders):
    """Species ``sid -> leader genome``, in the order given (Encog's list order)."""
    for sid, leader in leaders.items():
        species.species[sid] = neat.species.Species(sid, 0)
        species.species[sid].update(leader, {leader.key: leader})
    species.history.append((0, species.threshold, len(leaders)))


def speciate(config, species, population, best):
    if species.deferred:
        species.speciate(config, population, 1)
        species.speciate_scored(config, 1, best)
    else:
        species.speciate(config, population, 1)
    return {sid: sorted(s.members) for sid, s in species.species.items()}


def test_a_joiner_takes_its_species_and_a_founder_keeps_the_pointer_it_had():
    config, species = species_set()
    with_species(species, {1: genome(1, 0.0, 50.0, pointer=7)})
    population = {1: species.species[1].representative, 10: genome(10, 1.0, 10.0, pointer=5),
                  11: genome(11, 9.0, 20.0, pointer=5)}
    members = speciate(config, species, population, population[1])
    # 10 is 0.4 from the leader: joins species 1 and points at it; 11 (3.6 away) founds 100,
    # and keeps pointing at 5; the leader keeps its own pointer
    assert members == {1: [1, 10], 100: [11]}
    assert [population[k].species_pointer for k in (1, 10, 11)] == [7, 1, 5]


def two_generations(books):
    """Generation t: species 1 and 2 lost their leaders; the new best genome 20 (a mutant of a
    member of species 1: it points at 1) is far from both and founds a species. Generation t+1:
    20 is carried, its children are near it."""
    config, species = species_set(books)
    dead1, dead2 = genome(1, 0.0, 40.0), genome(2, 5.0, 30.0)
    with_species(species, {1: dead1, 2: dead2})
    best = genome(20, 10.0, 90.0, pointer=1)
    population = {20: best, 21: genome(21, 0.5, 10.0), 22: genome(22, 10.5, 12.0)}
    first = speciate(config, species, population, best)
    threshold_t = species.history[-1][1]
    population = {20: best, 30: genome(30, 10.2, 11.0), 31: genome(31, 0.2, 9.0)}
    second = speciate(config, species, population, best)
    return first, threshold_t, second, species.history[-1][1], species


def test_the_best_genomes_pointer_keeps_a_species_whose_leader_died():
    first, threshold_t, second, threshold_t1, species = two_generations("encog")
    # t: species 1 survives its dead leader (20 points at it), species 2 is disbanded; one
    # survivor (< 2): the threshold falls to 0.99; 21 joins the zombie (0.2 from the dead
    # leader), 20 founds 100 and 22 joins it
    assert first == {1: [1, 21], 100: [20, 22]}
    assert threshold_t == pytest.approx(0.99)
    # t+1: the zombie (its leader 1 still dead, still pointed at) and 20's species survive:
    # two species, so the threshold holds still; 31 joins the zombie, whose leader (40) it
    # does not beat, and the dead leader stays a member that breeds
    assert second == {1: [1, 31], 100: [20, 30]}
    assert threshold_t1 == pytest.approx(0.99)
    assert species.species[1].representative.key == 1


def test_with_the_membership_books_the_same_species_is_disbanded_and_the_threshold_falls():
    first, threshold_t, second, threshold_t1, _ = two_generations("membership")
    assert 1 not in first and 2 not in first
    assert threshold_t1 == pytest.approx(threshold_t - 0.01)


def test_a_joiner_that_beats_the_leader_leads_for_the_rest_of_the_pass():
    config, species = species_set()
    leader = genome(1, 0.0, 10.0)
    with_species(species, {1: leader})
    # 10 (0.8 from the leader, fitness 20) joins and leads; 11 is 1.6 from the old leader but
    # 0.8 from 10: it joins too. Compared with the old leader only, 11 would found a species.
    population = {1: leader, 10: genome(10, 2.0, 20.0), 11: genome(11, 4.0, 5.0)}
    assert speciate(config, species, population, leader) == {1: [1, 10, 11]}
    assert species.species[1].representative.key == 10
    config, species = species_set()
    with_species(species, {1: leader})
    population[10].fitness = 10.0  # a tie: the leader keeps its place, and 11 founds a species
    assert speciate(config, species, population, leader) == {1: [1, 10], 100: [11]}


def test_a_genome_joins_the_first_species_in_encogs_order_not_the_oldest():
    config, species = species_set()
    a, b = genome(1, 0.0, 10.0), genome(2, 1.0, 50.0)
    with_species(species, {sid: s.representative for sid, s in levelled_order({1: _species(1, a),
                                                                               2: _species(2, b)}).items()})
    assert list(species.species) == [2, 1]  # levelled: the better leader first
    population = {1: a, 2: b, 10: genome(10, 0.5, 1.0)}  # 0.2 from both leaders
    assert speciate(config, species, population, b) == {2: [2, 10], 1: [1]}


def _species(sid, leader):
    s = neat.species.Species(sid, 0)
    s.update(leader, {leader.key: leader})
    return s


def test_levelled_order_sorts_by_leader_score_and_keeps_ties_in_place():
    leaders = {5: genome(1, 0, 3.0), 3: genome(2, 0, 7.0), 9: genome(3, 0, 3.0), 4: genome(4, 0, 1.0)}
    order = levelled_order({sid: _species(sid, g) for sid, g in leaders.items()})
    assert list(order) == [3, 5, 9, 4]


def test_first_best_is_the_first_finite_score_whatever_the_others_scored():
    population = {3: genome(3, 0, float("nan")), 7: genome(7, 0, 1.0), 5: genome(5, 0, float("-inf")),
                  9: genome(9, 0, 99.0)}
    assert first_best(population).key == 7
    assert first_best({1: genome(1, 0, float("nan")), 2: genome(2, 0, float("nan"))}).key == 2


def test_a_mutant_inherits_its_parents_pointer_and_a_crossover_child_has_none():
    child = SimpleNamespace()
    inherit_pointer(child, (genome(1, 0, pointer=4),))
    assert child.species_pointer == 4
    inherit_pointer(child, (genome(1, 0, pointer=4), genome(2, 0, pointer=4)))
    assert child.species_pointer is None


def real_population(books, size=30):
    exp = load_experiment(None, {"population": size, "method": "hyperneat-m", **ENCOG, "species_bookkeeping": books,
                                 "weights": "encog", "truncation": "encog"})
    return neat.Population(make_neat_config(exp), seed=4)


def score_all(population, fitness):
    for key, g in population.population.items():
        g.fitness = fitness(key)


def test_generation_0_is_speciated_after_scoring_at_0_99_and_the_ratchet_starts_from_its_first_genome():
    population = real_population("encog")
    first = min(population.population)
    assert population.species.pending is population.population and not population.species.species
    fittest = max(population.population)
    score_all(population, lambda k: 100.0 if k == fittest else 10.0 + (k % 5))
    reproduction, species = population.reproduction, population.species
    new = reproduction.reproduce(population.config, species, 30, 0)
    generation, threshold, count = species.history[0]
    assert (generation, threshold) == (0, pytest.approx(0.99))
    assert count >= 27  # random weights in +-5: nearly every genome is beyond 0.99 of every leader
    assert reproduction.best.key == first and first in new and fittest not in new
    # nearly every species is one genome: its offspring are its mutants, in proportion to its score
    # species of fewer than 7 breed from their best alone (Encog's truncation): all mutants
    parents = [reproduction.ancestors[k] for k in new if k != first]
    assert all(len(p) == 1 for p in parents)
    assert sum(1 for p in parents if p == (fittest,)) >= 5


def test_with_the_membership_books_generation_0_is_one_species_and_its_fittest_is_carried():
    population = real_population("membership")
    fittest = max(population.population)
    assert len(population.species.species) == 1
    score_all(population, lambda k: 100.0 if k == fittest else 10.0 + (k % 5))
    new = population.reproduction.reproduce(population.config, population.species, 30, 0)
    assert population.reproduction.best.key == fittest and fittest in new


def test_children_carry_their_pointers_through_a_real_reproduction():
    population = real_population("encog")
    score_all(population, lambda k: float(k % 7))
    reproduction, species, config = population.reproduction, population.species, population.config
    generation_1 = reproduction.reproduce(config, species, 30, 0)
    species.speciate(config, generation_1, 0)
    score_all(SimpleNamespace(population=generation_1), lambda k: float(k % 3))
    generation_2 = reproduction.reproduce(config, species, 30, 1)  # speciates generation 1 first
    assert species.history[-1][0] == 1 and species.pending is None
    # mutants of one parent are near each other: some of generation 1 joined a species
    assert sum(pointer(g) is not None for g in generation_1.values()) >= 5
    kinds = []
    for key, child in generation_2.items():
        if key in reproduction.carried:
            continue
        parents = reproduction.ancestors[key]
        want = pointer(generation_1[parents[0]]) if len(parents) == 1 else None
        assert pointer(child) == want
        kinds.append("crossover" if len(parents) == 2 else "inherited" if want is not None else "none")
    assert len(kinds) == 29 and {"inherited", "none"} <= set(kinds), kinds  # (crossover: by hand above)


@pytest.mark.parametrize("keys", [{"speciation": "adaptive"}, {"elitism": "species"}])
def test_encog_books_without_encogs_species_of_leaders_are_refused(keys):
    with pytest.raises(ExperimentError, match=r"species_bookkeeping = 'encog'.*allowed: with speciation = "
                                              r"'original' and elitism = 'ratchet'"):
        load_experiment(None, {**ENCOG, **keys})
    with pytest.raises(ExperimentError, match=r"species_bookkeeping='pointers'; allowed: \['membership', 'encog'\]"):
        load_experiment(None, {**ENCOG, "species_bookkeeping": "pointers"})


@pytest.mark.parametrize("stagnant", [False, True])
def test_the_species_the_best_genome_points_at_breeds_from_its_dead_leader(stagnant):
    """Species 1 lost its leader D (score 2) but the best genome B (54) points at it; B and C (34)
    found species of their own. Shares of 9 places: 54/90 * 9 = 5.4 -> 5, 34/90 * 9 = 3.4 -> 3,
    2/90 * 9 = 0.2 -> 0, but the best species gets at least 1: one mutant of the dead leader
    (also when the zombie has not improved for 100 generations: stagnation spares it), with the
    pointer D had."""
    population = real_population("encog", size=10)
    reproduction, species, config = population.reproduction, population.species, population.config
    d, b, c = (population.population[k] for k in sorted(population.population)[:3])
    d.fitness, b.fitness, c.fitness = 2.0, 54.0, 34.0
    sid = next(species.indexer)
    zombie = _species(sid, d)
    if stagnant:
        zombie.fitness_history, zombie.last_improved = [1000.0], -100
    species.species = {sid: zombie}
    species.history.append((4, 1.0, 1))
    b.species_pointer, d.species_pointer = sid, 7
    reproduction.best = b
    species.pending = {b.key: b, c.key: c}
    new = reproduction.reproduce(config, species, 10, 5)
    assert species.history[-1][2] == 3  # the zombie, B's and C's species
    parents = [reproduction.ancestors[k] for k in new if k != b.key]
    assert sorted(p[0] for p in parents) == sorted([d.key] + [b.key] * 5 + [c.key] * 3)
    assert all(pointer(new[k]) == 7 for k in new if reproduction.ancestors.get(k) == (d.key,))  # D's own


def test_encog_never_removes_its_last_species_even_when_it_stagnates():
    population = real_population("encog", size=10)
    reproduction, species, config = population.reproduction, population.species, population.config
    b = population.population[min(population.population)]
    b.fitness = 5.0
    sid = next(species.indexer)
    only = _species(sid, b)
    only.fitness_history, only.last_improved = [1000.0], -100  # stagnant for 105 generations
    species.species = {sid: only}
    species.history.append((4, 1.0, 1))
    reproduction.best = b  # pointing at no species
    species.pending = {b.key: b}
    new = reproduction.reproduce(config, species, 10, 5)
    assert len(new) == 10 and all(reproduction.ancestors[k] == (b.key,) for k in new if k != b.key)


def test_a_runs_statistics_give_the_species_and_threshold_of_each_scored_generation(tmp_path):
    """The record of generation g under Encog's books holds the speciation of g itself, made
    after g was scored: generation 0 nearly a species per genome at 0.99, then one step of 0.01
    (or none) a generation; with the membership books generation 0 is one species at 1.0."""
    from evolution.cli import evolve_main
    from evolution.run.stats import read_stats
    from tests.test_protocol import experiment

    for books, version in (("encog", 10), ("membership", 9)):
        exp = experiment(tmp_path, name=books, generations=3, population=10,
                         body=f'protocol = "original"\nprotocol_version = {version}')
        assert evolve_main([str(exp), "--out", str(tmp_path / books), "--workers", "1", "--no-progress"]) == 0
        rows = read_stats(tmp_path / books / "stats.jsonl")
        if books == "encog":
            assert rows[0]["threshold"] == pytest.approx(0.99) and rows[0]["species"] >= 9
            steps = [round(a["threshold"] - b["threshold"], 6) for a, b in zip(rows, rows[1:])]
            assert all(step in (0.0, 0.01) for step in steps), steps
        else:
            assert (rows[0]["threshold"], rows[0]["species"]) == (1.0, 1)
