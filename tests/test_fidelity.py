"""Method fidelity: shipped defaults vs docs/model.md, shared breeding, NEAT-MODS details,
signed CPPN outputs, NEAT-M operators and speciation; each against hand values."""

from __future__ import annotations

import math
import random
import tomllib
from collections import Counter
from pathlib import Path
from types import SimpleNamespace

import neat
import numpy as np
import pytest

from evolution.encodings.direct import NEATMGenome, SensorGene, decode_neat_m
from evolution.encodings.genome import CPPNGenome
from evolution.encodings.substrate import Substrate, decode
from evolution.reproduction.breeding import NEATReproduction, breed, truncate
from evolution.reproduction.mods import MODSReproduction
from evolution.reproduction.operators import BreedingGenome
from evolution.reproduction.species import GatheringSpeciesSet
from gathering_env import SENSOR_TYPES

CONFIGS = Path(__file__).resolve().parent.parent / "configs"

# docs/model.md §5, copied by hand: the original's probabilities of the one operator per offspring.
SPEC_OPERATORS = {
    CPPNGenome: {"crossover": 0.5, "weights": 0.494, "add_node": 0.0005, "add_link": 0.005, "remove_link": 0.0005},
    NEATMGenome: {"crossover": 0.32, "weights": 0.335, "add_node": 0.05, "add_link": 0.05, "remove_link": 0.005,
                  "sensor_angles": 0.1, "sensor_reach": 0.07, "add_sensor": 0.07},
}
CFG_FILES = {CPPNGenome: "hyperneat_m.neat.cfg", NEATMGenome: "neat_m.neat.cfg"}


def load(genome_type, reproduction=NEATReproduction, path=None):
    return neat.Config(genome_type, reproduction, GatheringSpeciesSet, neat.DefaultStagnation,
                       str(path or CONFIGS / CFG_FILES[genome_type]))


# ---------------------------------------------------------------- shipped defaults
@pytest.mark.parametrize("genome_type", [CPPNGenome, NEATMGenome])
def test_shipped_breeding_rates_are_the_originals(genome_type):
    for reproduction in (NEATReproduction, MODSReproduction):  # both arms read one section
        gc = load(genome_type, reproduction).genome_config
        ops = {name: p for name, p in genome_type.operators(gc) if p > 0}
        assert ops == SPEC_OPERATORS[genome_type]
        assert gc.variation == "one_operator" and gc.parent_fraction == 0.3
    mo = load(genome_type, MODSReproduction).reproduction_config
    assert mo.progression == "round_robin" and mo.species_bound == "per_objective"


def test_shipped_cppn_outputs_signed_and_bottom_on_node0():
    gc = load(CPPNGenome).genome_config
    assert gc.output_activations == dict.fromkeys(range(6), "clamped")
    assert Substrate().bottom_on_node0 and not Substrate().bias_threshold
    for name in ("S1", "S2", "S3", "M1", "M2", "M3"):
        doc = tomllib.loads((CONFIGS / f"{name}.toml").read_text())
        assert doc["substrate"]["bottom_on_node0"] is True
        assert doc["experiment"]["convergence_stop"] is (name[0] == "S")   # MO never stops early


def test_shipped_neat_m_sensor_defaults():
    gc = load(NEATMGenome).genome_config
    assert gc.sensor_remove_prob == 0.0                        # not in the original
    # the original's sensor operators, read from the shipped section (not class defaults)
    assert (gc.sensor_add_prob, gc.sensor_angle_mutate_prob, gc.sensor_reach_mutate_prob) == (0.07, 0.1, 0.07)
    assert gc.sensor_types == ["infrared", "ultrasonic", "colour", "camera", "bottom"]


