"""The HyperNEAT-M CPPN genome on neat-python.

``CPPNGenome`` is a ``neat.DefaultGenome`` (through ``evolution.reproduction.operators.BreedingGenome``)
whose config section (``[CPPNGenome]``) must declare 4 inputs (x1, y1, x2, y2 of the two
substrate nodes; neat-python gives every node its own bias, so no explicit bias input is
needed) and 6 outputs (weight, fov, orientation, range, type, bias-weight, in that order;
see ``evolution.encodings.substrate``). Everything else (activation set, mutation rates, initial
connection density, the breeding keys of ``evolution.reproduction.breeding``) comes from the config file
through neat-python's ``parse_config``; unknown keys in the section are an error.

**Output activations.** The decoding maps [-1, 1] onto sensor-type bands, parameter ranges
and signed weights, so the CPPN's *output* nodes must be able to produce the whole of
[-1, 1] (the original: a clipped linear function, neat-python's ``clamped``); hidden nodes
draw from the section's ``activation_options`` as usual. Extra key::

    output_activation = clamped      # one name for all 6 outputs, or 6 names in output order;
                                     # 'random': outputs draw from activation_options like
                                     # hidden nodes (unsigned functions then bias the decoding)

A named output activation must take negative and positive values (sigmoid, gauss, abs or
relu are refused); it is set on new genomes and restored after every mutation.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from evolution.encodings.substrate import CPPN_OUTPUTS
from evolution.reproduction.operators import BreedingGenome

CPPN_INPUTS = ("x1", "y1", "x2", "y2")


def is_signed(function: Any) -> bool:
    """True if an activation function takes both negative and positive values on [-5, 5]."""
    values = [function(float(z)) for z in np.linspace(-5.0, 5.0, 41)]
    return min(values) < 0.0 < max(values)


class CPPNGenome(BreedingGenome):
    """A CPPN for HyperNEAT-M: 4 coordinate inputs, 6 outputs (``CPPN_OUTPUTS``)."""

    EXTRA_PARAMS = (*BreedingGenome.EXTRA_PARAMS, ("output_activation", str, "clamped"))

    @classmethod
    def validate_config(cls, config: Any, section: str) -> None:
        super().validate_config(config, section)
        if config.num_inputs != len(CPPN_INPUTS):
            raise ValueError(f"[{section}] num_inputs={config.num_inputs}; HyperNEAT-M needs "
                             f"{len(CPPN_INPUTS)} {CPPN_INPUTS}")
        if config.num_outputs != len(CPPN_OUTPUTS):
            raise ValueError(f"[{section}] num_outputs={config.num_outputs}; HyperNEAT-M needs "
                             f"{len(CPPN_OUTPUTS)} {CPPN_OUTPUTS}")
        names = config.output_activation.split()
        if names == ["random"]:
            config.output_activations = None
            return
        if len(names) == 1:
            names = names * len(CPPN_OUTPUTS)
        where = f"[{section}] output_activation={config.output_activation!r}"
        if len(names) != len(CPPN_OUTPUTS):
            raise ValueError(f"{where}; allowed: 'random', one name, or {len(CPPN_OUTPUTS)} names {CPPN_OUTPUTS}")
        for name in names:
            if not config.activation_defs.is_valid(name):
                raise ValueError(f"{where}: unknown activation {name!r}")
            if not is_signed(config.activation_defs.get(name)):
                raise ValueError(f"{where}: {name!r} never goes negative; allowed: a signed function "
                                 "such as clamped, tanh, sin or identity")
        config.output_activations = dict(zip(config.output_keys, names))

    def pin_output_activations(self, config: Any) -> None:
        """Give every output node its configured activation (no-op for 'random')."""
        for key, name in (config.output_activations or {}).items():
            self.nodes[key].activation = name

    def configure_new(self, config: Any) -> None:
        super().configure_new(config)
        self.pin_output_activations(config)

    def mutate(self, config: Any) -> None:
        super().mutate(config)
        self.pin_output_activations(config)
