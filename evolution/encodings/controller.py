"""The team controller: one feed-forward network evaluated for all robots at once.

A homogeneous team shares one network, so a step is a matrix product over the team:
``(N, S)`` readings in, ``(N, 2)`` wheel commands out. The network is stored as *layers*;
each layer computes ``act(bias + response * (Z @ W.T))`` for its nodes, where ``Z`` holds the
sensor readings followed by the values of the nodes computed so far, so any feed-forward DAG
(the HyperNEAT-M substrate, with or without hidden ring, or a NEAT-M network) runs as one
matrix product per layer. There is no recurrence: each step is one fresh activation pass.

The two output nodes give the left and right wheel: ``wheel = 2 * output - 1``; with the
HyperNEAT-M default output activation ``steep_sigmoid`` = ``1 / (1 + exp(-4.924273 (x -
2.4621365)))`` the outputs lie in (0, 1), so wheels lie in (-1, 1).

**The same numbers on other machines.** A layer runs as one compiled loop (``_layer``): each
node's weighted sum is added up input by input in column order, without fused multiply-adds,
and the activation calls the C library's ``exp``, ``tanh``, ... on one value at a time. So the
result depends on neither the BLAS kernel nor numpy's SIMD code (only, like every kernel, on the
C library's functions: docs/guarantees.md). numpy's
matrix product would not do: BLAS picks a kernel per processor (with or without FMA), and
numpy's ``exp`` and ``tanh`` take processor-specific SIMD code (AVX-512 or not); a team's
commands then differ in the last bit between machines, and over a 10 000-step episode the
physics turns that into another episode (measured: one champion's training episode scored
110.44, 105.73 or 90.00 by the BLAS kernel and numpy's SIMD set of the machine that ran it).
Each activation's formula is written once, as a scalar function (``activate``); the compiled
loop and the tests' plain-Python reference (``activate.py_func``) both run that function.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit

FORMAT = "team-controller"

#: The activation functions a controller node may use: neat-python's (same scaling and
#: clamping) plus ``steep_sigmoid``; a node stores its name, the compiled loop its index here.
ACTIVATION_NAMES = ("steep_sigmoid", "sigmoid", "tanh", "sin", "gauss", "relu", "identity", "clamped", "abs",
                    "hat", "square", "cube", "softplus", "exp", "elu", "lelu")
ACTIVATIONS = {name: code for code, name in enumerate(ACTIVATION_NAMES)}


@njit(cache=True)
def _clip(x: float, low: float, high: float) -> float:
    return low if x < low else high if x > high else x


@njit(cache=True)
def activate(code: int, z: float) -> float:  # noqa: C901 - one branch per function
    """Activation ``ACTIVATION_NAMES[code]`` of one value (scalar IEEE operations and C-library
    calls only, so it does not depend on numpy's SIMD code)."""
    if code == 0:
        return 1.0 / (1.0 + math.exp(-4.924273 * _clip(z - 2.4621365, -30.0, 30.0)))
    if code == 1:
        return 1.0 / (1.0 + math.exp(-_clip(5.0 * z, -60.0, 60.0)))
    if code == 2:
        return math.tanh(_clip(2.5 * z, -60.0, 60.0))
    if code == 3:
        return math.sin(_clip(5.0 * z, -60.0, 60.0))
    if code == 4:
        c = _clip(z, -3.4, 3.4)
        return math.exp(-5.0 * (c * c))
    if code == 5:
        return z if z > 0.0 else 0.0
    if code == 6:
        return z
    if code == 7:
        return _clip(z, -1.0, 1.0)
    if code == 8:
        return abs(z)
    if code == 9:
        return max(0.0, 1.0 - abs(z))
    if code == 10:
        return z * z
    if code == 11:
        return z * z * z
    if code == 12:
        return 0.2 * math.log1p(math.exp(_clip(5.0 * z, -60.0, 60.0)))
    if code == 13:
        return math.exp(_clip(z, -60.0, 60.0))
    if code == 14:
        return z if z > 0.0 else math.expm1(z)
    return z if z > 0.0 else 0.005 * z


@njit(cache=True)
def _layer(z, weights, bias, response, codes, out):
    """out[i, l] = activate(codes[l], bias[l] + response[l] * sum_k z[i, k] * weights[l, k]),
    the sum taken in column order."""
    for i in range(z.shape[0]):
        for node in range(weights.shape[0]):
            total = 0.0
            for k in range(weights.shape[1]):
                total += z[i, k] * weights[node, k]
            out[i, node] = activate(codes[node], bias[node] + response[node] * total)


@dataclass
class Layer:
    """Nodes computed together. ``targets``: their columns in Z; ``weights``: (L, width of Z)."""

    targets: np.ndarray
    weights: np.ndarray
    bias: np.ndarray
    response: np.ndarray
    activation: list[str]

    def __post_init__(self) -> None:
        self.targets = np.asarray(self.targets, dtype=np.intp)
        self.weights = np.asarray(self.weights, dtype=float)
        self.bias = np.asarray(self.bias, dtype=float)
        self.response = np.asarray(self.response, dtype=float)
        bad = [a for a in self.activation if a not in ACTIVATIONS]
        if bad:
            raise ValueError(f"unknown activation(s) {bad}; allowed: {sorted(ACTIVATIONS)}")
        n = len(self.targets)
        if self.weights.ndim != 2 or self.weights.shape[0] != n or self.bias.shape != (n,) \
                or self.response.shape != (n,) or len(self.activation) != n:
            raise ValueError(f"layer arrays disagree: {n} targets, weights {self.weights.shape}, "
                             f"bias {self.bias.shape}, response {self.response.shape}")
        if not (np.isfinite(self.weights).all() and np.isfinite(self.bias).all() and np.isfinite(self.response).all()):
            raise ValueError("layer weights, bias and response must be finite")
        self._codes = np.array([ACTIVATIONS[name] for name in self.activation], dtype=np.int64)

    def apply(self, z: np.ndarray) -> np.ndarray:
        """(N, L) node values from the (N, width) state (only the first ``width`` columns are read)."""
        out = np.empty((z.shape[0], len(self.targets)))
        _layer(np.ascontiguousarray(z, dtype=float), self.weights, self.bias, self.response, self._codes, out)
        return out


MAX_NODES = 100_000
"""Most computed nodes a controller may have (a bound for files read from disk)."""


class TeamController:
    """A feed-forward network over ``num_inputs`` sensor readings driving two wheels.

    Args:
        num_inputs: S, the number of sensors (observation width).
        num_nodes: computed nodes (hidden + 2 outputs); Z has S + num_nodes columns.
        layers: evaluated in order. outputs: the two Z columns of (left, right) wheel outputs.
    """

    def __init__(self, num_inputs: int, num_nodes: int, layers: Sequence[Layer], outputs: Sequence[int]) -> None:
        self.num_inputs = int(num_inputs)
        self.num_nodes = int(num_nodes)
        self.layers = list(layers)
        self.outputs = np.asarray(outputs, dtype=np.intp)
        if self.outputs.shape != (2,):
            raise ValueError(f"a team controller has 2 outputs (left, right wheel); got {self.outputs.tolist()}")
        width = self.num_inputs + self.num_nodes
        if not (0 <= self.num_inputs and 0 <= self.num_nodes <= MAX_NODES):
            raise ValueError(f"num_inputs={self.num_inputs}, num_nodes={self.num_nodes}; allowed: >= 0 and "
                             f"num_nodes <= {MAX_NODES}")
        if ((self.outputs < self.num_inputs) | (self.outputs >= width)).any():
            raise ValueError(f"outputs {self.outputs.tolist()} are not computed nodes; allowed: "
                             f"{self.num_inputs}..{width - 1}")
        for layer in self.layers:
            if layer.weights.shape[1] > width or (layer.targets < self.num_inputs).any() or (layer.targets >= width).any():
                raise ValueError("layer targets/weights do not fit the controller's inputs and nodes")
        # Fast path: one layer computing exactly the two outputs from the inputs.
        only = self.layers[0] if len(self.layers) == 1 else None
        self._direct = (only is not None and only.weights.shape[1] <= self.num_inputs
                        and list(only.targets) == list(self.outputs))

    @classmethod
    def single_layer(cls, weights: np.ndarray, bias: np.ndarray, activation: str = "steep_sigmoid") -> TeamController:
        """Inputs wired straight to the two outputs: ``weights`` (2, S), ``bias`` (2,)."""
        weights = np.asarray(weights, dtype=float)
        weights = weights.reshape(2, weights.size // 2)
        s = weights.shape[1]
        layer = Layer(targets=[s, s + 1], weights=weights, bias=bias, response=np.ones(2), activation=[activation] * 2)
        return cls(s, 2, [layer], [s, s + 1])

    @property
    def num_links(self) -> int:
        """Number of non-zero connection weights (the controller-complexity measure)."""
        return int(sum(np.count_nonzero(layer.weights) for layer in self.layers))

    def act(self, observations: np.ndarray) -> np.ndarray:
        """Wheel commands (N, 2) in [-1, 1] for readings (N, S)."""
        obs = np.asarray(observations, dtype=float)
        if obs.ndim != 2 or obs.shape[1] != self.num_inputs:
            raise ValueError(f"observations have shape {obs.shape}; this controller expects (N, {self.num_inputs})")
        if self._direct:
            out = self.layers[0].apply(obs)
        else:
            z = np.zeros((obs.shape[0], self.num_inputs + self.num_nodes))
            z[:, : self.num_inputs] = obs
            for layer in self.layers:
                z[:, layer.targets] = layer.apply(z)
            out = z[:, self.outputs]
        return 2.0 * out - 1.0

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe description (weights as nested lists)."""
        return {
            "format": FORMAT,
            "num_inputs": self.num_inputs,
            "num_nodes": self.num_nodes,
            "outputs": self.outputs.tolist(),
            "layers": [{
                "targets": layer.targets.tolist(), "weights": layer.weights.tolist(),
                "bias": layer.bias.tolist(), "response": layer.response.tolist(),
                "activation": list(layer.activation),
            } for layer in self.layers],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TeamController:
        """Inverse of ``to_dict``; raises ``ValueError``/``KeyError`` on malformed data."""
        if data.get("format") != FORMAT:
            raise ValueError(f"controller 'format' must be {FORMAT!r}")
        layers = []
        for item in data["layers"]:
            weights = np.asarray(item["weights"], dtype=float)
            if weights.size == 0:
                weights = weights.reshape(len(item["targets"]), 0)
            layers.append(Layer(item["targets"], weights, item["bias"], item["response"], list(item["activation"])))
        return cls(int(data["num_inputs"]), int(data["num_nodes"]), layers, data["outputs"])
