"""Environment throughput on the workload matched with the original Java simulator.

Setting: environment 2, 20 robots, Khepera III morphology, pickup heuristic on, the
"wander" team (``evolution.policies.scripted.WanderTeam``: forward at 0.8 with a drift in
+-0.3 redrawn every 50 steps, a 10-step spin in a random direction after 20 consecutive
steps with the front ultrasonic >= 0.999, the counter frozen while spinning), 10 000-step
trials, one process. The controller runs **inside the timed region**, as it does in the
Java measurement it is compared with.

    python benchmarks/bench_env.py [--steps 10000] [--repeats 3] [--kernels compiled,numpy]
                                   [--drive velocity|force|shuffled] [--java STEPS_PER_S]

Prints, for each kernel, the best of ``--repeats`` runs of:
* the PettingZoo parallel API (dict actions and observations),
* the fast path (``env.step_batch``, arrays in and out),
* the W-world batch (``gathering_env.vector.VectorSimulation``, W = 5 and 16), per world,
each in steps/s and as a ratio to the **yardstick** measured first in the same process: a
bare pymunk step of the same world (``space.step`` of environment 2 after reset, nothing
sensed, driven or scored). The ratio travels between machines and loads better than steps/s.
With ``--java`` (the Java original's steps/s measured the same day on the same machine) it
also prints each path as a multiple of the Java figure.
For the compiled kernel, microseconds per step by phase (physics = pymunk's set, step and
get; sensing; heuristics + scoring = the drive and settle kernels and the weld joints;
controller = the wander team; glue = the rest: validation, copies).
Last, the sensing alone (microseconds per team reading, both kernels) for suites of growing
range: Khepera III, ten 10-unit infrared, ten 25-unit ultrasonics, ten 20-unit cameras.

The Java side by side (docs/performance.md), measured 2026-11 in one session on this
project's machine with the controller included on both sides: fast path 1.9x the Java,
PettingZoo API 1.26x, 16 worlds per call 2.8x per world; the Java ran 12 800 steps/s that day.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from evolution.policies.scripted import WanderTeam
from evolution.run.protocol import ORIGINAL_FORCE_DRIVE, ORIGINAL_SCHEDULE
from gathering_env import Morphology, SensorSpec, parallel_env
from gathering_env.compiled.kernels import CompiledSensorBank
from gathering_env.reference.sensing import SensorBank
from gathering_env.vector import VectorSimulation

ENV = dict(environment=2, num_robots=20)
EVOLVED = Path(__file__).resolve().parent.parent / "docs" / "evidence" / "original-S1-v11" / "champion-gen65.json"
#: ``--drive``: the robot drive timed (``gathering_env.drive``); the default is the paper's.
DRIVES = {"velocity": {}, "force": ORIGINAL_FORCE_DRIVE, "shuffled": {**ORIGINAL_FORCE_DRIVE, **ORIGINAL_SCHEDULE}}
JAVA_SIDE_BY_SIDE = ("measured 2026-11, one session, controller included on both sides: fast path 1.9x the Java, "
                     "PettingZoo API 1.26x, 16 worlds per call 2.8x per world; Java 12 800 steps/s that day "
                     "(a quoted measurement, not recomputed here; --java compares with today's)")


def run_api(kernel: str, steps: int) -> float:
    env = parallel_env(**ENV, max_cycles=steps, kernel=kernel)
    obs, _ = env.reset(seed=0)
    agents = list(env.possible_agents)
    team = WanderTeam(env.morphology, seed=0)
    t0 = time.perf_counter()
    for _ in range(steps):
        wheels = team.act(np.stack([obs[a] for a in agents]))
        obs, *_ = env.step(dict(zip(agents, wheels)))
        if not env.agents:
            break
    return time.perf_counter() - t0


def run_fast(kernel: str, steps: int, profile: dict | None = None) -> float:
    """Seconds for ``steps`` steps of the fast path, the wander team included; with ``profile``,
    the engine's phase timings and the controller's seconds (key ``controller``) are added."""
    env = parallel_env(**ENV, max_cycles=steps, kernel=kernel)
    env.reset(seed=0)
    team = WanderTeam(env.morphology, seed=0)
    obs = env.sim.observe()
    if profile is not None:
        env.sim.engine.timings = profile
    act = team.act
    if profile is not None:
        profile["controller"] = 0.0

        def act(o):
            t = time.perf_counter()
            wheels = team.act(o)
            profile["controller"] += time.perf_counter() - t
            return wheels
    t0 = time.perf_counter()
    for _ in range(steps):
        obs, _, terminated, truncated = env.step_batch(act(obs))
        if terminated or truncated:
            break
    return time.perf_counter() - t0


def run_batch(kernel: str, steps: int, worlds: int) -> float:
    sims = VectorSimulation(worlds, **ENV, max_cycles=steps, kernel=kernel)
    obs = sims.reset(list(range(worlds)))
    team = WanderTeam(sims.morphology, seed=0)
    t0 = time.perf_counter()
    for _ in range(steps):
        obs, *_ = sims.step(team.act(obs.reshape(-1, obs.shape[-1])).reshape(worlds, -1, 2))
        if not sims.active.any():
            break
    return time.perf_counter() - t0


def run_yardstick(steps: int) -> float:
    """Seconds for ``steps`` bare pymunk steps of the same world: environment 2 after reset,
    ``space.step(dt)`` only (no sensing, drive, heuristics or scoring)."""
    env = parallel_env(**ENV, max_cycles=steps, kernel="numpy")
    env.reset(seed=0)
    space, dt = env.sim.world.space, env.config.dt
    t0 = time.perf_counter()
    for _ in range(steps):
        space.step(dt)
    return time.perf_counter() - t0


SUITES = {
    "Khepera III": Morphology.khepera_iii(),
    "10 x infrared 10": Morphology([SensorSpec("infrared", b, 0.0, 10.0, 1.0) for b in np.linspace(-3, 3, 10)]),
    "10 x ultrasonic 25": Morphology([SensorSpec("ultrasonic", b, 0.0, 25.0, 1.0) for b in np.linspace(-3, 3, 10)]),
    "10 x camera 20": Morphology([SensorSpec("camera", b, 0.0, 20.0, 1.0) for b in np.linspace(-3, 3, 10)]),
    # an evolved suite of mixed ranges: S1 version 11's generation-65 champion (bottom, 5 infrared
    # of range 4-6, 2 colour of 6, 2 ultrasonic of 15)
    "evolved mix 4-15": Morphology.coerce(json.loads(EVOLVED.read_text())["morphology"]),
}


def sensing_costs(states: int = 200, repeats: int = 5) -> None:
    """Microseconds per team reading on world states sampled along a wander episode."""
    env = parallel_env(**ENV, max_cycles=states * 10, kernel="compiled")
    obs, _ = env.reset(seed=0)
    team = WanderTeam(env.morphology, seed=0)
    w, poses = env.sim.world, []
    obs = env.sim.observe()
    for t in range(states * 10):
        obs, *_ = env.step_batch(team.act(obs))
        if t % 10 == 0:
            poses.append((w.robot_pos.copy(), w.robot_angle.copy(), w.block_pos.copy(), w.block_angle.copy()))
    print(f"sensing alone, microseconds per team reading (20 robots, 15 blocks, {states} states):")
    print(f"  {'suite':<22}{'compiled':>10}{'numpy':>10}")
    for name, morph in SUITES.items():
        row = []
        for bank_class in (CompiledSensorBank, SensorBank):
            bank = bank_class(morph, env.config, w.block_half, w.block_need)
            best = np.inf
            for _ in range(repeats):
                t0 = time.perf_counter()
                for pose in poses:
                    bank.read(*pose)
                best = min(best, time.perf_counter() - t0)
            row.append(1e6 * best / len(poses))
        print(f"  {name:<22}{row[0]:>10.1f}{row[1]:>10.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=10_000, help="steps per timed run (default 10000)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per path; the best is reported")
    parser.add_argument("--kernels", default="compiled,numpy", help="comma-separated kernels to time")
    parser.add_argument("--drive", choices=DRIVES, default="velocity",
                        help="robot drive: velocity (the paper's, default), force (the original robot) or "
                             "shuffled (the force drive under the original's shuffled schedule)")
    parser.add_argument("--java", type=float, default=None, metavar="STEPS_PER_S",
                        help="the Java original's steps/s measured the same day: also print each path "
                             "as a multiple of it")
    parser.add_argument("--sensing-only", action="store_true", help="time the sensing alone, nothing else")
    args = parser.parse_args()
    if args.sensing_only:
        sensing_costs()
        return
    if args.java is not None and not args.java > 0:
        parser.error(f"--java {args.java}: allowed: a number of steps per second > 0")
    ENV.update(DRIVES[args.drive])
    kernels = [k.strip() for k in args.kernels.split(",") if k.strip()]
    run_fast(kernels[0], 50)  # compile or load the kernels before timing
    print(f"collective gathering, environment 2, 20 robots, Khepera III, pickup on, {args.drive} drive, wander "
          f"team (timed with the steps), {args.steps} steps, best of {args.repeats}")
    yard = args.steps / min(run_yardstick(args.steps) for _ in range(args.repeats))
    print(f"yardstick: bare pymunk step of the same world, {yard:.0f} steps/s (this process, now)")
    java = f"{'vs Java':>10}" if args.java else ""
    print(f"{'kernel':<10}{'path':<34}{'steps/s':>10}{'robot-steps/s':>16}{'/ yardstick':>13}{java}")
    for kernel in kernels:
        rows = [("PettingZoo parallel API", lambda k=kernel: run_api(k, args.steps), 1),
                ("fast path (step_batch)", lambda k=kernel: run_fast(k, args.steps), 1)]
        for worlds in (5, 16):
            rows.append((f"W-world batch, W={worlds} (per world)",
                         lambda k=kernel, w=worlds: run_batch(k, args.steps, w), worlds))
        for name, fn, worlds in rows:
            best = min(fn() for _ in range(args.repeats))
            rate = worlds * args.steps / best
            vs_java = f"{rate / args.java:>9.2f}x" if args.java else ""
            print(f"{kernel:<10}{name:<34}{rate:>10.0f}{rate * 20:>16.0f}{rate / yard:>12.3f}x{vs_java}")
    if "compiled" in kernels:
        profile: dict[str, float] = {}
        total = run_fast("compiled", args.steps, profile)
        us = {k: 1e6 * v / args.steps for k, v in profile.items()}
        parts = {"physics (pymunk set/step/get)": us["physics"], "sensing": us["sensing"],
                 "heuristics + scoring (drive, settle, welds)": us["drive"] + us["settle"],
                 "controller (the wander team)": us["controller"]}
        parts["glue (validation, copies)"] = 1e6 * total / args.steps - sum(parts.values())
        print(f"compiled fast path, microseconds per step ({1e6 * total / args.steps:.1f} in all):")
        for name, value in parts.items():
            print(f"  {name:<46}{value:7.1f}")
    sensing_costs()
    print(f"Java side by side: {JAVA_SIDE_BY_SIDE}")


if __name__ == "__main__":
    main()
