"""The team controller's step: the compiled layer against the numpy matrix product it replaced.

A team controller (``evolution.encodings.controller``) runs once per step on the readings of
every robot of every world in the batch: 20 robots for one world, 100 for a genome's 5 trials,
320 for 16 worlds. Since 2026-12 each layer is one compiled loop that adds each weighted sum up
in column order with scalar IEEE operations, so the commands are the same bits on every
processor (numpy's ``@`` goes through BLAS, whose kernel, with or without FMA, depends on the
processor). This prints microseconds per call for both, best of ``--repeats``, same process:

    python benchmarks/bench_controller.py [--calls 2000] [--repeats 5]

The numpy form here is the former ``Layer.apply`` (``bias + response * (Z @ W.T)`` then the
activation on the whole array), kept only as the yardstick.
"""

from __future__ import annotations

import argparse
import timeit

import numpy as np

from evolution.encodings.controller import TeamController


def numpy_act(controller: TeamController, obs: np.ndarray) -> np.ndarray:
    """The former numpy form of a single-layer controller with the steep sigmoid."""
    layer = controller.layers[0]
    pre = layer.bias + layer.response * (obs @ layer.weights.T)
    return 2.0 / (1.0 + np.exp(-4.924273 * np.clip(pre - 2.4621365, -30.0, 30.0))) - 1.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    controller = TeamController.single_layer(rng.normal(0.0, 3.0, (2, 10)), rng.normal(0.0, 2.0, 2))
    print("| robots per call | compiled layer (us) | numpy @ (us) |")
    print("|---|---|---|")
    for rows in (20, 100, 320):
        obs = rng.uniform(0.0, 1.0, (rows, 10))
        np.testing.assert_allclose(controller.act(obs), numpy_act(controller, obs), rtol=0, atol=1e-12)
        times = [min(timeit.repeat(lambda f=f, obs=obs: f(obs), number=args.calls, repeat=args.repeats)) / args.calls * 1e6
                 for f in (controller.act, lambda o: numpy_act(controller, o))]
        print(f"| {rows} | {times[0]:.1f} | {times[1]:.1f} |")


if __name__ == "__main__":
    main()
