"""Run one episode with random wheel commands, save it as a GIF/MP4 and print the score.

    python examples/random_episode.py --environment 2 --steps 600 --out out/random_episode.gif

The pickup heuristic is on (as in the paper), so robots that bump into a block attach to
it and push it towards the zone; random driving alone rarely gathers much.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from evolution.guard import ArgumentParser, check_output_file, command, int_arg
from evolution.run.experiment import LIMITS
from gathering_env import parallel_env
from gathering_env.config import ENVIRONMENT_PRESETS, INT_RANGES
from gathering_env.render import save_png, save_video


@command
def main(argv: list[str] | None = None) -> int:
    parser = ArgumentParser(prog="random_episode.py", description=__doc__,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--environment", type=int, default=2, choices=tuple(ENVIRONMENT_PRESETS))
    parser.add_argument("--steps", type=int_arg(*INT_RANGES["max_cycles"]), default=600,
                        help="episode length (max_cycles)")
    parser.add_argument("--seed", type=int_arg(*LIMITS["seed"]), default=0)
    parser.add_argument("--frame-every", type=int_arg(1, float("inf")), default=5, help="record every k-th step")
    parser.add_argument("--out", type=Path, default=Path("out/random_episode.gif"), help=".gif or .mp4")
    parser.add_argument("--png", type=Path, help="also save the last frame as a PNG picture")
    args = parser.parse_args(argv)
    check_output_file(args.out, (".gif", ".mp4"), "--out")
    if args.png is not None:
        check_output_file(args.png, (".png",), "--png")

    env = parallel_env(environment=args.environment, max_cycles=args.steps, render_mode="rgb_array")
    env.reset(seed=args.seed)
    rng = np.random.default_rng(args.seed)
    frames = [env.render()]
    total_reward, infos, t = 0.0, {}, 0
    while env.agents:
        actions = {a: rng.uniform(-1, 1, 2).astype(np.float32) for a in env.agents}
        _, rewards, _, _, infos = env.step(actions)
        total_reward += rewards["robot_0"]
        t += 1
        if t % args.frame_every == 0:
            frames.append(env.render())
    env.close()
    info = infos["robot_0"]
    path = save_video(frames, args.out, fps=15)
    if args.png is not None:
        save_png(frames[-1], args.png)
    print(f"environment {args.environment}, {t} steps, random actions")
    print(f"gathered value {info['gathered_value']:.0f} / {info['total_value']:.0f} "
          f"(blocks by type {info['blocks_gathered_by_type']}), summed reward {total_reward:.1f}, "
          f"task performance ft = {info['task_performance']:.1f}")
    print(f"wrote {path} ({len(frames)} frames)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
