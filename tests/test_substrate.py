"""HyperNEAT-M decoding with hand-built CPPNs whose outputs are known in closed form."""

from __future__ import annotations

import math
from pathlib import Path

import neat
import numpy as np
import pytest
from neat.innovation import InnovationTracker

from evolution.encodings.genome import CPPNGenome
from evolution.encodings.substrate import Substrate, decode
from evolution.reproduction.breeding import NEATReproduction
from evolution.reproduction.species import GatheringSpeciesSet
from gathering_env import SENSOR_TYPES, parallel_env

CFG = Path(__file__).resolve().parent.parent / "configs" / "hyperneat_m.neat.cfg"
X1, Y1, X2, Y2 = -1, -2, -3, -4            # neat-python input keys
WEIGHT, FOV, ORIENT, RANGE, TYPE, BIAS = range(6)


def cppn_config():
    """The shipped HyperNEAT-M neat config, ready to build genomes by hand."""
    cfg = neat.Config(CPPNGenome, NEATReproduction, GatheringSpeciesSet, neat.DefaultStagnation, str(CFG))
    cfg.genome_config.innovation_tracker = InnovationTracker()
    return cfg


@pytest.fixture(scope="module")
def config():
    return cppn_config()


def cppn(config, links: dict[tuple[int, int], float], biases: dict[int, float] | None = None):
    """A CPPN with identity outputs: output_k = bias_k + sum of w * input over ``links``."""
    g = CPPNGenome(1)
    g.configure_new(config.genome_config)
    g.connections.clear()
    for k, node in g.nodes.items():
        node.activation, node.aggregation, node.response = "identity", "sum", 1.0
        node.bias = (biases or {}).get(k, 0.0)
    for (src, dst), w in links.items():
        g.add_connection(config.genome_config, src, dst, w, True)
    return g


def test_weights_threshold_and_scaling(config):
    # weight output = 0.3 * x1: input node at angle a has x1 = 1.5 cos(a).
    genome = cppn(config, {(X1, WEIGHT): 0.3, (X1, TYPE): 0.0}, biases={BIAS: 0.2})
    controller, morph = decode(genome, config, Substrate(bottom_on_node0=False))
    angles = 0.65 * np.arange(10)
    w = 0.3 * 1.5 * np.cos(angles)                      # CPPN weight of node i's links
    linked = np.abs(w) > 0.2
    assert len(morph) == linked.sum()                   # no link -> no sensor
    expected = np.sign(w[linked]) * (np.abs(w[linked]) - 0.2) * 5.0 / 0.8
    layer = controller.layers[0]
    np.testing.assert_allclose(layer.weights[0], expected)   # both outputs get the same weight
    np.testing.assert_allclose(layer.weights[1], expected)
    np.testing.assert_allclose(layer.bias, [0.2 * 5.0, 0.2 * 5.0])  # bias output * max_weight
    # bearings come from the linked nodes' positions (atan2, wrapped into [-pi, pi))
    bearings = [math.atan2(math.sin(a), math.cos(a)) for a in angles[linked]]
    np.testing.assert_allclose([s.bearing for s in morph], bearings)


