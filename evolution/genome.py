"""The HyperNEAT-M CPPN genome on neat-python.

``CPPNGenome`` is a ``neat.DefaultGenome`` whose config section (``[CPPNGenome]``) must declare
4 inputs (x1, y1, x2, y2 of the two substrate nodes; neat-python gives every node its own
bias, so no explicit bias input is needed) and 6 outputs (weight, fov, orientation, range,
type, bias-weight, in that order; see ``evolution.substrate``). Everything else (activation
set, mutation rates, initial connection density) comes from the config file through
neat-python's documented ``parse_config`` mechanism; unknown keys in the section are an error.
"""

from __future__ import annotations

from typing import Any

import neat

from .substrate import CPPN_OUTPUTS

CPPN_INPUTS = ("x1", "y1", "x2", "y2")


def check_genome_section(config: Any, param_dict: dict[str, str], section: str, extra: set[str] = frozenset()) -> None:
    """Raise ``ValueError`` for keys of a genome section that neat-python would silently ignore."""
    known = {p.name for p in config._params} | set(extra) | {"node_gene_type", "connection_gene_type"}
    unknown = sorted(set(param_dict) - known)
    if unknown:
        raise ValueError(f"[{section}] unknown key(s) {unknown}")


class CPPNGenome(neat.DefaultGenome):
    """A CPPN for HyperNEAT-M: 4 coordinate inputs, 6 outputs (``CPPN_OUTPUTS``)."""

    @classmethod
    def parse_config(cls, param_dict: dict[str, str]) -> neat.genome.DefaultGenomeConfig:
        config = super().parse_config(param_dict)
        check_genome_section(config, param_dict, cls.__name__)
        if config.num_inputs != len(CPPN_INPUTS):
            raise ValueError(f"[{cls.__name__}] num_inputs={config.num_inputs}; HyperNEAT-M needs "
                             f"{len(CPPN_INPUTS)} {CPPN_INPUTS}")
        if config.num_outputs != len(CPPN_OUTPUTS):
            raise ValueError(f"[{cls.__name__}] num_outputs={config.num_outputs}; HyperNEAT-M needs "
                             f"{len(CPPN_OUTPUTS)} {CPPN_OUTPUTS}")
        return config