# ---------------------------------------------------------------- shared breeding
BREED_CFG = """
[NEAT]
fitness_criterion = max
fitness_threshold = 1e9
pop_size = 10
reset_on_extinction = False
no_fitness_termination = True

[BreedingGenome]
variation = one_operator
parent_fraction = 0.3
crossover_prob = {crossover}
weight_mutate_prob = {weights}
weight_reset_prob = 0.0
num_inputs = 4
num_outputs = 6
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
bias_mutate_rate = 0.0
bias_replace_rate = 0.0
compatibility_disjoint_coefficient = 1.0
compatibility_weight_coefficient = 0.5
conn_add_prob = {add_link}
conn_delete_prob = 0.0
enabled_default = True
enabled_mutate_rate = 0.0
node_add_prob = {add_node}
node_delete_prob = 0.0
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
weight_mutate_rate = 0.0
weight_replace_rate = 0.0

[GatheringSpeciesSet]
compatibility_threshold = 3.0

[DefaultStagnation]
species_fitness_func = max
max_stagnation = 15
species_elitism = 0

[NEATReproduction]
elitism = 0
min_species_size = 1
"""


def breed_config(tmp_path, crossover=0.5, weights=0.3, add_node=0.1, add_link=0.1):
    path = tmp_path / "breed.cfg"
    path.write_text(BREED_CFG.format(crossover=crossover, weights=weights, add_node=add_node, add_link=add_link))
    config = load(BreedingGenome, path=path)
    config.genome_config.innovation_tracker = neat.innovation.InnovationTracker()
    return config


def parents(config, n):
    genomes = {}
    for k in range(1, n + 1):
        g = BreedingGenome(k)
        g.configure_new(config.genome_config)
        genomes[k] = g
    return genomes


def test_one_operator_per_offspring_in_proportion(tmp_path, monkeypatch):
    config = breed_config(tmp_path, crossover=0.5, weights=0.3, add_node=0.1, add_link=0.1)
    genomes = parents(config, 4)
    seen = Counter()
    original = BreedingGenome.apply_operator
    monkeypatch.setattr(BreedingGenome, "apply_operator",
                        lambda self, name, cfg: (seen.update([name]), original(self, name, cfg)))
    random.seed(1)
    ancestors = {}
    keys = iter(range(100, 10**6))
    n = 4000
    children = breed([1, 2, 3, 4], genomes, {k: float(-k) for k in genomes}, n, config, lambda: next(keys), ancestors)
    seen["crossover"] = sum(len(a) == 2 for a in ancestors.values())
    assert sum(seen.values()) == n                            # exactly one operator per child
    for name, p in {"crossover": 0.5, "weights": 0.3, "add_node": 0.1, "add_link": 0.1}.items():
        assert abs(seen[name] - n * p) < 4 * math.sqrt(n * p * (1 - p)), (name, seen)
    for key, child in children.items():                       # a mutated copy changes one thing
        if len(ancestors[key]) == 1:
            parent = genomes[ancestors[key][0]]
            extra_nodes = len(child.nodes) - len(parent.nodes)
            extra_links = len(child.connections) - len(parent.connections)
            assert (extra_nodes, extra_links) in {(0, 0), (1, 2), (0, 1)}


def test_truncation_keeps_the_best_30_percent(tmp_path):
    assert truncate(list(range(10)), 0.3) == [0, 1, 2]
    assert truncate(list(range(4)), 0.3) == [0, 1]             # ceil(1.2) = 2
    assert truncate([7], 0.3) == [7]
    config = breed_config(tmp_path)
    genomes = parents(config, 10)
    score = {k: float(100 - k) for k in genomes}                # 1 is best
    ancestors = {}
    keys = iter(range(100, 10**6))
    breed(sorted(genomes, key=lambda k: -score[k]), genomes, score, 300, config, lambda: next(keys), ancestors)
    used = {p for a in ancestors.values() for p in a}
    assert used == {1, 2, 3}


@pytest.mark.parametrize("n, neat_keep, encog_keep", [
    (1, 1, 1), (3, 2, 1), (4, 2, 1), (6, 2, 1), (7, 3, 2), (10, 3, 3), (11, 4, 3), (20, 6, 6), (40, 12, 12)])
