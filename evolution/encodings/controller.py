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
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

FORMAT = "team-controller"


def _steep_sigmoid(x: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-4.924273 * np.clip(x - 2.4621365, -30.0, 30.0)))


# numpy versions of neat-python's activation functions (same clamping), plus steep_sigmoid.
ACTIVATIONS = {
    "steep_sigmoid": _steep_sigmoid,
    "sigmoid": lambda z: 1.0 / (1.0 + np.exp(-np.clip(5.0 * z, -60.0, 60.0))),
    "tanh": lambda z: np.tanh(np.clip(2.5 * z, -60.0, 60.0)),
    "sin": lambda z: np.sin(np.clip(5.0 * z, -60.0, 60.0)),
    "gauss": lambda z: np.exp(-5.0 * np.clip(z, -3.4, 3.4) ** 2),
    "relu": lambda z: np.maximum(z, 0.0),
    "identity": lambda z: z,
    "clamped": lambda z: np.clip(z, -1.0, 1.0),
    "abs": np.abs,
    "hat": lambda z: np.maximum(0.0, 1.0 - np.abs(z)),
    "square": np.square,
    "cube": lambda z: z ** 3,
    "softplus": lambda z: 0.2 * np.log1p(np.exp(np.clip(5.0 * z, -60.0, 60.0))),
    "exp": lambda z: np.exp(np.clip(z, -60.0, 60.0)),
    "elu": lambda z: np.where(z > 0.0, z, np.expm1(np.minimum(z, 0.0))),
    "lelu": lambda z: np.where(z > 0.0, z, 0.005 * z),
}


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
        groups: dict[str, list[int]] = {}
        for i, name in enumerate(self.activation):
            groups.setdefault(name, []).append(i)
        self._groups = [(ACTIVATIONS[name], np.array(idx)) for name, idx in groups.items()]
        self._single = self._groups[0][0] if len(self._groups) == 1 else None

    def apply(self, z: np.ndarray) -> np.ndarray:
        """(N, L) node values from the (N, width) state (only the first ``width`` columns are read)."""
        pre = self.bias + self.response * (z[:, : self.weights.shape[1]] @ self.weights.T)
        if self._single is not None:
            return self._single(pre)
        out = np.empty_like(pre)
        for fn, idx in self._groups:
            out[:, idx] = fn(pre[:, idx])
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
