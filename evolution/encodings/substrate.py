"""HyperNEAT-M: the substrate and the decoding of a CPPN into a controller and a morphology.

Substrate (docs/model.md §5, paper Figure 3): ``num_inputs`` = 10 input nodes on a circle of
radius 1.5 at angles 0, 0.65, 1.30, ... (all < 2 pi), the robot's body seen from above with
its heading along +x; two output nodes, left wheel at (-0.5, -1.875) and right wheel at
(0.5, -1.875). Every input may link to every output. Optionally (``hidden_nodes`` > 0) a
hidden ring of radius ``hidden_radius`` at angles evenly spaced from 0: inputs then link to
hidden nodes (tanh) and hidden nodes to outputs, and the direct input -> output links stay.

The CPPN (a neat-python genome with inputs x1, y1, x2, y2 and outputs **weight, fov,
orientation, range, type, bias-weight**) is queried for each potential link (source,
target); every output is clipped to [-1, 1]. Decoding:

* a link exists when |w| > ``weight_threshold`` (0.2); its weight is
  ``sign(w) (|w| - 0.2) * max_weight / (1 - 0.2)`` (max_weight = 5);
* a node's bias is the bias-weight output queried at (0, 0, x_target, y_target), times
  ``max_weight`` (docs/model.md §5: not thresholded); with ``bias_threshold`` (the original's choice)
  it goes through the same threshold and rescaling as a link weight, so |b| <= 0.2 gives 0;
* each input node's **sensor** comes from its outgoing link with the highest *signed* CPPN
  weight: type from the ``type`` output split into ``len(sensor_types)`` equal bands over
  [-1, 1] (infrared, ultrasonic, camera, colour: the original's order); fov and range mapped linearly from
  [-1, 1] onto the type's bounds (range onto [``range_floor`` * max, max] since 0 is
  excluded), orientation onto [-pi/2, pi/2]; bearing = atan2(y, x) of the input node
  (``bearings = "atan"``: the original's atan(y / x), which puts every sensor on the front half
  of the body, a node behind it at its angle minus pi);
* ``decode_window`` (default 1): the share of each interval (range, FOV, orientation) the
  outputs reach, centred on its middle; the original code reached only the middle 0.2 (its
  Encog ``NormalizedField`` mapped [-1, 1] as if from [-5, 5]);
* an input node with no outgoing link has **no sensor** and no controller input;
* ``bottom_on_node0`` (default on, as in the original): input node 0 (the front of the
  robot) always carries a bottom sensor instead of a configurable one, whatever its links.

The morphology lists the sensors by input-node index; the controller's input columns follow
the same order. Decoding queries the CPPN (10 x 2 + 2 times without a hidden ring) through
``neat.nn.FeedForwardNetwork``: a Python loop of a few dozen calls, once per genome.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import neat
import numpy as np

from evolution.encodings.controller import Layer, TeamController
from gathering_env import SENSOR_TYPES, Morphology, SensorSpec

CPPN_OUTPUTS = ("weight", "fov", "orientation", "range", "type", "bias")
W, FOV, ORIENT, RANGE, TYPE, BIAS = range(6)


@dataclass(frozen=True)
class Substrate:
    """Geometry and decoding parameters of the HyperNEAT-M substrate (see module docstring)."""

    num_inputs: int = 10
    input_radius: float = 1.5
    angle_step: float = 0.65
    outputs: tuple[tuple[float, float], tuple[float, float]] = ((-0.5, -1.875), (0.5, -1.875))
    weight_threshold: float = 0.2
    max_weight: float = 5.0
    bottom_on_node0: bool = True
    sensor_types: tuple[str, ...] = ("infrared", "ultrasonic", "camera", "colour")  # the original's order
    hidden_nodes: int = 0
    hidden_radius: float = 0.75
    range_floor: float = 0.001
    output_activation: str = "steep_sigmoid"
    hidden_activation: str = "tanh"
    bias_threshold: bool = False
    decode_window: float = 1.0
    bearings: str = "atan2"

    def __post_init__(self) -> None:
        if not 1 <= self.num_inputs <= 10:
            raise ValueError(f"substrate num_inputs={self.num_inputs}; allowed: 1..10 (a morphology has <= 10 sensors)")
        if (self.num_inputs - 1) * self.angle_step >= 2 * math.pi:
            raise ValueError(f"substrate: {self.num_inputs} inputs at angle_step {self.angle_step} wrap past a full circle")
        if not 0.0 <= self.weight_threshold < 1.0:
            raise ValueError(f"substrate weight_threshold={self.weight_threshold}; allowed: [0, 1)")
        if self.max_weight <= 0:
            raise ValueError(f"substrate max_weight={self.max_weight}; allowed: > 0")
        bad = [t for t in self.sensor_types if t not in SENSOR_TYPES or not SENSOR_TYPES[t].configurable]
        if bad or not self.sensor_types:
            allowed = [t for t, s in SENSOR_TYPES.items() if s.configurable]
            raise ValueError(f"substrate sensor_types={list(self.sensor_types)}; allowed: a non-empty list of {allowed}")
        if self.hidden_nodes < 0:
            raise ValueError(f"substrate hidden_nodes={self.hidden_nodes}; allowed: >= 0")
        if not 0.0 < self.decode_window <= 1.0:
            raise ValueError(f"substrate decode_window={self.decode_window}; allowed: (0, 1]")
        if not 0.0 < self.range_floor < 1.0:
            raise ValueError(f"substrate range_floor={self.range_floor}; allowed: (0, 1)")
        if self.bearings not in BEARING_RULES:
            raise ValueError(f"substrate bearings={self.bearings!r}; allowed: {', '.join(BEARING_RULES)}")

    def input_positions(self) -> np.ndarray:
        """(num_inputs, 2) input node coordinates."""
        angles = self.angle_step * np.arange(self.num_inputs)
        return self.input_radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)

    def hidden_positions(self) -> np.ndarray:
        """(hidden_nodes, 2) hidden ring coordinates (empty without a hidden ring)."""
        angles = 2 * math.pi * np.arange(self.hidden_nodes) / max(self.hidden_nodes, 1)
        return self.hidden_radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)

    def output_positions(self) -> np.ndarray:
        return np.asarray(self.outputs, dtype=float)

    def scale_weight(self, w: np.ndarray) -> np.ndarray:
        """CPPN weight -> link weight (0 where |w| <= threshold)."""
        w = np.asarray(w, dtype=float)
        t = self.weight_threshold
        return np.where(np.abs(w) > t, np.sign(w) * (np.abs(w) - t) * self.max_weight / (1.0 - t), 0.0)

    def sensor_from_outputs(self, outputs: np.ndarray, bearing: float) -> SensorSpec:
        """Sensor of an input node from the CPPN outputs of its strongest link."""
        o = np.clip(np.asarray(outputs, dtype=float), -1.0, 1.0)
        bands = len(self.sensor_types)
        kind = self.sensor_types[min(int((o[TYPE] + 1.0) / 2.0 * bands), bands - 1)]
        spec = SENSOR_TYPES[kind]
        window = self.decode_window
        unit = lambda v: (window * v + 1.0) / 2.0  # noqa: E731 - [-1, 1] -> the window of [0, 1]
        low = self.range_floor * spec.range_max
        return SensorSpec(
            kind,
            bearing=bearing,
            orientation=float(window * o[ORIENT] * math.pi / 2),
            range=float(low + unit(o[RANGE]) * (spec.range_max - low)),
            fov=float(spec.fov_min + unit(o[FOV]) * (spec.fov_max - spec.fov_min)),
        )


BEARING_RULES = ("atan2", "atan")


def _bearing(x: float, y: float, rule: str = "atan2") -> float:
    """A sensor's bearing from its input node's position: ``atan2`` (all round the body, in
    [-pi, pi)) or the original's ``atan`` of y / x, which folds every node into the front half,
    [-pi/2, pi/2] (a node at angle theta behind the body lands at theta - pi)."""
    if rule == "atan":
        return math.atan(y / x) if x != 0.0 else math.copysign(math.pi / 2, y)
    b = math.atan2(y, x)
    return -math.pi if b >= math.pi else b


def query(net: Any, source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """CPPN outputs (6,) for the link source -> target, clipped to [-1, 1]."""
    out = net.activate([float(source[0]), float(source[1]), float(target[0]), float(target[1])])
    if len(out) != len(CPPN_OUTPUTS):
        raise ValueError(f"the CPPN has {len(out)} outputs; HyperNEAT-M needs {len(CPPN_OUTPUTS)}: {CPPN_OUTPUTS}")
    return np.clip(np.nan_to_num(np.asarray(out, dtype=float), nan=0.0), -1.0, 1.0)


def decode(genome: Any, config: Any, substrate: Substrate | None = None) -> tuple[TeamController, Morphology]:
    """Decode a HyperNEAT-M CPPN genome into the team controller and the sensor morphology."""
    sub = substrate or Substrate()
    net = neat.nn.FeedForwardNetwork.create(genome, config)
    inputs, hidden, outputs = sub.input_positions(), sub.hidden_positions(), sub.output_positions()
    targets = np.vstack([hidden, outputs])  # every input links to hidden nodes and outputs
    origin = np.zeros(2)

    # CPPN outputs for every input -> target link: (num_inputs, T, 6)
    q_in = np.array([[query(net, p, t) for t in targets] for p in inputs]).reshape(len(inputs), len(targets), 6)
    w_in = sub.scale_weight(q_in[:, :, W])                               # (I, T)
    q_hid = np.array([[query(net, h, o) for o in outputs] for h in hidden]).reshape(len(hidden), 2, 6)
    w_hid = sub.scale_weight(q_hid[:, :, W]) if len(hidden) else np.zeros((0, 2))
    bias_out = np.array([query(net, origin, t)[BIAS] for t in targets])
    bias = sub.scale_weight(bias_out) if sub.bias_threshold else bias_out * sub.max_weight

    sensors: list[SensorSpec] = []
    used: list[int] = []
    for i, (x, y) in enumerate(inputs):
        linked = np.flatnonzero(w_in[i] != 0.0)
        if sub.bottom_on_node0 and i == 0:
            sensors.append(SensorSpec("bottom"))
            used.append(i)
            continue
        if linked.size == 0:
            continue  # no link, no sensor
        strongest = linked[np.argmax(q_in[i, linked, W])]
        sensors.append(sub.sensor_from_outputs(q_in[i, strongest], _bearing(x, y, sub.bearings)))
        used.append(i)

    s = len(used)
    h = len(hidden)
    w_used = w_in[used]                                   # (S, H + 2)
    if h == 0:
        controller = TeamController.single_layer(w_used[:, h:].T, bias[h:], sub.output_activation)
    else:
        # Z columns: S inputs, H hidden, 2 outputs.
        hidden_layer = Layer(np.arange(s, s + h), w_used[:, :h].T, bias[:h], np.ones(h), [sub.hidden_activation] * h)
        out_weights = np.hstack([w_used[:, h:].T, w_hid.T])  # (2, S + H)
        out_layer = Layer([s + h, s + h + 1], out_weights, bias[h:], np.ones(2), [sub.output_activation] * 2)
        controller = TeamController(s, h + 2, [hidden_layer, out_layer], [s + h, s + h + 1])
    return controller, Morphology(sensors)
