"""Replay a champion's team in the environment and record it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gathering_env import parallel_env
from gathering_env.render import save_video

from .champion import Champion


def replay(champion: Champion, env_config: dict[str, Any], seed: int, out: Path,
           frame_every: int = 10, fps: int = 15, png: Path | None = None) -> tuple[dict[str, Any], Path, int]:
    """Run one episode of the champion's team with rendering; returns (final info, video path, frames).

    ``png``: also save the last frame there.
    """
    env = parallel_env(render_mode="rgb_array", **env_config)
    obs_dict, _ = env.reset(seed=seed, options={"morphology": champion.morphology})
    obs = np.stack([obs_dict[a] for a in env.possible_agents])
    frames = [env.render()]
    step = 0
    while env.agents:
        obs, _, terminated, truncated = env.step_batch(champion.controller.act(obs))
        step += 1
        if step % frame_every == 0 or terminated or truncated:
            frames.append(env.render())
    info = env.team_info()
    env.close()
    if png is not None:
        import imageio.v2 as imageio

        Path(png).parent.mkdir(parents=True, exist_ok=True)
        imageio.imwrite(png, frames[-1])
    return info, save_video(frames, out, fps=fps), len(frames)
