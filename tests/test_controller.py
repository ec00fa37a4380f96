"""The batched team controller against per-robot reference computations."""

from __future__ import annotations

import math
import random
from pathlib import Path

import neat
import numpy as np
import pytest

from evolution.encodings.controller import TeamController
from evolution.encodings.direct import NEATMGenome, decode_neat_m
from evolution.reproduction.breeding import NEATReproduction
from evolution.reproduction.species import GatheringSpeciesSet

CFG = Path(__file__).resolve().parent.parent / "configs" / "neat_m.neat.cfg"


def steep(x: float) -> float:
    return 1.0 / (1.0 + math.exp(-4.924273 * (x - 2.4621365)))


def test_single_layer_matches_per_robot_loop():
    rng = np.random.default_rng(0)
    w = rng.uniform(-5, 5, (2, 7))
    b = rng.uniform(-5, 5, 2)
    controller = TeamController.single_layer(w, b)
    obs = rng.uniform(0, 1, (20, 7))
    got = controller.act(obs)
    for i in range(20):
        for j in range(2):
            x = b[j] + sum(w[j, k] * obs[i, k] for k in range(7))
            assert got[i, j] == pytest.approx(2.0 * steep(x) - 1.0)


def test_zero_sensors_gives_bias_only_output():
    controller = TeamController.single_layer(np.zeros((2, 0)), np.array([2.4621365, 10.0]))
    np.testing.assert_allclose(controller.act(np.zeros((3, 0))), [[0.0, 1.0]] * 3, atol=1e-9)


def test_wrong_observation_width_is_refused():
    controller = TeamController.single_layer(np.ones((2, 3)), np.zeros(2))
    with pytest.raises(ValueError, match=r"expects \(N, 3\)"):
        controller.act(np.zeros((4, 5)))


def test_round_trip_through_dict():
    rng = np.random.default_rng(1)
    controller = TeamController.single_layer(rng.normal(size=(2, 4)), rng.normal(size=2))
    again = TeamController.from_dict(controller.to_dict())
    obs = rng.uniform(size=(6, 4))
    np.testing.assert_array_equal(again.act(obs), controller.act(obs))
    assert again.num_links == 8


def test_neat_m_network_matches_neat_feed_forward_per_robot():
    """A NEAT-M genome with hidden nodes: our layered batch vs neat-python's own network."""
    config = neat.Config(NEATMGenome, NEATReproduction, GatheringSpeciesSet,
                         neat.DefaultStagnation, str(CFG))
    population = neat.Population(config, seed=4)
    random.seed(4)
    genomes = list(population.population.values())[:10]
    for g in genomes:  # grow some hidden structure and give every slot a sensor
        for _ in range(6):
            g.mutate_add_node(config.genome_config)
            g.mutate_add_connection(config.genome_config)
        for slot in range(10):
            g.sensors.setdefault(slot, next(iter(genomes[0].sensors.values())))
        g.sensors = dict(sorted(g.sensors.items()))
    rng = np.random.default_rng(2)
    for g in genomes:
        controller, morph = decode_neat_m(g, config)
        assert len(morph) == 10
        obs = rng.uniform(0, 1, (5, 10))
        reference = neat.nn.FeedForwardNetwork.create(g, config)
        got = controller.act(obs)
        for i in range(5):
            expected = 2.0 * np.array(reference.activate(obs[i].tolist())) - 1.0
            np.testing.assert_allclose(got[i], expected, atol=1e-9)


def test_wander_team_follows_its_documented_rule():
    """Hand trace: 20 blocked readings start a 10-step spin in a random direction, the counter
    is frozen while spinning, drifts are redrawn every 50 steps."""
    from evolution.policies.scripted import BLOCKED_STEPS, DRIFT_PERIOD, FORWARD, SPIN_STEPS, WanderTeam

    team = WanderTeam(seed=3)
    front = team.front
    blocked = np.zeros((2, 6))
    blocked[0, front] = 1.0  # robot 0 always sees a wall ahead, robot 1 never
    rng = np.random.default_rng(3)
    drift = rng.uniform(-0.3, 0.3, 2)
    spins, signs = [], []
    for t in range(BLOCKED_STEPS + SPIN_STEPS + BLOCKED_STEPS + 2):
        wheels = team.act(blocked)
        if t == 0:
            np.testing.assert_allclose(wheels[1], [FORWARD - drift[1], FORWARD + drift[1]])
        is_spin = abs(wheels[0, 0]) == 1.0 and wheels[0, 0] == -wheels[0, 1]
        spins.append(is_spin)
        if is_spin:
            signs.append(wheels[0, 0])
        assert not (abs(wheels[1, 0]) == 1.0 and wheels[1, 0] == -wheels[1, 1])
    # steps 0..18 count to 19, step 19 reaches 20 and spins (steps 19..28), frozen meanwhile;
    # the next spin needs 20 fresh blocked steps after it: steps 29..48 -> spin from step 48 (..51)
    expected = [False] * (BLOCKED_STEPS - 1) + [True] * SPIN_STEPS + [False] * (BLOCKED_STEPS - 1) + [True] * 4
    assert spins == expected
    # the direction of each spin is drawn when it starts (seed 3: both directions occur over seeds)
    directions = set()
    for seed in range(8):
        team = WanderTeam(seed=seed)
        for _ in range(BLOCKED_STEPS):
            wheels = team.act(blocked)
        directions.add(float(wheels[0, 0]))
    assert directions == {1.0, -1.0}
    assert DRIFT_PERIOD == 50