def test_encog_truncation_floors_where_neat_python_rounds_up(n, neat_keep, encog_keep):
    # by hand: neat-python max(ceil(0.3 n), 2), Encog's TruncationSelection max(floor(0.3 n), 1)
    assert len(truncate(list(range(n)), 0.3)) == min(neat_keep, n)
    assert truncate(list(range(n)), 0.3, "encog") == list(range(encog_keep))


def breed_counts(config, genomes, n, seed=4):
    """(children that crossed over, parents used) of ``n`` offspring of ``genomes`` (1 is best)."""
    random.seed(seed)
    ancestors = {}
    keys = iter(range(100, 10**6))
    score = {k: float(100 - k) for k in genomes}
    breed(sorted(genomes, key=lambda k: -score[k]), genomes, score, n, config, lambda: next(keys), ancestors)
    return sum(len(a) == 2 for a in ancestors.values()), {p for a in ancestors.values() for p in a}


def test_under_encog_truncation_a_small_species_breeds_from_its_best_alone(tmp_path, monkeypatch):
    config = breed_config(tmp_path)
    genomes = parents(config, 6)                               # 0.3 * 6 = 1.8: Encog keeps 1, neat-python 2
    crossed, used = breed_counts(config, genomes, 400)
    assert used == {1, 2} and 150 < crossed < 250              # crossover 0.5 between the best two
    config.genome_config.truncation = "encog"
    mutated = Counter()
    original = BreedingGenome.apply_operator
    monkeypatch.setattr(BreedingGenome, "apply_operator",
                        lambda self, name, cfg: (mutated.update([name]), original(self, name, cfg)))
    crossed, used = breed_counts(config, genomes, 400)
    assert used == {1} and crossed == 0                        # copies of the best, no crossover ...
    assert sum(mutated.values()) == 400 and "crossover" not in mutated   # ... each changed by one mutation


def test_an_encog_crossover_that_draws_one_parent_twice_draws_another_operator(tmp_path, monkeypatch):
    """Encog draws the second parent up to 6 times; if each repeats the first there is no
    child and another operator is drawn. With one draw and 2 parents that fails half the
    time, so crossover's share falls from 0.5 to 0.25 / (0.25 + 0.5) = 1/3 (by hand)."""
    import evolution.reproduction.breeding as breeding

    config = breed_config(tmp_path)
    config.genome_config.truncation = "encog"
    genomes = parents(config, 7)                               # 0.3 * 7 = 2.1: 2 parents
    n = 3000
    crossed, used = breed_counts(config, genomes, n)
    assert used == {1, 2} and abs(crossed - n * 63 / 127) < 4 * math.sqrt(n / 4)   # 6 draws: 63/127
    monkeypatch.setattr(breeding, "ENCOG_PARENT_DRAWS", 1)
    crossed, _ = breed_counts(config, genomes, n)
    assert abs(crossed - n / 3) < 4 * math.sqrt(n * 2 / 9)


def test_the_experiment_sets_the_truncation_both_arms_breed_with(tmp_path):
    from evolution.run.experiment import load_experiment
    from evolution.run.neat_setup import make_neat_config

    for body, objectives, rule in (("", '["task"]', "neat"), ('protocol = "original"', '["task"]', "encog"),
                                   ('truncation = "encog"', '["task", "morphology"]', "encog"),
                                   ('protocol = "original"\nprotocol_version = 3', '["task"]', "neat")):
        path = tmp_path / "e.toml"
        path.write_text(f"[experiment]\nobjectives = {objectives}\npopulation = 10\n{body}\n")
        assert make_neat_config(load_experiment(path)).genome_config.truncation == rule, body


@pytest.mark.parametrize("method, sigmas", [("hyperneat-m", (0.02, 1.0)), ("neat-m", (0.004, 0.2))])
def test_the_original_protocol_sets_encog_weights_for_either_method(tmp_path, method, sigmas):
    from evolution.run.experiment import load_experiment
    from evolution.run.neat_setup import make_neat_config

    path = tmp_path / "e.toml"
    for body, encog in (("", False), ('protocol = "original"', True), ('weights = "encog"', True),
                        ('protocol = "original"\nprotocol_version = 3', False)):
        path.write_text(f'[experiment]\nmethod = "{method}"\npopulation = 10\n{body}\n')
        gcfg = make_neat_config(load_experiment(path)).genome_config
        assert getattr(gcfg, "encog_sigmas", None) == (sigmas if encog else None), body
        assert (gcfg.weight_max_value, gcfg.bias_min_value, gcfg.weight_init_type) == \
            ((5.0, -5.0, "uniform") if encog else (3.0, -3.0, "gaussian")), body


