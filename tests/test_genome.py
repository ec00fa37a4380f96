"""CPPN and NEAT-M genomes inside real neat-python populations; sensor-gene variation."""

from __future__ import annotations

import math
import random
from pathlib import Path

import neat
import numpy as np
import pytest
from neat.innovation import InnovationTracker

from evolution.encodings.direct import NEATMGenome, SensorGene, decode_neat_m
from evolution.encodings.genome import CPPNGenome
from evolution.encodings.substrate import decode
from evolution.reproduction.breeding import NEATReproduction
from evolution.reproduction.species import GatheringSpeciesSet
from gathering_env import SENSOR_TYPES, Morphology

CONFIGS = Path(__file__).resolve().parent.parent / "configs"


def load(genome_type, name):
    return neat.Config(genome_type, NEATReproduction, GatheringSpeciesSet,
                       neat.DefaultStagnation, str(CONFIGS / name))


@pytest.mark.parametrize("genome_type,name,decoder", [
    (CPPNGenome, "hyperneat_m.neat.cfg", decode),
    (NEATMGenome, "neat_m.neat.cfg", decode_neat_m),
])
def test_population_runs_and_decodes(genome_type, name, decoder):
    config = load(genome_type, name)
    config.pop_size = 20
    population = neat.Population(config, seed=1)

    def fitness(genomes, cfg):
        for _, g in genomes:
            controller, morph = decoder(g, cfg)
            assert isinstance(morph, Morphology)
            g.fitness = float(len(morph))

    population.run(fitness, 2)
    assert len(population.population) == 20


def test_neat_m_mutation_keeps_sensors_within_bounds():
    config = load(NEATMGenome, "neat_m.neat.cfg")
    gc = config.genome_config
    gc.sensor_add_prob = gc.sensor_angle_mutate_prob = gc.sensor_reach_mutate_prob = 1.0
    gc.sensor_angle_mutate_power = gc.sensor_reach_mutate_power = 2.0  # huge steps
    population = neat.Population(config, seed=2)
    random.seed(2)
    genome = next(iter(population.population.values()))
    seen_types = set()
    for _ in range(300):
        genome.mutate(gc)
        for gene in genome.sensors.values():
            spec = SENSOR_TYPES[gene.type]
            seen_types.add(gene.type)
            assert -math.pi <= gene.bearing < math.pi
            assert -math.pi / 2 <= gene.orientation <= math.pi / 2
            if spec.configurable:
                assert 0 < gene.range <= spec.range_max
                assert spec.fov_min <= gene.fov <= spec.fov_max
        decode_neat_m(genome, config)  # always a valid Morphology (SensorSpec validates)
    assert len(genome.sensors) <= 10
    assert len(seen_types) >= 3


def test_distance_grows_with_sensor_differences():
    config = load(NEATMGenome, "neat_m.neat.cfg")
    population = neat.Population(config, seed=3)
    a = next(iter(population.population.values()))
    b = NEATMGenome(999)
    b.nodes = {k: n.copy() for k, n in a.nodes.items()}
    b.connections = {k: c.copy() for k, c in a.connections.items()}
    b.sensors = {s: SensorGene(**g.to_dict()) for s, g in a.sensors.items()}
    gc = config.genome_config
    assert a.distance(b, gc) == pytest.approx(0.0)
    slot = next(iter(b.sensors))
    b.sensors[slot].fov = SENSOR_TYPES[b.sensors[slot].type].fov_max if b.sensors[slot].type != "bottom" else 0.0
    b.sensors[slot].bearing += 1.0
    b.sensors[slot].clamp()
    d1 = a.distance(b, gc)
    assert d1 > 0
    b.sensors[slot].type = "camera" if a.sensors[slot].type != "camera" else "infrared"
    assert a.distance(b, gc) > d1


def test_crossover_takes_sensor_genes_from_parents():
    config = load(NEATMGenome, "neat_m.neat.cfg")
    population = neat.Population(config, seed=5)
    p1, p2 = list(population.population.values())[:2]
    p1.fitness, p2.fitness = 2.0, 1.0
    child = NEATMGenome(1000)
    child.configure_crossover(p1, p2, config.genome_config)
    assert set(child.sensors) == set(p1.sensors)        # slots of the fitter parent
    for slot, gene in child.sensors.items():
        candidates = [p.sensors[slot].to_dict() for p in (p1, p2) if slot in p.sensors]
        assert gene.to_dict() in candidates
        assert gene is not p1.sensors[slot]             # copied, not shared


