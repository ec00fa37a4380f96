"""NEAT-M (Hewland & Nitschke): a NEAT controller plus directly encoded sensor genes.

``NEATMGenome`` is a ``neat.DefaultGenome`` (through ``evolution.reproduction.operators.BreedingGenome``)
whose network has one input per possible sensor *slot* (``num_inputs`` = 10) and two outputs
(left, right wheel). Alongside its node and connection genes it carries ``sensors``: slot ->
``SensorGene`` (type, bearing, orientation, range, fov). A slot without a sensor gene
contributes no input.

Extra keys of the ``[NEATMGenome]`` config section (neat-python ``ConfigParameter``s;
docs/model.md §5 gives the original rates; with ``variation = one_operator`` each ``*_prob`` is the
probability of that operator being *the* operator of an offspring, see ``evolution.reproduction.breeding``)::

    sensor_types             = infrared ultrasonic colour camera bottom
    initial_sensors          = 3      # random sensors of a new genome
    sensor_add_prob          = 0.07   # add a random sensor in a free slot
    sensor_remove_prob       = 0.0    # remove a random sensor (not in the original)
    sensor_angle_mutate_prob = 0.1    # perturb bearing/orientation of 1-4 sensors
    sensor_angle_mutate_power = 0.3   # stdev (rad)
    sensor_reach_mutate_prob = 0.07   # perturb range/fov of all sensors of one type
    sensor_reach_mutate_power = 0.1   # stdev as a fraction of the type's bounds
    sensor_compatibility_coefficient = 4.0  # weight of the mean sensor difference in the distance

Parameters are clamped to their type's bounds; bearing wraps around the body. A genome has
at most one bottom sensor; it reads under the robot's centre, so its bearing is fixed at 0
and never mutated. The distance adds ``sensor_compatibility_coefficient`` times the mean
per-slot sensor difference (1 for a missing or retyped sensor) to neat-python's distance:
with a coefficient above the species set's ``compatibility_threshold``, two genomes with the
same network and entirely different sensors fall into different species.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass
from typing import Any

import numpy as np
from neat.graphs import feed_forward_layers

from evolution.encodings.controller import Layer, TeamController
from evolution.reproduction.operators import BreedingGenome, check_probability
from gathering_env import SENSOR_TYPES, Morphology, SensorSpec

SENSOR_PARAMS = (
    ("sensor_types", str, "infrared ultrasonic colour camera bottom"),
    ("initial_sensors", int, 3),
    ("sensor_add_prob", float, 0.07),
    ("sensor_remove_prob", float, 0.0),
    ("sensor_angle_mutate_prob", float, 0.1),
    ("sensor_angle_mutate_power", float, 0.3),
    ("sensor_reach_mutate_prob", float, 0.07),
    ("sensor_reach_mutate_power", float, 0.1),
    ("sensor_compatibility_coefficient", float, 4.0),
)


@dataclass
class SensorGene:
    """One sensor of a NEAT-M genome (same fields and bounds as ``SensorSpec``)."""

    type: str
    bearing: float
    orientation: float
    range: float
    fov: float

    def to_spec(self) -> SensorSpec:
        if not SENSOR_TYPES[self.type].configurable:
            return SensorSpec(self.type, bearing=self.bearing)
        return SensorSpec(self.type, self.bearing, self.orientation, self.range, self.fov)

    def to_dict(self) -> dict[str, Any]:
        return {"type": self.type, "bearing": self.bearing, "orientation": self.orientation,
                "range": self.range, "fov": self.fov}

    def clamp(self) -> SensorGene:
        """Bearing wrapped to [-pi, pi); orientation, range and fov clamped to the type's bounds;
        everything 0 for a bottom sensor (it reads under the robot's centre)."""
        spec = SENSOR_TYPES[self.type]
        self.bearing = (self.bearing + math.pi) % (2 * math.pi) - math.pi
        self.orientation = min(max(self.orientation, -math.pi / 2), math.pi / 2)
        if spec.configurable:
            self.range = min(max(self.range, 1e-3 * spec.range_max), spec.range_max)
            self.fov = min(max(self.fov, spec.fov_min), spec.fov_max)
        else:
            self.bearing = self.orientation = self.range = self.fov = 0.0
        return self

    def distance(self, other: SensorGene) -> float:
        """0 for identical genes; 1 per differing type; else normalised parameter gaps."""
        if self.type != other.type:
            return 1.0
        spec = SENSOR_TYPES[self.type]
        d = abs((self.bearing - other.bearing + math.pi) % (2 * math.pi) - math.pi) / math.pi
        d += abs(self.orientation - other.orientation) / math.pi
        if spec.configurable:
            d += abs(self.range - other.range) / spec.range_max
            d += abs(self.fov - other.fov) / (spec.fov_max - spec.fov_min)
        return d / 4.0


def random_sensor(types: list[str], existing: Any = ()) -> SensorGene:
    """A random sensor of one of ``types``; no second bottom sensor if ``existing`` has one."""
    if any(g.type == "bottom" for g in existing):
        types = [t for t in types if t != "bottom"]
    kind = random.choice(types)
    spec = SENSOR_TYPES[kind]
    gene = SensorGene(kind, random.uniform(-math.pi, math.pi), random.uniform(-math.pi / 2, math.pi / 2),
                      random.uniform(1e-3 * spec.range_max, spec.range_max) if spec.configurable else 0.0,
                      random.uniform(spec.fov_min, spec.fov_max) if spec.configurable else 0.0)
    return gene.clamp()


class NEATMGenome(BreedingGenome):
    """A NEAT network (10 sensor-slot inputs, 2 outputs) with sensor genes (see module docstring)."""

    EXTRA_PARAMS = (*BreedingGenome.EXTRA_PARAMS, *SENSOR_PARAMS)

    @classmethod
    def validate_config(cls, config: Any, section: str) -> None:
        super().validate_config(config, section)
        config.sensor_types = config.sensor_types.split()
        bad = [t for t in config.sensor_types if t not in SENSOR_TYPES]
        if bad or not config.sensor_types or config.sensor_types == ["bottom"]:
            raise ValueError(f"[{section}] sensor_types={config.sensor_types}; allowed: a list of {list(SENSOR_TYPES)} "
                             "with at least one type other than bottom")
        for key in ("sensor_add_prob", "sensor_remove_prob", "sensor_angle_mutate_prob", "sensor_reach_mutate_prob"):
            check_probability(section, key, getattr(config, key))
        if not 1 <= config.num_inputs <= 10:
            raise ValueError(f"[{section}] num_inputs={config.num_inputs}; allowed: 1..10 sensor slots")
        if config.num_outputs != 2:
            raise ValueError(f"[{section}] num_outputs={config.num_outputs}; allowed: 2 (left, right wheel)")
        if not 0 <= config.initial_sensors <= config.num_inputs:
            raise ValueError(f"[{section}] initial_sensors={config.initial_sensors}; allowed: 0..{config.num_inputs}")

    @classmethod
    def operators(cls, config: Any) -> list[tuple[str, float]]:
        return [*super().operators(config), ("sensor_angles", config.sensor_angle_mutate_prob),
                ("sensor_reach", config.sensor_reach_mutate_prob), ("add_sensor", config.sensor_add_prob),
                ("remove_sensor", config.sensor_remove_prob)]

    def __init__(self, key: int) -> None:
        super().__init__(key)
        self.sensors: dict[int, SensorGene] = {}

    def configure_new(self, config: Any) -> None:
        super().configure_new(config)
        self.sensors = {}
        for slot in sorted(random.sample(range(config.num_inputs), config.initial_sensors)):
            self.sensors[slot] = random_sensor(config.sensor_types, self.sensors.values())

    def configure_crossover(self, genome1: Any, genome2: Any, config: Any) -> None:
        super().configure_crossover(genome1, genome2, config)
        fit, other = (genome1, genome2) if genome1.fitness > genome2.fitness else (genome2, genome1)
        self.sensors = {}
        for slot, gene in fit.sensors.items():  # NEAT rule: disjoint genes from the fitter parent
            match = other.sensors.get(slot)
            chosen = gene if match is None or random.random() < 0.5 else match
            if chosen.type == "bottom" and any(g.type == "bottom" for g in self.sensors.values()):
                others = [g for g in (gene, match) if g is not None and g.type != "bottom"]
                if not others:
                    continue  # never two bottom sensors
                chosen = others[0]
            self.sensors[slot] = SensorGene(**chosen.to_dict())

    def apply_operator(self, name: str, config: Any) -> None:
        if name == "sensor_angles":
            self.mutate_sensor_angles(config)
        elif name == "sensor_reach":
            self.mutate_sensor_reach(config)
        elif name == "add_sensor":
            self.mutate_add_sensor(config)
        elif name == "remove_sensor":
            self.mutate_remove_sensor()
        else:
            super().apply_operator(name, config)

    def mutate(self, config: Any) -> None:
        """``variation = neat_python``: neat-python's mutation, then each sensor operator with its probability."""
        super().mutate(config)
        for name, p in self.operators(config)[-4:]:
            if random.random() < p:
                self.apply_operator(name, config)

    def mutate_sensor_angles(self, config: Any) -> None:
        """Perturb bearing and orientation of 1-4 random sensors (not the bottom sensor)."""
        movable = [s for s, g in sorted(self.sensors.items()) if SENSOR_TYPES[g.type].configurable]
        for slot in random.sample(movable, min(len(movable), random.randint(1, 4))):
            gene = self.sensors[slot]
            gene.bearing += random.gauss(0.0, config.sensor_angle_mutate_power)
            gene.orientation += random.gauss(0.0, config.sensor_angle_mutate_power)
            gene.clamp()

    def mutate_sensor_reach(self, config: Any) -> None:
        """Shift range and fov of every sensor of one random configurable type by the same amounts."""
        configurable = sorted({g.type for g in self.sensors.values() if SENSOR_TYPES[g.type].configurable})
        if not configurable:
            return
        kind = random.choice(configurable)
        spec = SENSOR_TYPES[kind]
        d_range = random.gauss(0.0, config.sensor_reach_mutate_power) * spec.range_max
        d_fov = random.gauss(0.0, config.sensor_reach_mutate_power) * (spec.fov_max - spec.fov_min)
        for gene in self.sensors.values():
            if gene.type == kind:
                gene.range += d_range
                gene.fov += d_fov
                gene.clamp()

    def mutate_add_sensor(self, config: Any) -> None:
        """A random sensor in a random free slot."""
        free = [s for s in range(config.num_inputs) if s not in self.sensors]
        if free:
            self.sensors[random.choice(free)] = random_sensor(config.sensor_types, self.sensors.values())
            self.sensors = dict(sorted(self.sensors.items()))

    def mutate_remove_sensor(self) -> None:
        if self.sensors:
            del self.sensors[random.choice(sorted(self.sensors))]

    def distance(self, other: Any, config: Any) -> float:
        return super().distance(other, config) + self.sensor_distance(other, config)

    def sensor_distance(self, other: Any, config: Any) -> float:
        """The sensor genes' part of the speciation distance: the coefficient times the mean
        gene difference over the slots either genome fills (a slot only one fills counts 1)."""
        slots = set(self.sensors) | set(other.sensors)
        if not slots:
            return 0.0
        total = sum(self.sensors[s].distance(other.sensors[s]) if s in self.sensors and s in other.sensors else 1.0
                    for s in slots)
        return config.sensor_compatibility_coefficient * total / len(slots)


def decode_neat_m(genome: NEATMGenome, config: Any) -> tuple[TeamController, Morphology]:
    """The team controller (inputs = present sensor slots, in slot order) and the morphology."""
    gcfg = config.genome_config
    slots = sorted(genome.sensors)
    morphology = Morphology([genome.sensors[s].to_spec() for s in slots])
    input_keys = list(gcfg.input_keys)                   # slot i <-> key -(i + 1)
    present = {input_keys[s]: col for col, s in enumerate(slots)}
    connections = [cg.key for cg in genome.connections.values() if cg.enabled]
    layers_keys = feed_forward_layers(input_keys, gcfg.output_keys, connections)
    layers_keys = layers_keys[0] if isinstance(layers_keys, tuple) else layers_keys
    order = [k for layer in layers_keys for k in sorted(layer)]
    for k in gcfg.output_keys:  # outputs that nothing feeds still exist (they output act(bias))
        if k not in order:
            order.append(k)
            layers_keys = [*layers_keys, {k}]
    column = dict(present)
    s = len(slots)
    for i, k in enumerate(order):
        column[k] = s + i
    width = s + len(order)
    incoming: dict[int, list[tuple[int, float]]] = {}
    for (a, b) in connections:
        if a in column and b in column:
            incoming.setdefault(b, []).append((a, genome.connections[(a, b)].weight))
    layers = []
    for layer in layers_keys:
        nodes = sorted(layer)
        weights = np.zeros((len(nodes), width))
        for row, node in enumerate(nodes):
            for src, w in incoming.get(node, ()):
                weights[row, column[src]] += w
            if genome.nodes[node].aggregation != "sum":
                raise ValueError(f"NEAT-M node {node} uses aggregation {genome.nodes[node].aggregation!r}; "
                                 "the batched controller supports 'sum'")
        layers.append(Layer([column[n] for n in nodes], weights,
                            [genome.nodes[n].bias for n in nodes], [genome.nodes[n].response for n in nodes],
                            [genome.nodes[n].activation for n in nodes]))
    controller = TeamController(s, len(order), layers, [column[k] for k in gcfg.output_keys])
    return controller, morphology
