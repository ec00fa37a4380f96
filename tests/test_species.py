"""The species set (evolution.reproduction.species): a threshold that holds a species count,
the original implementation's rule and distance, and its config errors."""

from __future__ import annotations

import random
from types import SimpleNamespace

import neat
import numpy as np
import pytest

from evolution.cli import evolve_main
from evolution.encodings.genome import CPPNGenome
from evolution.reproduction.breeding import NEATReproduction
from evolution.reproduction.species import (
    GatheringSpeciesSet,
    adapted_threshold,
    original_distance,
    target_count,
)
from evolution.run.experiment import load_experiment
from evolution.run.neat_setup import make_neat_config
from evolution.run.presets import CONFIG_DIR

CFG = CONFIG_DIR / "hyperneat_m.neat.cfg"


def config_with(tmp_path, **keys):
    text = CFG.read_text()
    for key, value in keys.items():
        lines = text.splitlines()
        at = next(i for i, line in enumerate(lines) if line.startswith("[GatheringSpeciesSet]"))
        lines = [line for line in lines if not line.split("=")[0].strip() == key]
        lines.insert(at + 1, f"{key} = {value}")
        text = "\n".join(lines) + "\n"
    path = tmp_path / "species.cfg"
    path.write_text(text)
    return path


def load(path=CFG, pop_size=150):
    config = neat.Config(CPPNGenome, NEATReproduction, GatheringSpeciesSet, neat.DefaultStagnation, str(path))
    config.pop_size = pop_size
    return config


def cheap_fitness(seed):
    rng = np.random.default_rng(seed)

    def fitness(genomes, config):
        for _, g in genomes:
            w = [c.weight for c in g.connections.values()]
            g.fitness = float(np.tanh(np.mean(w)) * 50 + 50 + rng.normal(0, 5))
            g.objectives = (g.fitness, float(100 - 2 * len(w)))
    return fitness


# ---------------------------------------------------------------- the adaptive rule
def test_adapted_threshold_by_hand():
    # fewer species than the target: down in proportion to the shortfall
    assert adapted_threshold(1.0, 5, 15, 0.2, 0.01) == pytest.approx(1.0 - 0.2 * 10 / 15)
    # more, and a new species formed: up by the whole step; none formed: held (no wind-up)
    assert adapted_threshold(1.0, 20, 15, 0.2, 0.01, new_species=True) == pytest.approx(1.2)
    assert adapted_threshold(1.0, 20, 15, 0.2, 0.01, new_species=False) == 1.0
    assert adapted_threshold(1.0, 15, 15, 0.2, 0.01) == 1.0
    assert adapted_threshold(0.011, 1, 15, 0.5, 0.01) == 0.01   # floor


def test_target_count_counts_and_fractions():
    assert target_count("0.1", 150) == 15 and target_count("0.1", 6) == 1
    assert target_count("12", 150) == 12
    for bad in ("0", "-3", "2.5", "x", "151"):
        with pytest.raises(ValueError, match="target_species"):
            target_count(bad, 150)


def test_threshold_moves_the_right_way_on_a_real_population():
    config = load()
    population = neat.Population(config, seed=3)
    species = population.species
    start_count = len(species.species)
    assert 10 <= start_count <= 20            # the shipped start (1.2) gives ~15 at N = 150
    # far too many species wanted: the threshold falls; far too few: it rises with new species
    config.species_set_config.target_species = "100"
    before = species.threshold
    species.speciate(config, population.population, 1)
    assert species.threshold < before
    config.species_set_config.target_species = "1"
    species.species = {}                      # every species new: count > 1 with new species
    species.speciate(config, population.population, 2)
    assert species.threshold > species.history[-1][1]


@pytest.mark.parametrize("objectives", [("task",), ("task", "morphology")])
def test_species_count_stays_near_the_target_over_generations(objectives):
    """A real neat-python population of 150 HyperNEAT-M CPPNs, cheap fitness: after a few
    generations the count stays within 30 % of the target (15) every generation."""
    exp = load_experiment(None, {"population": 150, "objectives": list(objectives)})
    config = make_neat_config(exp)
    population = neat.Population(config, seed=7)
    fitness = cheap_fitness(0)
    for _ in range(15):
        population.run(fitness, 1)
    counts = [count for _, _, count in population.species.history]
    assert len(counts) == 16                 # one entry per generation (MODS speciates twice)
    assert all(abs(c - 15) <= 0.3 * 15 for c in counts[3:]), counts


