"""Make the pictures of docs/rendering.md: one per render option, from one champion's episode.

    gathering-evolve configs/quick.toml --out out/quick        # or any champion.json
    python examples/render_gallery.py out/quick/champion.json --out docs/img

Writes render-*.png into --out (an existing file is only replaced with --force). Every picture
is the same episode (--environment, --seed) at --step, drawn with one option changed.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

import numpy as np

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

from evolution.guard import ArgumentParser, UsageError, command, int_arg  # noqa: E402
from evolution.run.champion import load_champion  # noqa: E402
from evolution.run.experiment import LIMITS  # noqa: E402
from gathering_env import Morphology, SensorSpec, parallel_env  # noqa: E402
from gathering_env.config import ENVIRONMENT_PRESETS, INT_RANGES  # noqa: E402
from gathering_env.render import Renderer, film_strip, save_png, sensor_layout  # noqa: E402

NAMES = ("default", "cameras-auto", "cameras-all", "cones-robots", "zone", "follow", "trail", "small", "strip", "sensors", "human")


def ten_cameras(environment: int, seed: int) -> dict[str, np.ndarray]:
    """20 robots with ten 20-unit cameras each, driving at random for 200 steps: auto vs all cones."""
    cameras = Morphology([SensorSpec("camera", bearing=b, orientation=0.0, range=20.0, fov=8 * math.pi / 9)
                          for b in np.linspace(-math.pi, math.pi, 10, endpoint=False)])
    env = parallel_env(environment=environment, morphology=cameras, render_mode="rgb_array",
                       render_options={"panel": False, "size_px": 400})
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    for _ in range(200):
        env.step_batch(rng.uniform(-1.0, 1.0, (env.config.num_robots, 2)))
    pictures = {"cameras-auto": env.render(), "cameras-all": env.render(cones="all")}
    env.close()
    return pictures


@command
def main(argv: list[str] | None = None) -> int:
    parser = ArgumentParser(prog="render_gallery.py", description=__doc__,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("champion", type=Path)
    parser.add_argument("--out", type=Path, default=Path("gallery"))
    parser.add_argument("--environment", type=int, default=1, choices=tuple(ENVIRONMENT_PRESETS))
    parser.add_argument("--seed", type=int_arg(*LIMITS["seed"]), default=3)
    parser.add_argument("--step", type=int_arg(*INT_RANGES["max_cycles"]), default=600,
                        help="the step every single picture shows")
    parser.add_argument("--steps", type=int_arg(*INT_RANGES["max_cycles"]), default=1200,
                        help="episode length (the film strip's last step)")
    parser.add_argument("--force", action="store_true", help="replace existing pictures")
    args = parser.parse_args(argv)
    if not 0 < args.step <= args.steps:
        raise UsageError(f"--step: {args.step} is outside the episode; allowed: 1..{args.steps}")
    if args.out.exists() and not args.out.is_dir():
        raise UsageError(f"--out {args.out}: is a file; allowed: a folder (missing, or holding earlier pictures)")
    paths = {name: args.out / f"render-{name}.png" for name in NAMES}
    existing = [str(p) for p in paths.values() if p.exists()]
    if existing and not args.force:
        raise UsageError(f"--out: {existing[0]} exists; allowed: a folder without render-*.png, or --force")
    champion = load_champion(args.champion)  # a ChampionError (a ValueError) is one line, exit 2

    env = parallel_env(environment=args.environment, max_cycles=args.steps, render_mode="rgb_array",
                       render_options={"trail": 200})
    obs, _ = env.reset(seed=args.seed, options={"morphology": champion.morphology})
    obs = np.stack([obs[a] for a in env.possible_agents])
    strip_steps = [0, args.steps // 4, args.steps // 2, args.steps]
    strip, captions = [], []
    pictures: dict[str, np.ndarray] | None = None
    step = 0
    while True:
        if step in strip_steps or not env.agents:
            sim = env.sim
            strip.append(env.render(trail=0, panel=False, size_px=320))
            captions.append(f"step {sim.steps}: value {sim.gathered_value:g} / {sim.total_value:g}")
        if pictures is None and (step == args.step or not env.agents):   # or the episode ended early
            pictures = {
                "default": env.render(trail=0),
                "cones-robots": env.render(trail=0, cones=[3, 11]),
                "zone": env.render(trail=0, view="zone"),
                "follow": env.render(trail=0, view="follow:3"),
                "trail": env.render(),
                "small": env.render(trail=0, size_px=320, panel=False, min_robot_px=3),
            }
            human = Renderer(env.config, "human", size_px=480)
            human.render(env.sim)
            import pygame

            pictures["human"] = np.ascontiguousarray(
                pygame.surfarray.array3d(pygame.display.get_surface()).transpose(1, 0, 2))
            human.close()
        if not env.agents:
            break
        obs, *_ = env.step_batch(champion.controller.act(obs))
        step += 1
    env.close()
    pictures.update(ten_cameras(args.environment, args.seed))
    pictures["strip"] = film_strip(strip[:len(strip_steps)], captions[:len(strip_steps)])
    title = f"{champion.experiment or 'champion'} ({champion.method}): the sensors of every robot"
    pictures["sensors"] = sensor_layout(champion.morphology, size_px=420, title=title)
    for name in NAMES:
        save_png(pictures[name], paths[name])
        print(f"wrote {paths[name]} ({paths[name].stat().st_size // 1024} KiB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