def test_the_original_weights_are_uniform_in_plus_minus_5(tmp_path):
    """Encog's initial weights: uniform in [-5, 5] (standard deviation 10 / sqrt(12) = 2.887 by
    hand), where the shipped config draws N(0, 1) clamped to +-3."""
    from evolution.reproduction.encog import use_encog_weights

    config = load(CPPNGenome)
    config.genome_config.innovation_tracker = neat.innovation.InnovationTracker()
    before = [w for g in parents(config, 40).values() for w in [c.weight for c in g.connections.values()]]
    use_encog_weights(config.genome_config, "hyperneat-m")
    genomes = parents(config, 40)
    weights = [c.weight for g in genomes.values() for c in g.connections.values()]
    biases = [n.bias for g in genomes.values() for n in g.nodes.values()]
    assert max(map(abs, before)) <= 3.0 and abs(np.std(before) - 1.0) < 0.15
    for values in (weights, biases):
        assert max(map(abs, values)) <= 5.0 and abs(np.std(values) - 10 / math.sqrt(12)) < 0.35
        assert min(values) < -4.5 and max(values) > 4.5


def weight_changes(genome, config, operations=3000, seed=2):
    """The weight changes (|delta| of every link changed) of each of ``operations`` weight operations."""
    random.seed(seed)
    genome.fitness = 0.0
    out = []
    for _ in range(operations):
        child = BreedingGenome(2)
        child.configure_crossover(genome, genome, config.genome_config)
        child.apply_operator("weights", config.genome_config)
        delta = [abs(child.connections[k].weight - g.weight) for k, g in genome.connections.items()]
        delta += [abs(child.nodes[k].bias - g.bias) for k, g in genome.nodes.items()]
        out.append([d for d in delta if d > 0])
    return out


def test_the_original_weight_operation_perturbs_by_0_02_or_1(tmp_path):
    """Encog's weight operation: 45 % of operations perturb by N(0, 0.02), 45 % by N(0, 1), 10 %
    reset. So about half of them change no weight by 0.08 (4 sigma of the small one) or more;
    with the shipped N(0, 0.5) about 13 % of single changes are that small."""
    from evolution.reproduction.encog import use_encog_weights

    config = breed_config(tmp_path)
    genome = parents(config, 1)[1]
    small = lambda changes: sum(max(c) < 0.08 for c in changes if c) / len(changes)  # noqa: E731
    assert small(weight_changes(genome, config)) < 0.15
    use_encog_weights(config.genome_config, "hyperneat-m")
    genome = parents(config, 1)[1]
    changes = weight_changes(genome, config)
    assert 0.41 < small(changes) < 0.52
    assert all(c for c in changes)                              # every operation changes a link


def test_the_original_proportion_pick_draws_each_link_with_probability_0_02(tmp_path, monkeypatch):
    """Encog's SelectProportion(0.02): each link with probability 0.02, one at random if none:
    on 400 links the count varies (binomial, mean 8, variance 7.84); the shipped rule changes
    round(0.02 * 400) = 8 every time."""
    import evolution.reproduction.operators as operators
    from evolution.reproduction.encog import use_encog_weights

    path = tmp_path / "big.cfg"
    path.write_text(BREED_CFG.format(crossover=0.5, weights=0.3, add_node=0.1, add_link=0.1)
                    .replace("num_inputs = 4", "num_inputs = 100"))
    config = load(BreedingGenome, path=path)
    config.genome_config.innovation_tracker = neat.innovation.InnovationTracker()
    genome = parents(config, 1)[1]
    links = len(genome.connections) + len(genome.nodes)
    use_encog_weights(config.genome_config, "hyperneat-m")
    monkeypatch.setattr(operators, "ENCOG_WEIGHT_OPERATIONS", ((0.02, 1, 1.0),))
    counts = [len(c) for c in weight_changes(genome, config, 600)]
    p = 0.02
    assert abs(np.mean(counts) - links * p) < 0.5 and abs(np.var(counts) - links * p * (1 - p)) < 2.0