def test_fixed_mode_is_neat_pythons_species_set(tmp_path):
    """The assignment is neat-python's own: same species and members as DefaultSpeciesSet."""
    path = config_with(tmp_path, species_mode="fixed", compatibility_threshold="1.1")
    text = path.read_text().replace("[GatheringSpeciesSet]", "[DefaultSpeciesSet]")
    text = "\n".join(line for line in text.splitlines()
                     if line.split("=")[0].strip() not in ("species_mode", "target_species", "threshold_step"))
    ref_path = tmp_path / "default.cfg"
    ref_path.write_text(text + "\n")
    ref_config = neat.Config(CPPNGenome, NEATReproduction, neat.DefaultSpeciesSet, neat.DefaultStagnation,
                             str(ref_path))

    def lineage(config):
        pop = neat.Population(config, seed=5)
        fitness, seen = cheap_fitness(1), []
        random.seed(11)
        for _ in range(4):
            seen.append(sorted(sorted(s.members) for s in pop.species.species.values()))
            pop.run(fitness, 1)
        return pop, seen

    ours, mine = lineage(load(path))
    _, reference = lineage(ref_config)
    assert mine == reference and len(mine[0]) > 5
    assert ours.species.threshold == 1.1


# ---------------------------------------------------------------- the original rule
def genome_with(links):
    """A genome whose connection genes are (innovation, weight) pairs."""
    conns = {(-1, i): SimpleNamespace(key=(-1, i), innovation=inn, weight=w) for i, (inn, w) in enumerate(links)}
    return SimpleNamespace(connections=conns)


def test_original_distance_by_hand():
    a = genome_with([(1, 0.5), (2, -1.0), (3, 2.0), (6, 1.0)])
    b = genome_with([(1, 1.5), (3, 1.0), (4, 0.0), (8, 3.0), (9, 1.0)])
    # matching 1, 3: |0.5-1.5| = 1, |2-1| = 1 -> mean 1.0; a's max 6: b's 8, 9 are excess (2);
    # disjoint: a's 2, 6 and b's 4 (3); raw counts, no size normalisation
    assert original_distance(a, b) == pytest.approx(2 + 3 + 0.4 * 1.0)
    assert original_distance(b, a) == pytest.approx(original_distance(a, b))
    assert original_distance(a, a) == 0.0


def test_original_rule_moves_by_a_hundredth_at_its_bounds(tmp_path):
    exp = load_experiment(None, {"population": 150, "speciation": "original"})
    config = make_neat_config(exp)
    cfg = config.species_set_config
    assert (cfg.species_mode, cfg.compatibility_threshold, cfg.threshold_step, cfg.max_species,
            cfg.min_species) == ("original", 1.0, 0.01, 40, 2)
    population = neat.Population(config, seed=2)
    species = population.species
    # Encog puts generation 0 into one species
    assert len(species.species) == 1 and species.history[-1][1] == 1.0
    # one survivor is fewer than 2: -0.01 before assigning; raw-weight distances of new CPPNs
    # to the leader are large, so far more than 40 species form
    species.speciate(config, population.population, 1)
    assert species.history[-1][1] == pytest.approx(0.99)
    assert len(species.species) > 40
    species.speciate(config, population.population, 2)      # more than 40 survived: +0.01
    assert species.history[-1][1] == pytest.approx(1.0)
    mo = make_neat_config(load_experiment(None, {"population": 150, "speciation": "original",
                                                 "objectives": ["task", "morphology"]}))
    assert mo.species_set_config.max_species == 150


def test_original_spawn_by_hand():
    from evolution.reproduction.encog import original_spawn

    # shares 10, 0, 5, 0.2 of 15.2 over 9 places: 5.92 -> 6, 0, 2.96 -> 3, 0.12 -> 0 (dies)
    assert original_spawn([10, 0, 5, 0.2], [10, 0, 15, 0.2], 0, 9) == [6, 0, 3, 0]
    # the best genome's species keeps a place when its share rounds to 0 (the surplus comes off
    # the other species, which ranks below it by best score)
    assert original_spawn([50, 0.1], [50, 60], 1, 9) == [8, 1]
    # a surplus comes off the species with the lowest best scores (2 + 2 + 2 + 2 > 6)
    assert original_spawn([1, 1, 1, 1], [4, 3, 2, 1], 0, 6) == [2, 2, 2, 0]
    assert original_spawn([1, 1, 1, 1], [1, 2, 3, 4], 3, 6) == [0, 2, 2, 2]
    # a shortfall goes to the species with the best score; all shares 0: round(places / n) each
    assert original_spawn([1, 1, 1], [1, 5, 2], 1, 4) == [1, 2, 1]
    assert original_spawn([0.0] * 118, [0.0] * 118, 0, 149) == [32] + [1] * 117


