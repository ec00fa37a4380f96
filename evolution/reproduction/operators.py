"""The genome class that knows its variation operators, and its config keys.

``BreedingGenome`` is the ``neat.DefaultGenome`` both encodings extend (``CPPNGenome``,
``NEATMGenome``); ``evolution.reproduction.breeding.breed`` draws one of its operators per
offspring. The probabilities live in the genome's config section (they differ between HyperNEAT-M and
NEAT-M, and a genome class knows its operators)::

    variation          = one_operator   # or neat_python: crossover with crossover_prob, then
                                        # neat-python's mutate() with its per-gene rates
    parent_fraction    = 0.3            # truncation: the best 30 % of a species breed
    crossover_prob     = 0.5            # HyperNEAT-M 0.5, NEAT-M 0.32
    weight_mutate_prob = 0.494          # HyperNEAT-M 0.494, NEAT-M 0.335
    weight_reset_prob  = 0.1            # share of weight operations that reset instead of perturb
    node_add_prob, conn_add_prob, conn_delete_prob, node_delete_prob   # neat-python's keys

neat-python's keys ``node_add_prob`` ... are per-offspring probabilities in neat-python too,
so with ``variation = one_operator`` they are the structural operators' probabilities.
The weight operator is the original's: perturb (Gaussian, ``weight_mutate_power`` /
``bias_mutate_power``, clamped) or, with ``weight_reset_prob``, re-initialise 1, 2 or 3
links or 2 % of them (each of the four choices equally likely); a node's bias counts as a
link from the bias input, as in the original where the bias is a neuron.
"""

from __future__ import annotations

import random
from typing import Any

import neat
from neat.config import ConfigParameter

from evolution.reproduction.encog import ENCOG_WEIGHT_OPERATIONS

VARIATIONS = ("one_operator", "neat_python")
WEIGHT_LINK_CHOICES = (1, 2, 3, 0.02)  # links perturbed or reset by one weight operation


def add_parameters(config: Any, param_dict: dict[str, str], params: list[ConfigParameter], section: str) -> None:
    """Interpret extra genome keys with neat-python's ``ConfigParameter`` and register them."""
    for p in params:
        try:
            setattr(config, p.name, p.interpret(param_dict, section))
        except RuntimeError as err:
            raise ValueError(f"[{section}] {err}") from None
    config._params.extend(params)


def check_genome_section(config: Any, param_dict: dict[str, str], section: str) -> None:
    """Raise ``ValueError`` for keys of a genome section that neat-python would silently ignore."""
    known = {p.name for p in config._params} | {"node_gene_type", "connection_gene_type"}
    unknown = sorted(set(param_dict) - known)
    if unknown:
        raise ValueError(f"[{section}] unknown key(s) {unknown}")


def check_probability(section: str, name: str, value: float) -> None:
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"[{section}] {name}={value}; allowed: [0, 1]")


class BreedingGenome(neat.DefaultGenome):
    """A ``neat.DefaultGenome`` that knows its variation operators (see module docstring)."""

    EXTRA_PARAMS: tuple[tuple[str, type, Any], ...] = (
        ("variation", str, "one_operator"),
        ("parent_fraction", float, None),
        ("crossover_prob", float, None),
        ("weight_mutate_prob", float, None),
        ("weight_reset_prob", float, 0.1),
    )
    """Keys of the genome section beyond neat-python's: (name, type, default or None if required)."""

    @classmethod
    def parse_config(cls, param_dict: dict[str, str]) -> neat.genome.DefaultGenomeConfig:
        config = super().parse_config(param_dict)
        section = cls.__name__
        add_parameters(config, param_dict, [ConfigParameter(*p) for p in cls.EXTRA_PARAMS], section)
        check_genome_section(config, param_dict, section)
        cls.validate_config(config, section)
        return config

    @classmethod
    def validate_config(cls, config: Any, section: str) -> None:
        """Check the extra keys (subclasses extend this); raise ``ValueError`` naming the key."""
        if config.variation not in VARIATIONS:
            raise ValueError(f"[{section}] variation={config.variation!r}; allowed: {list(VARIATIONS)}")
        if not 0.0 < config.parent_fraction <= 1.0:
            raise ValueError(f"[{section}] parent_fraction={config.parent_fraction}; allowed: (0, 1]")
        for name in ("crossover_prob", "weight_mutate_prob", "weight_reset_prob"):
            check_probability(section, name, getattr(config, name))
        if config.variation == "one_operator" and sum(p for _, p in cls.operators(config)) <= 0:
            raise ValueError(f"[{section}] every operator probability is 0; allowed: at least one > 0")

    @classmethod
    def operators(cls, config: Any) -> list[tuple[str, float]]:
        """(operator, probability) of one offspring, crossover first."""
        return [("crossover", config.crossover_prob), ("weights", config.weight_mutate_prob),
                ("add_node", config.node_add_prob), ("remove_node", config.node_delete_prob),
                ("add_link", config.conn_add_prob), ("remove_link", config.conn_delete_prob)]

    def apply_operator(self, name: str, config: Any) -> None:
        """Apply one mutation operator (any name of ``operators`` except crossover)."""
        if name == "weights":
            self.mutate_weights(config)
        elif name == "add_node":
            self.mutate_add_node(config)
        elif name == "remove_node":
            self.mutate_delete_node(config)
        elif name == "add_link":
            self.mutate_add_connection(config)
        elif name == "remove_link":
            self.mutate_delete_connection()
        else:
            raise ValueError(f"unknown variation operator {name!r}")

    def mutate_weights(self, config: Any) -> None:
        """Perturb or reset 1, 2, 3 or 2 % of the links (enabled connections and node biases);
        with Encog's weights (``evolution.reproduction.encog.use_encog_weights``) one of its
        weight operations."""
        links = [(g, "weight") for _, g in sorted(self.connections.items()) if g.enabled]
        links += [(g, "bias") for _, g in sorted(self.nodes.items())]
        if not links:
            return
        sigmas = getattr(config, "encog_sigmas", None)
        if sigmas is not None:
            self._mutate_weights_encog(links, sigmas, config)
            return
        pick = random.choice(WEIGHT_LINK_CHOICES)
        k = pick if isinstance(pick, int) else max(1, round(pick * len(links)))
        reset = random.random() < config.weight_reset_prob
        for gene, name in random.sample(links, min(k, len(links))):
            attribute = next(a for a in gene._gene_attributes if a.name == name)
            if reset:
                value = attribute.init_value(config)
            else:
                power = getattr(config, attribute.mutate_power_name)
                value = attribute.clamp(getattr(gene, name) + random.gauss(0.0, power), config)
            setattr(gene, name, value)

    @staticmethod
    def _mutate_weights_encog(links: list[tuple[Any, str]], sigmas: tuple[float, float], config: Any) -> None:
        """One of Encog's weight operations (``ENCOG_WEIGHT_OPERATIONS``) on ``links``."""
        count, sigma, _ = random.choices(ENCOG_WEIGHT_OPERATIONS, [w for *_, w in ENCOG_WEIGHT_OPERATIONS])[0]
        if isinstance(count, int):
            chosen = random.sample(links, min(count, len(links)))
        else:  # each link with probability count, one at random if none was drawn
            chosen = [link for link in links if random.random() < count] or [random.choice(links)]
        for gene, name in chosen:
            attribute = next(a for a in gene._gene_attributes if a.name == name)
            if sigma is None:
                value = attribute.init_value(config)  # uniform in the range (use_encog_weights)
            else:
                value = attribute.clamp(getattr(gene, name) + random.gauss(0.0, sigmas[sigma]), config)
            setattr(gene, name, value)