def test_weight_operator_changes_one_to_three_links(tmp_path):
    config = breed_config(tmp_path)
    genome = parents(config, 1)[1]
    genome.fitness = 0.0
    random.seed(3)
    counts = Counter()
    for _ in range(300):
        child = BreedingGenome(2)
        child.configure_crossover(genome, genome, config.genome_config)
        child.apply_operator("weights", config.genome_config)
        changed = sum(child.connections[k].weight != g.weight for k, g in genome.connections.items())
        changed += sum(child.nodes[k].bias != g.bias for k, g in genome.nodes.items())
        counts[changed] += 1
        assert set(child.connections) == set(genome.connections)
    # 24 links + 6 biases: 1, 2 or 3 links, or 2 % of 30 -> 1; each choice a quarter
    assert set(counts) == {1, 2, 3}
    assert counts[1] > counts[2] and counts[1] > counts[3]


def test_crossover_takes_disjoint_genes_from_the_better_score_not_fitness(tmp_path):
    config = breed_config(tmp_path, crossover=1.0, weights=0.0, add_node=0.0, add_link=0.0)
    genomes = parents(config, 2)
    a, b = genomes[1], genomes[2]
    dropped = sorted(b.connections)[:5]
    for key in dropped:                                       # a holds 5 genes b lacks
        del b.connections[key]
    a.fitness, b.fitness = 1.0, 50.0                          # b has the higher task score ...
    for better, expect in ((1, True), (2, False)):            # ... but the rank score decides
        score = {1: 10.0, 2: 5.0} if better == 1 else {1: 5.0, 2: 10.0}
        keys = iter(range(100, 200))
        new_key = keys.__next__
        for child in breed([1, 2], genomes, score, 20, config, new_key, {}).values():
            assert all((k in child.connections) is expect for k in dropped)


def test_so_arm_breeds_through_neat_population(tmp_path):
    config = breed_config(tmp_path)
    population = neat.Population(config, seed=2)

    def fitness(genomes, cfg):
        for _, g in genomes:
            g.fitness = sum(c.weight for c in g.connections.values())

    population.run(fitness, 3)
    assert len(population.population) == 10
    assert isinstance(population.reproduction, neat.DefaultReproduction)


def test_survival_threshold_moved_to_the_genome_section(tmp_path):
    path = tmp_path / "old.cfg"
    path.write_text(BREED_CFG.format(crossover=0.5, weights=0.5, add_node=0, add_link=0).replace(
        "min_species_size = 1", "min_species_size = 1\nsurvival_threshold = 0.2"))
    with pytest.raises(ValueError, match="parent_fraction"):
        load(BreedingGenome, path=path)


# ---------------------------------------------------------------- NEAT-MODS
def mods(bound="per_objective", progression="round_robin"):
    return MODSReproduction(SimpleNamespace(species_bound=bound, progression=progression), None, None)


def g(key, *objectives):
    return SimpleNamespace(key=key, objectives=tuple(objectives), fitness=objectives[0])


def test_round_robin_is_the_published_scan():
    assert MODSReproduction.parse_config({}).progression == "round_robin"
    # species a = {1, 2, 3}, b = {4, 5, 6}. First front {1, 2, 3, 4}: 1 and 4 are extremes
    # (infinite crowding); crowding of 2 = (10-8)/10 + (3-1)/9 = 0.42, of 3 = (9-1)/10 + (10-2)/9
    # = 1.69, so the sort is 1, 4, 3, 2 | 5 | 6. Rows of the scan: (1, 4), (3, 5).
    pool = {1: g(1, 10, 1), 2: g(2, 9, 2), 3: g(3, 8, 3), 4: g(4, 1, 10), 5: g(5, 0, 9), 6: g(6, 0, 8)}
    species_of = {1: "a", 2: "a", 3: "a", 4: "b", 5: "b", 6: "b"}
    parents_, _, _ = mods().select(pool, species_of, 4)
    assert parents_ == [1, 4, 3, 5]