def test_unknown_genome_key_is_an_error(tmp_path):
    text = (CONFIGS / "hyperneat_m.neat.cfg").read_text().replace("num_hidden              = 0",
                                                                  "num_hidden              = 0\nnum_hiden = 3")
    path = tmp_path / "bad.cfg"
    path.write_text(text)
    with pytest.raises(ValueError, match="num_hiden"):
        neat.Config(CPPNGenome, NEATReproduction, GatheringSpeciesSet, neat.DefaultStagnation, str(path))


def test_cppn_needs_six_outputs(tmp_path):
    text = (CONFIGS / "hyperneat_m.neat.cfg").read_text().replace("num_outputs             = 6",
                                                                  "num_outputs             = 5")
    path = tmp_path / "bad.cfg"
    path.write_text(text)
    with pytest.raises(ValueError, match="num_outputs=5"):
        neat.Config(CPPNGenome, NEATReproduction, GatheringSpeciesSet, neat.DefaultStagnation, str(path))


# ---------------------------------------------------------------------------- each operator, exactly
def neat_m_genome(config, sensors):
    """A NEAT-M genome of the shipped config with the given slot -> sensor genes."""
    config.genome_config.innovation_tracker = InnovationTracker()
    genome = NEATMGenome(1)
    genome.configure_new(config.genome_config)
    genome.sensors = {slot: SensorGene(*gene) for slot, gene in sensors.items()}
    return genome


SENSORS = {0: ("bottom", 0.0, 0.0, 0.0, 0.0),
           1: ("camera", 0.5, 0.1, 12.0, 1.0), 2: ("camera", -1.0, -0.2, 10.0, 0.8),
           3: ("camera", 2.0, 0.3, 15.0, 1.2), 4: ("infrared", 1.0, 0.0, 0.5, 1.0),
           5: ("infrared", -2.0, 0.2, 0.3, 1.5), 7: ("colour", 0.0, 0.0, 3.0, 1.0)}


def snapshot(genome):
    return {slot: g.to_dict() for slot, g in genome.sensors.items()}


def test_angle_operator_moves_both_angles_of_one_to_four_sensors_and_nothing_else():
    config = load(NEATMGenome, "neat_m.neat.cfg")
    random.seed(11)
    counts = set()
    for _ in range(200):
        genome = neat_m_genome(config, SENSORS)
        before = snapshot(genome)
        genome.apply_operator("sensor_angles", config.genome_config)
        after = snapshot(genome)
        assert set(after) == set(before)
        changed = [s for s in before if after[s] != before[s]]
        assert 1 <= len(changed) <= 4
        counts.add(len(changed))
        assert after[0] == before[0]                                  # the bottom sensor never moves
        for slot in changed:
            assert after[slot]["bearing"] != before[slot]["bearing"]        # both angles move
            assert after[slot]["orientation"] != before[slot]["orientation"]
            for key in ("type", "range", "fov"):
                assert after[slot][key] == before[slot][key]
    assert counts == {1, 2, 3, 4}


def test_reach_operator_shifts_every_sensor_of_one_type_alike():
    config = load(NEATMGenome, "neat_m.neat.cfg")
    gc = config.genome_config
    gc.sensor_reach_mutate_power = 0.01                               # small steps: no clamping
    random.seed(12)
    kinds = set()
    for _ in range(100):
        genome = neat_m_genome(config, SENSORS)
        before = snapshot(genome)
        genome.apply_operator("sensor_reach", gc)
        after = snapshot(genome)
        changed = {s for s in before if after[s] != before[s]}
        types = {before[s]["type"] for s in changed}
        assert len(types) == 1
        kind = types.pop()
        kinds.add(kind)
        assert changed == {s for s in before if before[s]["type"] == kind}   # all sensors of the type
        d_range = {round(after[s]["range"] - before[s]["range"], 12) for s in changed}
        d_fov = {round(after[s]["fov"] - before[s]["fov"], 12) for s in changed}
        assert len(d_range) == 1 and len(d_fov) == 1 and 0.0 not in d_range | d_fov   # one shift each
        for s in changed:
            assert (after[s]["bearing"], after[s]["orientation"]) == (before[s]["bearing"], before[s]["orientation"])
    assert kinds == {"camera", "infrared", "colour"}                  # never the bottom sensor


