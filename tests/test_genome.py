"""CPPN and NEAT-M genomes inside real neat-python populations; sensor-gene variation."""

from __future__ import annotations

import math
import random
from pathlib import Path

import neat
import pytest

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