def test_species_bound_is_n_over_objectives():
    # 14 genomes in 4 species of 4, 4, 3, 3 (species = key % 4); N = 7. Any two species hold
    # >= 6 ... the first two in sort order (0 and 1) hold 8 >= 7, so the bound alone decides.
    species_of = {k: k % 4 for k in range(14)}
    three = {k: g(k, 14 - k, 0, 0) for k in range(14)}           # sort order = key order
    _, _, selected = mods().select(three, species_of, 7)
    assert selected == [0, 1]                                    # floor(7 / 3) = 2 species
    two = {k: g(k, 14 - k, 0) for k in range(14)}
    _, _, selected = mods().select(two, species_of, 7)
    assert selected == [0, 1, 2]                                 # floor(7 / 2) = 3 species
    _, _, selected = mods(bound="0.3").select(two, species_of, 7)
    assert selected == [0, 1]                                    # floor(0.3 * 7) = 2


def test_mods_rejects_removed_keys():
    with pytest.raises(ValueError, match="tournament_size"):
        MODSReproduction.parse_config({"tournament_size": "2"})
    with pytest.raises(ValueError, match="species_bound"):
        MODSReproduction.parse_config({"species_bound": "half"})


# ---------------------------------------------------------------- CPPN output activations
def test_cppn_outputs_pinned_hidden_nodes_free():
    config = load(CPPNGenome)
    gc = config.genome_config
    gc.innovation_tracker = neat.innovation.InnovationTracker()
    gc.activation_mutate_rate = 1.0
    random.seed(5)
    hidden = set()
    for key in range(30):
        genome = CPPNGenome(key)
        genome.configure_new(gc)
        assert {genome.nodes[k].activation for k in gc.output_keys} == {"clamped"}
        for _ in range(5):
            genome.mutate_add_node(gc)
            genome.mutate(gc)
        assert {genome.nodes[k].activation for k in gc.output_keys} == {"clamped"}
        hidden |= {n.activation for k, n in genome.nodes.items() if k not in gc.output_keys}
    assert len(hidden) >= 4                                    # hidden nodes keep the CPPN set


def test_signed_outputs_reach_every_type_and_negative_links():
    config = load(CPPNGenome)
    population = neat.Population(config, seed=7)
    types, negative, links = Counter(), 0, 0
    for genome in list(population.population.values())[:100]:
        controller, morphology = decode(genome, config)
        types.update(s.type for s in morphology)
        w = controller.layers[0].weights
        negative += int((w < 0).sum())
        links += int((w != 0).sum())
    assert {"infrared", "ultrasonic", "colour", "camera"} <= set(types)
    assert negative / links > 0.35                             # unsigned outputs gave ~29 %


@pytest.mark.parametrize("value, ok", [("clamped", True), ("tanh sin clamped identity tanh clamped", True),
                                       ("random", True), ("sigmoid", False), ("clamped relu clamped clamped "
                                                                             "clamped clamped", False),
                                       ("clamped tanh", False), ("nosuch", False)])
def test_output_activation_option(tmp_path, value, ok):
    text = (CONFIGS / "hyperneat_m.neat.cfg").read_text().replace(
        "output_activation       = clamped", f"output_activation       = {value}")
    path = tmp_path / "cppn.cfg"
    path.write_text(text)
    if ok:
        load(CPPNGenome, path=path)
    else:
        with pytest.raises(ValueError, match="output_activation"):
            load(CPPNGenome, path=path)