def test_add_and_remove_sensor_change_one_slot():
    config = load(NEATMGenome, "neat_m.neat.cfg")
    gc = config.genome_config
    random.seed(13)
    added = set()
    for _ in range(100):
        genome = neat_m_genome(config, SENSORS)
        before = snapshot(genome)
        genome.apply_operator("add_sensor", gc)
        after = snapshot(genome)
        new = set(after) - set(before)
        assert len(new) == 1 and {s: after[s] for s in before} == before
        assert after[new.pop()]["type"] != "bottom"                   # never a second bottom sensor
        added |= set(after) - set(before)
        genome.sensors = {slot: SensorGene(*gene) for slot, gene in SENSORS.items()}
        genome.apply_operator("remove_sensor", gc)
        after = snapshot(genome)
        assert len(after) == len(before) - 1 and all(after[s] == before[s] for s in after)
    assert added == {6, 8, 9}                                         # every free slot, only free slots


def test_weight_operator_resets_and_perturbs_at_the_configured_rates():
    """Resets and perturbations told apart by their values: a reset draws the init value
    (mean 2.5, stdev 0), a perturbation adds a Gaussian to 0. Fixed seed: no luck involved."""
    config = load(NEATMGenome, "neat_m.neat.cfg")
    gc = config.genome_config
    gc.weight_init_mean = gc.bias_init_mean = 2.5
    gc.weight_init_stdev = gc.bias_init_stdev = 0.0
    random.seed(14)
    gc.innovation_tracker = InnovationTracker()
    genome = NEATMGenome(1)
    genome.configure_new(gc)
    links = [g for g in genome.connections.values() if g.enabled] + list(genome.nodes.values())
    assert 3 < len(links) < 50                                        # 2 % of the links rounds to one link
    draws = 4000
    for reset_prob in (0.1, 0.3):
        gc.weight_reset_prob = reset_prob
        resets, sizes, steps = 0, [], []
        for _ in range(draws):
            for c in genome.connections.values():
                c.weight = 0.0
            for n in genome.nodes.values():
                n.bias = 0.0
            genome.mutate_weights(gc)
            values = [c.weight for c in genome.connections.values() if c.enabled] + \
                     [n.bias for n in genome.nodes.values()]
            moved = [v for v in values if v != 0.0]
            assert all(c.weight == 0.0 for c in genome.connections.values() if not c.enabled)
            is_reset = [v == 2.5 for v in moved]
            assert all(is_reset) or not any(is_reset)                 # one operation: all reset or all perturbed
            resets += all(is_reset)
            sizes.append(len(moved))
            if not any(is_reset):
                steps += moved
        # Binomial(4000, p): 5 standard deviations of the rate, at most 0.036.
        bound = 5 * math.sqrt(reset_prob * (1 - reset_prob) / draws)
        assert abs(resets / draws - reset_prob) < bound, (reset_prob, resets / draws)
        share = {k: sizes.count(k) / draws for k in (1, 2, 3)}        # choices 1, 2, 3, 2 % (= 1 link)
        assert set(sizes) == {1, 2, 3}
        for k, p in ((1, 0.5), (2, 0.25), (3, 0.25)):
            assert abs(share[k] - p) < 5 * math.sqrt(p * (1 - p) / draws), (k, share)
        sd = float(np.std(steps))
        assert abs(sd - gc.weight_mutate_power) < 0.05 * gc.weight_mutate_power   # perturbation size


def test_neat_python_variation_applies_each_sensor_operator_once_with_its_probability():
    """variation = neat_python: neat-python's mutate() (here: delete one link), then each of the
    four sensor operators with its own probability (here: add a sensor, certainly)."""
    config = load(NEATMGenome, "neat_m.neat.cfg")
    gc = config.genome_config
    gc.variation = "neat_python"
    gc.node_add_prob = gc.node_delete_prob = gc.conn_add_prob = 0.0
    gc.conn_delete_prob = 1.0
    gc.weight_mutate_rate = gc.bias_mutate_rate = gc.weight_replace_rate = gc.bias_replace_rate = 0.0
    gc.sensor_add_prob, gc.sensor_remove_prob = 1.0, 0.0
    gc.sensor_angle_mutate_prob = gc.sensor_reach_mutate_prob = 0.0
    random.seed(15)
    for _ in range(20):
        genome = neat_m_genome(config, {0: ("bottom", 0.0, 0.0, 0.0, 0.0), 1: ("camera", 0.5, 0.1, 12.0, 1.0)})
        links, before = len(genome.connections), snapshot(genome)
        genome.mutate(gc)
        assert len(genome.connections) == links - 1                 # neat-python's one deletion, no more
        after = snapshot(genome)
        assert len(after) == 3 and {s: after[s] for s in before} == before   # one sensor added, none moved