def test_sensor_type_bands_and_bounds(config):
    # type output = y2 * 0.8: the left output (x2 = -0.5, y2 = -1.875) -> -1.5 -> clipped to -1.
    # weight = 1 everywhere (bias 1), so every input links to both outputs; the strongest is a tie
    # -> the first (left) target. fov/orientation/range = +1 via biases.
    genome = cppn(config, {(Y2, TYPE): 0.8}, biases={WEIGHT: 1.0, FOV: 1.0, ORIENT: 1.0, RANGE: 1.0})
    _, morph = decode(genome, config, Substrate(bottom_on_node0=False))
    assert len(morph) == 10
    for s in morph:
        spec = SENSOR_TYPES["infrared"]                 # band 0 of (infrared, ultrasonic, camera, colour)
        assert s.type == "infrared"
        assert s.range == pytest.approx(spec.range_max)
        assert s.fov == pytest.approx(spec.fov_max)
        assert s.orientation == pytest.approx(math.pi / 2)
    genome = cppn(config, {}, biases={WEIGHT: 1.0, FOV: -1.0, ORIENT: -1.0, RANGE: -1.0, TYPE: 0.99})
    _, morph = decode(genome, config, Substrate(bottom_on_node0=False))
    spec = SENSOR_TYPES["colour"]                      # type 0.99 -> last band
    assert {s.type for s in morph} == {"colour"}
    assert morph[0].fov == pytest.approx(spec.fov_min)
    assert morph[0].orientation == pytest.approx(-math.pi / 2)
    assert morph[0].range == pytest.approx(0.001 * spec.range_max)
    # the original's order along the type output: infrared, ultrasonic, camera, colour
    for value, kind in ((-0.6, "infrared"), (-0.4, "ultrasonic"), (0.1, "camera"), (0.6, "colour")):
        genome = cppn(config, {}, biases={WEIGHT: 1.0, TYPE: value})
        _, morph = decode(genome, config, Substrate(bottom_on_node0=False))
        assert morph[0].type == kind, value


def test_strongest_link_chooses_the_sensor(config):
    # weight = 0.5 + 0.4 * x2: right output (x2 = +0.5) is stronger (0.7 > 0.3);
    # type = 0.7 * x2 -> right: 0.35 -> camera band [0, 0.5); left: -0.35 -> ultrasonic.
    genome = cppn(config, {(X2, WEIGHT): 0.4, (X2, TYPE): 0.7}, biases={WEIGHT: 0.5})
    _, morph = decode(genome, config, Substrate(bottom_on_node0=False))
    assert {s.type for s in morph} == {"camera"}


@pytest.mark.parametrize("slope, kind, fov_sign", [(-1.2, "ultrasonic", -1), (1.2, "camera", 1)])
def test_sensor_comes_from_the_highest_signed_weight_not_the_largest_magnitude(config, slope, kind, fov_sign):
    # weight = -0.3 + slope * x2: with slope -1.2 the left link (x2 = -0.5) has +0.3 and the right
    # (x2 = +0.5) -0.9; both exist (|w| > 0.2) and the signed maximum is the left one, though the
    # right one is larger in magnitude. slope +1.2 mirrors it. type = 0.7 * x2: -0.35 on the left
    # (ultrasonic band), +0.35 on the right (camera); fov = 0.8 * x2 likewise from the same link.
    genome = cppn(config, {(X2, WEIGHT): slope, (X2, TYPE): 0.7, (X2, FOV): 0.8}, biases={WEIGHT: -0.3})
    controller, morph = decode(genome, config, Substrate(bottom_on_node0=False))
    assert len(morph) == 10 and controller.num_links == 20           # every input links to both outputs
    spec = SENSOR_TYPES[kind]
    for s in morph:
        assert s.type == kind
        assert s.fov == pytest.approx(spec.fov_min + (1 + fov_sign * 0.4) / 2 * (spec.fov_max - spec.fov_min))


def test_bottom_sensor_on_node_zero(config):
    genome = cppn(config, {}, biases={WEIGHT: 1.0})
    controller, morph = decode(genome, config, Substrate(bottom_on_node0=True))
    assert morph[0].type == "bottom" and morph[0].bearing == 0.0
    assert len(morph) == 10 and controller.num_inputs == 10
    genome = cppn(config, {}, biases={WEIGHT: 0.0})   # no links at all
    controller, morph = decode(genome, config, Substrate(bottom_on_node0=True))
    assert [s.type for s in morph] == ["bottom"] and controller.num_links == 0