# ---------------------------------------------------------------------------- the same on every machine
def python_layer(z, layer):
    """Plain-Python reference: every sum in column order, every activation by the one scalar
    formula (``activate.py_func``) on Python floats: IEEE operations and C-library calls only."""
    from evolution.encodings.controller import ACTIVATIONS, activate

    out = np.empty((z.shape[0], len(layer.targets)))
    for i in range(z.shape[0]):
        for node, name in enumerate(layer.activation):
            total = 0.0
            for k in range(layer.weights.shape[1]):
                total += float(z[i, k]) * float(layer.weights[node, k])
            out[i, node] = activate.py_func(ACTIVATIONS[name], float(layer.bias[node]) + float(layer.response[node]) * total)
    return out


def random_layer(rng, activations, width=11):
    from evolution.encodings.controller import Layer

    n = len(activations)
    return Layer(targets=np.arange(width, width + n), weights=rng.normal(0.0, 3.0, (n, width)),
                 bias=rng.normal(0.0, 2.0, n), response=rng.uniform(0.5, 5.0, n), activation=list(activations))


def test_every_activation_is_bit_for_bit_the_plain_python_reference():
    from evolution.encodings.controller import ACTIVATION_NAMES

    rng = np.random.default_rng(7)
    layer = random_layer(rng, ACTIVATION_NAMES)
    z = rng.normal(0.0, 1.0, (64, 11))
    z[:4] = [[0.0] * 11, [1e-300] * 11, [30.0] * 11, [-30.0] * 11]   # zero, tiny, and clipping values
    np.testing.assert_array_equal(layer.apply(z), python_layer(z, layer))


def test_activations_agree_with_neat_pythons_own():
    from neat.activations import ActivationFunctionSet

    from evolution.encodings.controller import ACTIVATION_NAMES, ACTIVATIONS, activate

    theirs = ActivationFunctionSet()
    for name in ACTIVATION_NAMES:
        if name == "steep_sigmoid":
            continue
        for z in (-40.0, -2.0, -0.3, 0.0, 0.2, 1.7, 40.0):
            assert activate(ACTIVATIONS[name], z) == pytest.approx(theirs.get(name)(z), rel=1e-12, abs=1e-12), name


SUBPROCESS = """
import sys, numpy as np
from evolution.encodings.controller import TeamController
rng = np.random.default_rng(3)
controller = TeamController.single_layer(rng.normal(0.0, 3.0, (2, 10)), rng.normal(0.0, 2.0, 2))
sys.stdout.write(controller.act(rng.uniform(0.0, 1.0, (100, 10))).tobytes().hex())
"""


@pytest.mark.skipif(__import__("platform").machine() not in ("x86_64", "AMD64"),
                    reason="the BLAS core types and SIMD sets named are x86-64's")
def test_commands_do_not_depend_on_the_blas_kernel_or_numpys_simd():
    """The property the compiled layer exists for: BLAS kernels with and without fused
    multiply-adds, and numpy with and without its AVX-512 code, give the same bits."""
    import os
    import subprocess
    import sys

    outputs = set()
    for blas, simd in (("Haswell", ""), ("Sandybridge", ""), ("Haswell", "X86_V4 AVX512_ICL")):
        env = {**os.environ, "OPENBLAS_CORETYPE": blas, "NPY_DISABLE_CPU_FEATURES": simd}
        env.pop("OPENBLAS_L2_SIZE", None)
        run = subprocess.run([sys.executable, "-c", SUBPROCESS], env=env, capture_output=True, text=True, check=True)
        outputs.add(run.stdout)
    assert len(outputs) == 1
