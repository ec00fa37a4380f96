"""Replay a team in the environment and record it: video, picture, film strip, sensors.

The team is an evolved champion or any named policy of ``evolution.policies`` (``wander``,
``ppo:PATH``, ``benchmarl-sample:PATH``, ...), so a trained policy can be watched like an evolved team."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from evolution.policies import Policy
from evolution.run.champion import Champion
from gathering_env import parallel_env
from gathering_env.render import RenderOptionError, VideoWriter, film_strip, save_png, sensor_layout


def parse_steps(value: str | Sequence[int], max_cycles: int) -> list[int]:
    """Film-strip steps: ``"0,300,600"`` or a list of ints, each in 0..max_cycles, kept in order."""
    allowed = f"comma-separated steps in 0..{max_cycles} (e.g. '0,{max_cycles // 2},{max_cycles}')"
    if isinstance(value, str):
        try:
            steps = [int(part) for part in value.split(",")]
        except ValueError:
            raise RenderOptionError("strip", f"{value!r} is not a list of steps", allowed) from None
    else:
        steps = list(value)
        if not all(isinstance(s, (int, np.integer)) and not isinstance(s, bool) for s in steps):
            raise RenderOptionError("strip", f"{value!r} is not a list of steps", allowed)
    if not steps:
        raise RenderOptionError("strip", "no steps given", allowed)
    bad = [s for s in steps if not 0 <= s <= max_cycles]
    if bad:
        raise RenderOptionError("strip", f"step {bad[0]} is outside the episode", allowed)
    return [int(s) for s in steps]


def replay(team: Champion | Policy, env_config: dict[str, Any], seed: int, out: Path,
           frame_every: int = 10, fps: int = 15, png: Path | None = None,
           render_options: dict[str, Any] | None = None, strip: str | Sequence[int] | None = None,
           sensors_png: Path | None = None) -> tuple[dict[str, Any], Path, int]:
    """Run one episode of the team with rendering; returns (final info, video path, frames).

    Frames are streamed to the video file as they are drawn (``VideoWriter``: memory does not
    grow with the episode); the file appears only once complete, so a failure leaves none.

    Args:
        team: a champion or a ``Policy`` (``evolution.policies.make_policy``); its ``reset(seed)``
            is called before the episode.
        render_options: what the frames show (``gathering_env.render``: cones, view, size_px,
            trail, panel, min_robot_px).
        png: also save a picture there: the last frame, or with ``strip`` a film strip.
        strip: steps whose frames (arena only, captioned) go side by side into ``png``. If the
            episode ends before a step, that panel shows the last step.
        sensors_png: also save the morphology's sensor layout (paper Figure 3, middle) there.

    Raises:
        RenderOptionError (a ValueError) for a bad render option or strip step, before the run.
    """
    for option, path in (("png", png), ("sensors_png", sensors_png)):
        if path is not None and Path(path).suffix.lower() != ".png":
            raise RenderOptionError(option, f"{str(path)!r} has suffix {Path(path).suffix!r}", "a .png file")
    env = parallel_env(render_mode="rgb_array", render_options=render_options, **env_config)
    steps = parse_steps(strip, env.config.max_cycles) if strip is not None else []
    if steps and png is None:
        raise RenderOptionError("strip", "a film strip needs a picture file", "--png FILE.png with --strip")
    if isinstance(team, Champion):
        label = f"{team.experiment or 'champion'} ({team.method})"
        team = Policy(label, team.morphology, team.controller.act)
    if sensors_png is not None:
        save_png(sensor_layout(team.morphology, title=f"{team.name}: sensors of every robot"), sensors_png)
    video = VideoWriter(out, fps=fps)  # checks the suffix and fps before the episode
    obs_dict, _ = env.reset(seed=seed, options={"morphology": team.morphology})
    team.reset(seed)
    if team.bind is not None:
        team.bind(env.sim)
    obs = np.stack([obs_dict[a] for a in env.possible_agents])
    panels: dict[int, np.ndarray] = {}
    captions: dict[int, str] = {}

    def snap(step: int) -> None:
        sim = env.sim
        panels[step] = env.render(panel=False)
        captions[step] = f"step {sim.steps}: value {sim.gathered_value:g} / {sim.total_value:g}"

    with video:
        last = env.render()
        video.add(last)
        if 0 in steps:
            snap(0)
        step = 0
        while env.agents:
            obs, _, terminated, truncated = env.step_batch(np.asarray(team.act(obs), dtype=np.float64))
            step += 1
            if step % frame_every == 0 or terminated or truncated:
                last = env.render()
                video.add(last)
            if step in steps:
                snap(step)
        for s in steps:                                  # the episode ended before these steps
            if s not in panels:
                snap(s)
    info = env.team_info()
    env.close()
    if png is not None:
        if steps:
            save_png(film_strip([panels[s] for s in steps], [captions[s] for s in steps]), png)
        else:
            save_png(last, png)
    return info, Path(out), video.frames


def unseen_note(champion: Champion, env_config: dict[str, Any], seed: int, ft: float | None = None) -> str:
    """One line saying how the replayed episode relates to the champion's training score.

    A champion's ``task`` objective is its mean ft over the trial episodes of training, drawn
    from the run's seed; a replay runs the episode of ``seed``, which is none of them, so its ft
    is a single unseen episode and may be far from the training score."""
    trained = champion.objectives.get("task")
    if trained is None:
        return f"an unseen episode (seed {seed}): the champion file holds no training ft to compare with"
    changed = [key for key in sorted(set(env_config) | set(champion.environment))
               if env_config.get(key) != champion.environment.get(key)]
    own = champion.trial_seeds
    if seed in own and not changed:
        trial = own.index(seed)
        recorded = champion.trial_ft[trial] if champion.trial_ft else trained if len(own) == 1 else None
        which = (f"its training episode (seed {seed}, the run's one layout)" if len(own) == 1 else
                 f"training episode {trial + 1} of its {len(own)} (seed {seed})")
        if ft is not None and recorded is not None and round(ft, 2) != round(recorded, 2):
            return (f"{which}, but ft {ft:.2f} is not the ft {recorded:.2f} it scored in training: the run "
                    "computed other floating-point results (a run from before 2026-12, whose team controllers "
                    "used processor-dependent BLAS and SIMD code, or other code; docs/guarantees.md, 'The same "
                    "numbers on other machines')")
        if len(own) == 1:
            return f"{which}: the simulation is deterministic, so ft equals the training ft {trained:.2f}"
        if recorded is not None:
            return (f"{which}: ft equals the ft it scored in training, {recorded:.2f}; the training ft "
                    f"{trained:.2f} is the mean over all {len(own)}")
        return (f"one of its {len(own)} training episodes (seed {seed}): ft is that trial's score; the training "
                f"ft {trained:.2f} is the mean over all {len(own)}")
    world = f" in a changed world ({', '.join(changed)})" if changed else ""
    layout = f" (its training layout is --seed {own[0]})" if len(own) == 1 and not changed else ""
    return (f"an unseen episode (seed {seed}){world}: the training ft {trained:.2f} is the mean over the "
            f"run's own trial episodes{layout}; one new episode can score far from it")