def test_original_species_of_leaders_by_hand(tmp_path):
    """First species (oldest first) whose leader is within the threshold, not the nearest; a
    species whose leader is gone is disbanded; a genome far from every leader founds one."""
    config = make_neat_config(load_experiment(None, {"population": 6, "speciation": "original"}))
    assert config.species_set_config.leaders
    species = GatheringSpeciesSet(config.species_set_config, neat.reporting.ReporterSet())

    def genome(key, w):
        g = genome_with([(1, w)])
        g.key = key
        return g

    # leaders at 0.0 (species 1), 2.0 (species 2) and 4.0 (species 3); distance 0.4 * |dw|
    leaders = {1: genome(1, 0.0), 2: genome(2, 2.0), 3: genome(3, 4.0)}
    for sid, g in leaders.items():
        species.species[sid] = neat.species.Species(sid, 0)
        species.species[sid].update(g, {g.key: g})
    species.indexer = iter(range(4, 100))
    species.history.append((0, 1.0, 3))
    # genome 3 (species 3's leader) is not in the new population: species 3 is disbanded
    population = {1: leaders[1], 2: leaders[2], 10: genome(10, 1.5), 11: genome(11, 2.2), 12: genome(12, 4.0),
                  13: genome(13, 9.0)}
    species.speciate(config, population, 1)
    members = {sid: sorted(s.members) for sid, s in species.species.items()}
    # 10 is 0.6 from leader 1 and 0.2 from leader 2: the first within 1.0 wins (species 1);
    # 11: 0.88 from 1, joins 1; 12 (where leader 3 was): 1.6 and 0.8 -> species 2; 13 founds species 4
    assert members == {1: [1, 10, 11], 2: [2, 12], 4: [13]}
    assert species.species[4].representative.key == 13


def test_original_threshold_has_no_floor_and_below_0_every_genome_founds_a_species():
    """Encog's threshold falls by 0.01 while fewer than 2 species survive, past 0 (adaptive mode
    stops at threshold_min): from 0.005 to -0.005, where no genome joins the leader, not even
    one identical to it; then 3 species survive (> max 2 here) and it climbs back by 0.01."""
    config = make_neat_config(load_experiment(None, {"population": 6, "speciation": "original"}))
    config.species_set_config.max_species = 2
    species = GatheringSpeciesSet(config.species_set_config, neat.reporting.ReporterSet())

    def genome(key, w):
        g = genome_with([(1, w)])
        g.key = key
        return g

    leader = genome(1, 0.0)
    species.species[1] = neat.species.Species(1, 0)
    species.species[1].update(leader, {1: leader})
    species.indexer = iter(range(2, 100))
    species.history.append((0, 0.005, 1))
    species.threshold = 0.005
    population = {1: leader, 10: genome(10, 0.0), 11: genome(11, 0.01)}
    species.speciate(config, population, 1)
    assert species.history[-1][1] == pytest.approx(-0.005)
    assert sorted(sorted(s.members) for s in species.species.values()) == [[1], [10], [11]]
    species.speciate(config, population, 2)
    assert species.history[-1][1] == pytest.approx(0.005)


def test_run_statistics_record_threshold_and_species(tmp_path):
    from tests.small_runs import SMALL_WORLD
    exp = tmp_path / "e.toml"
    exp.write_text('[experiment]\nname = "e"\ngenerations = 2\npopulation = 20\ntrials = 1\nseed = 2\n' + SMALL_WORLD)
    assert evolve_main([str(exp), "--out", str(tmp_path / "run"), "--workers", "1", "--no-progress"]) == 0
    import json
    records = [json.loads(line) for line in (tmp_path / "run" / "stats.jsonl").read_text().splitlines()]
    assert [r["threshold"] for r in records][0] == 1.2
    assert all(r["species"] >= 1 and r["threshold"] > 0 for r in records)


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize("key,value,needle", [
    ("target_species", "0", "target_species = 0"),
    ("target_species", "151", "target_species = 151"),
    ("threshold_step", "0", "threshold_step = 0"),
    ("threshold_step", "-0.1", "threshold_step = -0.1"),
    ("species_mode", "clever", "species_mode = clever"),
])
def test_bad_species_settings_are_one_line_naming_file_and_key(tmp_path, capsys, key, value, needle):
    path = config_with(tmp_path, **{key: value})
    exp = tmp_path / "e.toml"
    exp.write_text(f'[experiment]\npopulation = 150\nneat_config = "{path}"\n')
    assert evolve_main([str(exp), "--out", str(tmp_path / "run"), "--workers", "1", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and needle in err[0] and "allowed" in err[0]
    assert not (tmp_path / "run").exists()


def test_unknown_speciation_in_an_experiment_file(tmp_path, capsys):
    exp = tmp_path / "e.toml"
    exp.write_text('[experiment]\nspeciation = "encog"\n')
    assert evolve_main([str(exp), "--out", str(tmp_path / "run"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "speciation" in err and "adaptive" in err and str(exp) in err
