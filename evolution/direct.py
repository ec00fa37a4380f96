"""NEAT-M (Hewland & Nitschke): a NEAT controller plus directly encoded sensor genes.

``NEATMGenome`` is a ``neat.DefaultGenome`` whose network has one input per possible sensor
*slot* (``num_inputs`` = 10) and two outputs (left, right wheel). Alongside its node and
connection genes it carries ``sensors``: slot -> ``SensorGene`` (type, bearing,
orientation, range, fov). A slot without a sensor gene contributes no input.

Extra keys of the ``[NEATMGenome]`` config section (parsed through ``parse_config``; SPEC
section 5 gives the original rates)::

    sensor_types             = infrared ultrasonic colour camera bottom
    initial_sensors          = 3      # random sensors of a new genome
    sensor_add_prob          = 0.07   # add a random sensor in a free slot
    sensor_remove_prob       = 0.02   # remove a random sensor (not in the original)
    sensor_angle_mutate_prob = 0.1    # perturb bearing/orientation of 1-4 sensors
    sensor_angle_mutate_power = 0.3   # stdev (rad)
    sensor_reach_mutate_prob = 0.07   # perturb range/fov of all sensors of one type
    sensor_reach_mutate_power = 0.1   # stdev as a fraction of the type's bounds
    sensor_compatibility_coefficient = 1.0  # weight of sensor differences in the distance

Parameters are clamped to their type's bounds; bearing wraps around the body.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass
from typing import Any

import neat
import numpy as np
from neat.graphs import feed_forward_layers

from gathering_env import SENSOR_TYPES, Morphology, SensorSpec

from .controller import Layer, TeamController
from .genome import check_genome_section

_SENSOR_KEYS = {
    "sensor_types": (str, "infrared ultrasonic colour camera bottom"),
    "initial_sensors": (int, "3"),
    "sensor_add_prob": (float, "0.07"),
    "sensor_remove_prob": (float, "0.02"),
    "sensor_angle_mutate_prob": (float, "0.1"),
    "sensor_angle_mutate_power": (float, "0.3"),
    "sensor_reach_mutate_prob": (float, "0.07"),
    "sensor_reach_mutate_power": (float, "0.1"),
    "sensor_compatibility_coefficient": (float, "1.0"),
}


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
        """Bearing wrapped to [-pi, pi); orientation, range and fov clamped to the type's bounds."""
        spec = SENSOR_TYPES[self.type]
        self.bearing = (self.bearing + math.pi) % (2 * math.pi) - math.pi
        self.orientation = min(max(self.orientation, -math.pi / 2), math.pi / 2)
        if spec.configurable:
            self.range = min(max(self.range, 1e-3 * spec.range_max), spec.range_max)
            self.fov = min(max(self.fov, spec.fov_min), spec.fov_max)
        else:
            self.orientation = self.range = self.fov = 0.0
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


def random_sensor(types: list[str]) -> SensorGene:
    kind = random.choice(types)
    spec = SENSOR_TYPES[kind]
    gene = SensorGene(kind, random.uniform(-math.pi, math.pi), random.uniform(-math.pi / 2, math.pi / 2),
                      random.uniform(1e-3 * spec.range_max, spec.range_max) if spec.configurable else 0.0,
                      random.uniform(spec.fov_min, spec.fov_max) if spec.configurable else 0.0)
    return gene.clamp()


