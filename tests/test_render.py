"""Rendering with real pygame on an offscreen surface, and video files."""

from __future__ import annotations

import imageio.v2 as imageio
import numpy as np
import pytest

from gathering_env import SensorSpec, parallel_env
from gathering_env.render import BLOCK_COLOURS, ROBOT, ZONE, save_video


@pytest.fixture
def env():
    e = parallel_env(environment=2, max_cycles=100, render_mode="rgb_array")
    e.reset(seed=0)
    yield e
    e.close()


def test_frame_shape_and_content(env):
    frame = env.render()
    assert frame.shape == (640, 640, 3) and frame.dtype == np.uint8
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 10          # not blank
    renderer = env._renderer
    x, y = renderer.to_screen(np.array([20.0, 2.0])).astype(int)      # inside the zone
    assert tuple(frame[y, x]) == ZONE
    env.step_batch(np.ones((20, 2)))
    for _ in range(20):
        env.step_batch(np.ones((20, 2)))
    assert not np.array_equal(env.render(), frame)                     # robots moved


def test_robot_and_block_pixels(env):
    w = env.sim.world
    w.place_robot(0, 20.0, 20.0, 0.0)
    w.place_block(0, 30.0, 30.0, 0.0)
    frame = env.render()
    r = env._renderer
    x, y = r.to_screen(np.array([20.0, 20.0])).astype(int)
    assert tuple(frame[y + 1, x]) == ROBOT       # just below the heading line (robot faces +x)
    x, y = r.to_screen(np.array([30.0, 30.0])).astype(int)
    assert tuple(frame[y, x]) == BLOCK_COLOURS[int(w.block_type[0])]


def test_cones_are_drawn(env):
    plain = env.render()
    env.reset(seed=0, options={"morphology": [SensorSpec("camera", 0.0, 0.0, 20.0, 2.5)]})
    with_cones = env.render()
    assert np.abs(with_cones.astype(int) - plain.astype(int)).sum() > 0


def test_save_video(tmp_path, env):
    frames = [env.render()]
    for _ in range(4):
        env.step_batch(np.ones((20, 2)))
        frames.append(env.render())
    path = save_video(frames, tmp_path / "ep.gif", fps=10)
    back = imageio.mimread(path)
    assert len(back) == 5 and back[0].shape[:2] == (640, 640)
    with pytest.raises(ValueError, match="suffix '.avi'"):
        save_video(frames, tmp_path / "ep.avi")
    with pytest.raises(ValueError, match="no frames"):
        save_video([], tmp_path / "ep.gif")


def test_human_mode_draws_into_a_window():
    # SDL's dummy video driver (set in conftest) gives a real, invisible pygame window.
    e = parallel_env(environment=1, max_cycles=5, render_mode="human")
    e.reset(seed=0)
    e.step({a: np.zeros(2) for a in e.agents})
    assert e.render() is None
    import pygame

    assert pygame.display.get_surface() is not None
    assert pygame.display.get_surface().get_size() == (640, 640)
    e.close()