def test_bias_threshold_option():
    config = load(CPPNGenome)
    genome = next(iter(neat.Population(config, seed=9).population.values()))
    net = neat.nn.FeedForwardNetwork.create(genome, config)
    sub = Substrate()
    raw = [float(np.clip(net.activate([0.0, 0.0, x, y])[5], -1, 1)) for x, y in sub.outputs]

    def by_hand(q):  # the link rule: 0 within 0.2, else sign * (|q| - 0.2) * 5 / 0.8
        return 0.0 if abs(q) <= 0.2 else math.copysign((abs(q) - 0.2) * 5.0 / 0.8, q)

    plain, _ = decode(genome, config, sub)
    thresholded, _ = decode(genome, config, Substrate(bias_threshold=True))
    np.testing.assert_allclose(plain.layers[0].bias, [5.0 * q for q in raw])
    np.testing.assert_allclose(thresholded.layers[0].bias, [by_hand(q) for q in raw])


# ---------------------------------------------------------------- NEAT-M
def neat_m():
    config = load(NEATMGenome)
    config.genome_config.innovation_tracker = neat.innovation.InnovationTracker()
    return config


def copy_network(source, key):
    other = NEATMGenome(key)
    other.nodes = {k: n.copy() for k, n in source.nodes.items()}
    other.connections = {k: c.copy() for k, c in source.connections.items()}
    return other


def test_entirely_different_sensors_cost_the_whole_sensor_coefficient():
    config = neat_m()
    gc = config.genome_config
    a = NEATMGenome(1)
    a.configure_new(gc)
    a.sensors = {s: SensorGene("infrared", 0.5 * s, 0.0, 5.0, 1.0) for s in (0, 1, 2)}
    b = copy_network(a, 2)
    b.sensors = {s: SensorGene("camera", 0.5 * s, 0.0, 5.0, 1.0) for s in (0, 1, 2)}
    assert a.distance(b, gc) == pytest.approx(gc.sensor_compatibility_coefficient)   # mean difference 1
    assert a.sensor_distance(b, gc) == pytest.approx(gc.sensor_compatibility_coefficient)
    same = copy_network(a, 3)
    same.sensors = {slot: gene for slot, gene in a.sensors.items()}
    assert a.distance(same, gc) == 0.0


def test_sensor_distance_by_hand():
    config = neat_m()
    gc = config.genome_config
    a = NEATMGenome(1)
    a.configure_new(gc)
    b = copy_network(a, 2)
    a.sensors = {3: SensorGene("infrared", 0.0, 0.0, 5.0, 1.0)}
    b.sensors = {3: SensorGene("infrared", math.pi / 2, 0.5, 7.0, 1.5), 4: SensorGene("bottom", 0, 0, 0, 0)}
    ir = SENSOR_TYPES["infrared"]
    gene = (0.5 + 0.5 / math.pi + 2.0 / ir.range_max + 0.5 / (ir.fov_max - ir.fov_min)) / 4.0
    expected = gc.sensor_compatibility_coefficient * (gene + 1.0) / 2.0               # slot 4 missing in a
    assert a.distance(b, gc) == pytest.approx(expected)


def test_angle_operator_touches_bearing_and_orientation_of_one_to_four_sensors():
    config = neat_m()
    gc = config.genome_config
    random.seed(11)
    touched = Counter()
    for key in range(200):
        genome = NEATMGenome(key)
        genome.configure_new(gc)
        genome.sensors = {s: SensorGene("ultrasonic", 0.1 * s, 0.0, 10.0, 1.0) for s in range(6)}
        genome.sensors[6] = SensorGene("bottom", 0.0, 0.0, 0.0, 0.0)
        before = {s: g.to_dict() for s, g in genome.sensors.items()}
        genome.apply_operator("sensor_angles", gc)
        moved = [s for s, g in genome.sensors.items() if g.to_dict() != before[s]]
        touched[len(moved)] += 1
        assert 6 not in moved                                  # never the bottom sensor
        for s in moved:
            after = genome.sensors[s].to_dict()
            assert {k for k in after if after[k] != before[s][k]} <= {"bearing", "orientation"}
    assert set(touched) == {1, 2, 3, 4}