class NEATMGenome(neat.DefaultGenome):
    """A NEAT network (10 sensor-slot inputs, 2 outputs) with sensor genes (see module docstring)."""

    @classmethod
    def parse_config(cls, param_dict: dict[str, str]) -> neat.genome.DefaultGenomeConfig:
        extra = {k: param_dict.pop(k, default) for k, (_, default) in _SENSOR_KEYS.items()}
        config = super().parse_config(param_dict)
        check_genome_section(config, param_dict, cls.__name__)
        for key, raw in extra.items():
            kind = _SENSOR_KEYS[key][0]
            try:
                value = raw.split() if key == "sensor_types" else kind(raw)
            except ValueError:
                raise ValueError(f"[{cls.__name__}] {key}={raw!r} must be a {kind.__name__}") from None
            setattr(config, key, value)
        bad = [t for t in config.sensor_types if t not in SENSOR_TYPES]
        if bad or not config.sensor_types:
            raise ValueError(f"[{cls.__name__}] sensor_types={config.sensor_types}; allowed: {list(SENSOR_TYPES)}")
        for key in ("sensor_add_prob", "sensor_remove_prob", "sensor_angle_mutate_prob", "sensor_reach_mutate_prob"):
            if not 0.0 <= getattr(config, key) <= 1.0:
                raise ValueError(f"[{cls.__name__}] {key}={getattr(config, key)}; allowed: [0, 1]")
        if not 1 <= config.num_inputs <= 10:
            raise ValueError(f"[{cls.__name__}] num_inputs={config.num_inputs}; allowed: 1..10 sensor slots")
        if config.num_outputs != 2:
            raise ValueError(f"[{cls.__name__}] num_outputs={config.num_outputs}; allowed: 2 (left, right wheel)")
        if not 0 <= config.initial_sensors <= config.num_inputs:
            raise ValueError(f"[{cls.__name__}] initial_sensors={config.initial_sensors}; allowed: 0..{config.num_inputs}")
        return config

    def __init__(self, key: int) -> None:
        super().__init__(key)
        self.sensors: dict[int, SensorGene] = {}

    def configure_new(self, config: Any) -> None:
        super().configure_new(config)
        slots = random.sample(range(config.num_inputs), config.initial_sensors)
        self.sensors = {slot: random_sensor(config.sensor_types) for slot in sorted(slots)}

    def configure_crossover(self, genome1: Any, genome2: Any, config: Any) -> None:
        super().configure_crossover(genome1, genome2, config)
        fit, other = (genome1, genome2) if genome1.fitness > genome2.fitness else (genome2, genome1)
        self.sensors = {}
        for slot, gene in fit.sensors.items():  # NEAT rule: disjoint genes from the fitter parent
            match = other.sensors.get(slot)
            chosen = gene if match is None or random.random() < 0.5 else match
            self.sensors[slot] = SensorGene(**chosen.to_dict())

    def mutate(self, config: Any) -> None:
        super().mutate(config)
        types = config.sensor_types
        if self.sensors and random.random() < config.sensor_angle_mutate_prob:
            for slot in random.sample(sorted(self.sensors), min(len(self.sensors), random.randint(1, 4))):
                gene = self.sensors[slot]
                gene.bearing += random.gauss(0.0, config.sensor_angle_mutate_power)
                gene.orientation += random.gauss(0.0, config.sensor_angle_mutate_power)
                gene.clamp()
        configurable = sorted({g.type for g in self.sensors.values() if SENSOR_TYPES[g.type].configurable})
        if configurable and random.random() < config.sensor_reach_mutate_prob:
            kind = random.choice(configurable)
            spec = SENSOR_TYPES[kind]
            d_range = random.gauss(0.0, config.sensor_reach_mutate_power) * spec.range_max
            d_fov = random.gauss(0.0, config.sensor_reach_mutate_power) * (spec.fov_max - spec.fov_min)
            for gene in self.sensors.values():
                if gene.type == kind:
                    gene.range += d_range
                    gene.fov += d_fov
                    gene.clamp()
        free = [s for s in range(config.num_inputs) if s not in self.sensors]
        if free and random.random() < config.sensor_add_prob:
            self.sensors[random.choice(free)] = random_sensor(types)
        if self.sensors and random.random() < config.sensor_remove_prob:
            del self.sensors[random.choice(sorted(self.sensors))]
        self.sensors = dict(sorted(self.sensors.items()))

    def distance(self, other: Any, config: Any) -> float:
        d = super().distance(other, config)
        slots = set(self.sensors) | set(other.sensors)
        if not slots:
            return d
        total = sum(self.sensors[s].distance(other.sensors[s]) if s in self.sensors and s in other.sensors else 1.0
                    for s in slots)
        return d + config.sensor_compatibility_coefficient * total / len(slots)


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