def test_an_unlinked_node_zero_keeps_every_sensor_on_its_own_links(config):
    # weight = 0.5 * y1: node 0 (y1 = 0) gets no link, yet carries the bottom sensor; every other
    # node's sensor reads into that node's own links. (The original's decoder numbered inputs by
    # first link, so there every reading fed the next node's links: not copied, docs/fidelity.md.)
    genome = cppn(config, {(Y1, WEIGHT): 0.5})
    controller, morph = decode(genome, config, Substrate(bottom_on_node0=True))
    y1 = 1.5 * np.sin(0.65 * np.arange(10))
    w = 0.5 * y1
    linked = np.flatnonzero(np.abs(w) > 0.2)
    assert 0 not in linked and len(linked) == 8      # nodes 1-4 and 6-9 (node 5: |w| = 0.08)
    assert morph[0].type == "bottom" and len(morph) == 1 + len(linked)
    expected = np.sign(w[linked]) * (np.abs(w[linked]) - 0.2) * 5.0 / 0.8
    weights = controller.layers[0].weights
    np.testing.assert_allclose(weights[:, 0], [0.0, 0.0])              # the bottom reading: no links
    np.testing.assert_allclose(weights[0, 1:], expected)               # column k: node linked[k - 1]
    np.testing.assert_allclose(weights[1, 1:], expected)
    np.testing.assert_allclose([s.bearing for s in morph[1:]],
                               [math.atan2(y1[i], 1.5 * math.cos(0.65 * i)) for i in linked])


def test_the_originals_atan_bearings_fold_every_sensor_to_the_front(config):
    # bearings = "atan": the original's atan(y / x). Nodes at 0.65 i; those behind the body
    # (cos < 0: i = 3..7) land at their angle minus pi, those past 3 pi / 2 (i = 8, 9) minus 2 pi.
    genome = cppn(config, {(X1, WEIGHT): 0.1}, biases={WEIGHT: 0.9})       # every node linked
    folded_controller, folded = decode(genome, config, Substrate(bottom_on_node0=False, bearings="atan"))
    controller, plain = decode(genome, config, Substrate(bottom_on_node0=False))
    by_hand = [0.0, 0.65, 1.3, 1.95 - math.pi, 2.6 - math.pi, 3.25 - math.pi, 3.9 - math.pi, 4.55 - math.pi,
               5.2 - 2 * math.pi, 5.85 - 2 * math.pi]
    np.testing.assert_allclose([s.bearing for s in folded], by_hand, atol=1e-12)
    assert all(abs(s.bearing) < math.pi / 2 for s in folded)
    assert [s.bearing for s in plain][5] == pytest.approx(3.25 - 2 * math.pi)   # atan2: behind the body
    # only the bearings differ: same types, parameters and controller
    assert [(s.type, s.range, s.fov, s.orientation) for s in folded] == \
        [(s.type, s.range, s.fov, s.orientation) for s in plain]
    np.testing.assert_array_equal(folded_controller.layers[0].weights, controller.layers[0].weights)
    with pytest.raises(ValueError, match="bearings='atan3'; allowed: atan2, atan"):
        Substrate(bearings="atan3")


def test_decoded_morphology_drives_the_env(config):
    genome = cppn(config, {(X1, WEIGHT): 0.3, (Y1, TYPE): 0.5}, biases={BIAS: 0.5})
    controller, morph = decode(genome, config)
    env = parallel_env(environment=1, num_robots=5, max_cycles=20)
    obs, _ = env.reset(seed=0, options={"morphology": morph})
    assert env.observation_space("robot_0").shape == (len(morph),)
    batch = np.stack([obs[a] for a in env.possible_agents])
    wheels = controller.act(batch)
    assert wheels.shape == (5, 2) and np.all(np.abs(wheels) <= 1)
    env.step_batch(wheels)


def test_hidden_ring(config):
    genome = cppn(config, {}, biases={WEIGHT: 1.0})
    controller, morph = decode(genome, config, Substrate(hidden_nodes=4))
    assert len(controller.layers) == 2
    # 9 configurable + bottom inputs -> 4 hidden, and inputs + hidden -> 2 outputs
    assert controller.num_links == 10 * 4 + 2 * (10 + 4)


def test_bad_substrate_values():
    with pytest.raises(ValueError, match="sensor_types"):
        Substrate(sensor_types=("laser",))
    with pytest.raises(ValueError, match="num_inputs"):
        Substrate(num_inputs=11)