def test_reach_operator_shifts_one_type_by_the_same_amount():
    config = neat_m()
    gc = config.genome_config
    gc.sensor_reach_mutate_power = 0.01                          # small: no clamping
    random.seed(12)
    genome = NEATMGenome(1)
    genome.configure_new(gc)
    genome.sensors = {0: SensorGene("ultrasonic", 0.0, 0.0, 10.0, 1.0), 1: SensorGene("ultrasonic", 1.0, 0.2, 12.0, 1.5),
                      2: SensorGene("infrared", 2.0, 0.0, 5.0, 1.0)}
    before = {s: g.to_dict() for s, g in genome.sensors.items()}
    genome.apply_operator("sensor_reach", gc)
    changed = {genome.sensors[s].type for s in before if genome.sensors[s].to_dict() != before[s]}
    assert len(changed) == 1
    kind = changed.pop()
    deltas = {(round(genome.sensors[s].range - before[s]["range"], 12), round(genome.sensors[s].fov - before[s]["fov"], 12))
              for s in before if before[s]["type"] == kind}
    assert len(deltas) == 1                                      # the same shift for the whole type
    for s in before:
        assert genome.sensors[s].bearing == before[s]["bearing"]
        assert genome.sensors[s].orientation == before[s]["orientation"]


def test_crossover_matching_from_either_disjoint_from_fitter():
    config = neat_m()
    gc = config.genome_config
    a = NEATMGenome(1)
    a.configure_new(gc)
    b = copy_network(a, 2)
    a.sensors = {0: SensorGene("infrared", 0.1, 0, 5, 1), 1: SensorGene("camera", 0.2, 0, 5, 1)}
    b.sensors = {0: SensorGene("ultrasonic", 0.3, 0, 5, 1), 5: SensorGene("colour", 0.4, 0, 5, 1)}
    a.fitness, b.fitness = 2.0, 1.0
    random.seed(13)
    slot0 = set()
    for key in range(100):
        child = NEATMGenome(10 + key)
        child.configure_crossover(a, b, gc)
        assert set(child.sensors) == {0, 1}                      # a's slots: b's disjoint slot 5 is dropped
        assert child.sensors[1].type == "camera"
        slot0.add(child.sensors[0].type)
    assert slot0 == {"infrared", "ultrasonic"}                   # matching: either parent


def test_at_most_one_bottom_sensor():
    config = neat_m()
    gc = config.genome_config
    gc.sensor_types = ["bottom", "infrared"]
    gc.initial_sensors = 6
    random.seed(14)
    for key in range(100):
        genome = NEATMGenome(key)
        genome.configure_new(gc)
        for _ in range(6):
            genome.apply_operator("add_sensor", gc)
        bottoms = [g for g in genome.sensors.values() if g.type == "bottom"]
        assert len(bottoms) <= 1
        assert all(g.bearing == 0.0 for g in bottoms)


def test_neat_m_decoding_with_empty_slots_matches_neat_network():
    config = neat_m()
    gc = config.genome_config
    random.seed(15)
    rng = np.random.default_rng(15)
    for key in range(10):
        genome = NEATMGenome(key)
        genome.configure_new(gc)
        for _ in range(4):
            genome.mutate_add_node(gc)
            genome.mutate_add_connection(gc)
        slots = sorted(random.sample(range(10), 4))
        genome.sensors = {s: SensorGene("infrared", 0.3 * s, 0.0, 5.0, 1.0) for s in slots}
        controller, morphology = decode_neat_m(genome, config)
        assert [s.bearing for s in morphology] == pytest.approx([0.3 * s for s in slots])
        obs = rng.uniform(0, 1, (3, 4))
        reference = neat.nn.FeedForwardNetwork.create(genome, config)
        for i in range(3):
            full = np.zeros(10)
            full[slots] = obs[i]                                 # sensor j feeds input slot j; empty slots 0
            expected = 2.0 * np.array(reference.activate(full.tolist())) - 1.0
            np.testing.assert_allclose(controller.act(obs)[i], expected, atol=1e-9)
