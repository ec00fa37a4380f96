"""How a team's welds end: which blocks its robots grip, from how far off course, and how soon they deliver them.

A robot that grips a block (the pickup heuristic) is welded to it and steers it towards the zone
until the block is gathered; nothing else releases it. This script plays a champion in its own
world (its ``environment`` keys; ``--world KEY=VALUE`` changes one, as in ``gathering-compare``)
and follows every weld: the robot's steering error when it gripped (its heading error to the zone
centre, folded to 0-90 degrees, since a robot with the zone behind it drives backwards), whether
the block was delivered or was still welded when the episode ended, and after how many steps.
It prints one markdown table of the episodes and one of the welds by steering error
(bins 0-15, 15-45 and 45-90 degrees, or ``--bins`` edges of one's own, such as 0,15,45,66,81,90:
the original's welded pair arrives from up to 66 degrees off and stalls from 81, docs/fidelity.md).

    python examples/weld_fates.py docs/evidence/original-S1-v10/champion-gen140.json --own-layout \\
        --world attached_steering=original --world weld_spin=free --episodes 10 --seed 1000

Episodes, as in ``gathering-compare``: seeds ``--seed`` .. ``--seed + --episodes - 1``, each a fresh
layout, or with ``--own-layout`` the one-layout run's own layout under the shuffled schedule.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from evolution.compare import champion_world
from evolution.guard import ArgumentParser, command, int_arg, with_world_settings, world_setting
from evolution.policies import make_policy
from evolution.run.experiment import LIMITS
from gathering_env import parallel_env
from gathering_env.reference.heuristics import zone_heading_error

#: Steering-error bins of the welds table, in degrees (the last one closed at 90); ``--bins``.
BINS = (0.0, 15.0, 45.0, 90.0)


def bins_arg(text: str) -> tuple[float, ...]:
    """``--bins``: comma-separated bin edges in degrees, rising from 0 to 90."""
    try:
        edges = tuple(float(part) for part in text.split(","))
    except ValueError:
        edges = ()
    rising = len(edges) >= 2 and all(map(math.isfinite, edges)) and all(b > a for a, b in zip(edges, edges[1:]))
    if not rising or edges[0] != 0.0 or edges[-1] != 90.0:
        raise argparse.ArgumentTypeError(f"{text!r}: allowed: comma-separated degrees rising from 0 to 90, "
                                         "such as 0,15,45,90")
    return edges


def steering_error(world, robots: np.ndarray) -> np.ndarray:
    """Degrees, 0-90: the heading error to the zone centre, or its supplement when the zone lies
    behind the robot (it then drives backwards)."""
    error = np.degrees(np.abs(zone_heading_error(world, robots)))
    return np.where(error > 90.0, 180.0 - error, error)


def follow_welds(env, policy, seed: int) -> tuple[dict, list[tuple[float, int, bool]]]:
    """One episode: its team info, its welded share of robot-steps and its welds as
    (steering error at the grip, steps welded, delivered). A weld made in step s and let go in
    step t was welded after steps s .. t - 1; one still welded at the end, after s .. the last."""
    obs_dict, _ = env.reset(seed=seed, options={"morphology": policy.morphology})
    policy.reset(seed)
    obs = np.stack([obs_dict[a] for a in env.possible_agents])
    world = env.sim.world
    before = world.robot_attached.copy()
    gripped: dict[int, tuple[float, int]] = {}
    welds, welded_steps, step, done = [], 0, 0, False
    while not done:
        obs, _, terminated, truncated = env.step_batch(np.asarray(policy.act(obs), dtype=np.float64))
        done, step = terminated or truncated, step + 1
        now = world.robot_attached
        welded_steps += int((now >= 0).sum())
        new = np.flatnonzero((now >= 0) & (before < 0))
        for robot, error in zip(new.tolist(), steering_error(world, new).tolist()):
            gripped[robot] = (error, step)
        for robot in np.flatnonzero((now < 0) & (before >= 0)).tolist():
            error, start = gripped.pop(robot)
            welds.append((error, step - start, True))
        before = now.copy()
    welds += [(error, step - start + 1, False) for error, start in gripped.values()]  # welded after every step since
    info = {**env.team_info(), "welded_share": welded_steps / (step * len(before))}
    return info, welds


def tables(episodes: list[tuple[int, dict]], welds: list[tuple[float, int, bool]],
           bins: tuple[float, ...] = BINS) -> str:
    lines = ["| seed | ft | steps | welded robot-steps |", "|---|---|---|---|"]
    lines += [f"| {seed} | {info['task_performance']:.2f} | {info['steps']} | {info['welded_share']:.1%} |"
              for seed, info in episodes]
    lines += ["", "| steering error at the grip | welds | delivered | still welded at the end | "
                  "median steps to deliver |", "|---|---|---|---|---|"]
    for low, high in zip(bins, bins[1:]):
        inside = [w for w in welds if low <= w[0] < high or (high == bins[-1] and w[0] == high)]
        delivered = [w[1] for w in inside if w[2]]
        median = f"{np.median(delivered):.0f}" if delivered else "—"
        lines.append(f"| {low:g}–{high:g}° | {len(inside)} | {len(delivered)} | "
                     f"{len(inside) - len(delivered)} | {median} |")
    return "\n".join(lines)


@command
def main(argv: list[str] | None = None) -> int:
    parser = ArgumentParser(prog="weld_fates.py", description=__doc__.splitlines()[0])
    parser.add_argument("champion", type=Path, help="champion JSON written by gathering-evolve")
    parser.add_argument("--own-layout", action="store_true",
                        help="keep a one-layout run's layout (layout_seed); the seeds then vary only the schedule")
    parser.add_argument("--world", type=world_setting, action="append", default=[], metavar="KEY=VALUE",
                        help="set one world parameter over the champion's world (repeat)")
    parser.add_argument("--episodes", type=int_arg(1, 10_000), default=10, help="episodes (default 10)")
    parser.add_argument("--seed", type=int_arg(*LIMITS["seed"]), default=0, help="first episode seed (default 0)")
    parser.add_argument("--bins", type=bins_arg, default=BINS, metavar="DEGREES",
                        help="steering-error bin edges, rising from 0 to 90 (default 0,15,45,90)")
    args = parser.parse_args(argv)
    policy = make_policy(f"champion:{args.champion}")
    world = champion_world(policy, args.champion, args.own_layout)
    env = parallel_env(**with_world_settings(world, args.world, ()))
    episodes, welds = [], []
    for seed in range(args.seed, args.seed + args.episodes):
        info, found = follow_welds(env, policy, seed)
        episodes.append((seed, info))
        welds += found
    changes = ", ".join(f"{k} = {v!r}" for k, v in args.world)
    print(f"{args.champion}{' on its own layout' if args.own_layout else ''}"
          f"{', with ' + changes if changes else ''}\n")
    print(tables(episodes, welds, args.bins))
    return 0


if __name__ == "__main__":
    sys.exit(main())
