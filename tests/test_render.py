"""Rendering with real pygame on an offscreen surface, and video files (no mocks)."""

from __future__ import annotations

import math
import os
import sys

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import imageio.v2 as imageio  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from gathering_env.config import WorldConfig  # noqa: E402
from gathering_env.render import (  # noqa: E402
    BLOCK_COLOURS,
    FLOOR,
    GATHERED_SHADE,
    ROBOT,
    ROBOT_ATTACHED,
    WALL,
    ZONE,
    Renderer,
    cone_colour_on,
    save_video,
)
from gathering_env.sensors import Morphology, SensorSpec  # noqa: E402
from gathering_env.simulation import GatheringSimulation  # noqa: E402


def make_sim(morphology: Morphology | None = None, seed: int = 0, **kwargs) -> GatheringSimulation:
    sim = GatheringSimulation(WorldConfig.from_kwargs(environment=kwargs.pop("environment", 2), **kwargs),
                              morphology)
    sim.reset(seed=seed)
    return sim


def pixel(frame: np.ndarray, renderer: Renderer, x: float, y: float) -> tuple[int, ...]:
    """Colour of the pixel holding world point (x, y)."""
    col, row = renderer.to_screen(np.array([x, y])).astype(int)
    return tuple(int(v) for v in frame[row, col])


def park_blocks(sim: GatheringSimulation) -> None:
    """Move every block to a row along the north wall, out of the way."""
    for j in range(len(sim.world.block_half)):
        sim.world.place_block(j, 2.0 + 2.4 * j, 38.0, 0.0)


@pytest.fixture
def sim() -> GatheringSimulation:
    return make_sim()


@pytest.mark.parametrize("size_px", [200, 640])
def test_rgb_array_shape_dtype_and_no_window(sim, size_px):
    import pygame

    window_before = pygame.display.get_surface()
    renderer = Renderer(sim.config, "rgb_array", size_px=size_px)
    frame = renderer.render(sim)
    assert isinstance(frame, np.ndarray)
    assert frame.shape == (size_px, size_px, 3) and frame.dtype == np.uint8
    assert pygame.display.get_surface() is window_before       # rgb_array opened no window
    frame[:] = 0                                                # the caller owns the array
    assert renderer.render(sim).any()
    renderer.close()


def test_non_square_arena_gives_square_frame():
    sim = make_sim(Morphology([SensorSpec("bottom")]), arena_width=60.0, arena_height=30.0)
    renderer = Renderer(sim.config, "rgb_array", size_px=300)
    frame = renderer.render(sim)
    assert frame.shape == (300, 300, 3)
    assert pixel(frame, renderer, 30.0, 4.0) == ZONE            # zone centred along the south wall
    left, top, width, height = renderer.arena_rect
    assert abs(width / height - 2.0) < 0.05


def test_frame_not_blank_and_changes_after_steps(sim):
    renderer = Renderer(sim.config, "rgb_array")
    first = renderer.render(sim)
    assert len(np.unique(first.reshape(-1, 3), axis=0)) > 10
    rng = np.random.default_rng(0)
    for _ in range(20):
        sim.step(rng.uniform(-1, 1, (20, 2)))
    assert not np.array_equal(renderer.render(sim), first)


def test_robot_body_colour_at_its_pixel(sim):
    renderer = Renderer(sim.config, "rgb_array")
    park_blocks(sim)
    body = sim.world.robot_bodies[0]
    body.position = (20.0, 20.0)
    body.angle = 0.0
    sim.world.read_state()
    frame = renderer.render(sim)
    assert pixel(frame, renderer, 20.0, 20.0) == ROBOT
    body.position = (31.0, 17.0)
    sim.world.read_state()
    frame = renderer.render(sim)
    assert pixel(frame, renderer, 31.0, 17.0) == ROBOT
    assert pixel(frame, renderer, 20.0, 20.0) != ROBOT           # the robot moved away


def test_attached_robot_is_marked(sim):
    w = sim.world
    park_blocks(sim)
    block = 5                                                   # a medium block, half side 0.3
    w.place_block(block, 20.0, 20.0, 0.0)
    w.place_robot(0, 20.0 - 0.3 - sim.config.robot_radius - 0.01, 20.0, 0.0)
    assert w.try_attach(0, block)
    renderer = Renderer(sim.config, "rgb_array")
    frame = renderer.render(sim)
    assert pixel(frame, renderer, *w.robot_pos[0]) == ROBOT_ATTACHED
    assert pixel(frame, renderer, 20.1, 20.0) == BLOCK_COLOURS[1]


def test_zone_floor_and_wall_colours():
    sim = make_sim(Morphology([SensorSpec("bottom")]))      # no cones over the zone
    renderer = Renderer(sim.config, "rgb_array")
    frame = renderer.render(sim)
    x0, y0, x1, y1 = sim.config.zone_rect
    assert pixel(frame, renderer, 0.5 * (x0 + x1), 0.5 * (y0 + y1)) == ZONE
    assert pixel(frame, renderer, x0 + 0.3, y0 + 0.3) == ZONE
    assert pixel(frame, renderer, x0 - 0.5, 0.5 * (y0 + y1)) == FLOOR   # west of the zone
    assert pixel(frame, renderer, 0.5 * (x0 + x1), y1 + 0.5) == FLOOR   # north of the zone
    assert pixel(frame, renderer, -0.2, 20.0) == WALL
    assert pixel(frame, renderer, 20.0, sim.config.arena_height + 0.2) == WALL


def test_sensor_cone_is_drawn_where_the_sensor_looks():
    morph = Morphology([SensorSpec("ultrasonic", bearing=0.0, orientation=0.0, range=4.0, fov=1.0)])
    sim = make_sim(morph, num_robots=1)
    park_blocks(sim)
    sim.world.place_robot(0, 20.0, 20.0, 0.0)                # facing east (+x)
    renderer = Renderer(sim.config, "rgb_array")
    frame = renderer.render(sim)
    tinted = np.array(cone_colour_on(FLOOR, "ultrasonic"))
    assert np.abs(np.array(pixel(frame, renderer, 22.0, 20.0)) - tinted).max() <= 1   # inside
    assert np.abs(np.array(pixel(frame, renderer, 23.5, 21.0)) - tinted).max() <= 1   # inside, off-axis
    assert pixel(frame, renderer, 18.0, 20.0) == FLOOR                                # behind
    assert pixel(frame, renderer, 20.0, 22.0) == FLOOR                                # beside
    assert pixel(frame, renderer, 24.5, 20.0) == FLOOR                                # beyond range
    # turned north by the sensor's orientation
    sim.world.place_robot(0, 20.0, 20.0, math.pi / 2)
    frame = renderer.render(sim)
    assert np.abs(np.array(pixel(frame, renderer, 20.0, 22.0)) - tinted).max() <= 1
    assert pixel(frame, renderer, 22.0, 20.0) == FLOOR
    # facing the west wall from 1 unit away: the cone is clipped at the wall
    sim.world.place_robot(0, 1.0, 20.0, math.pi)
    frame = renderer.render(sim)
    assert np.abs(np.array(pixel(frame, renderer, 0.4, 20.0)) - tinted).max() <= 1
    assert pixel(frame, renderer, -0.2, 20.0) == WALL


def test_gathered_block_is_drawn_darker(sim):
    park_blocks(sim)
    x0, y0, x1, y1 = sim.config.zone_rect
    sim.world.place_block(0, 0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.3)
    sim.step(np.zeros((sim.config.num_robots, 2)))
    assert sim.gathered[0] and not sim.gathered[1:].any()
    renderer = Renderer(sim.config, "rgb_array")
    frame = renderer.render(sim)
    kind = int(sim.world.block_type[0])
    shaded = tuple(int(v * GATHERED_SHADE) for v in BLOCK_COLOURS[kind])
    assert pixel(frame, renderer, *sim.world.block_pos[0]) == shaded
    other = int(np.flatnonzero(sim.world.block_type == 2)[0])
    assert pixel(frame, renderer, *sim.world.block_pos[other]) == BLOCK_COLOURS[2]


def test_frame_without_font_still_renders(sim):
    renderer = Renderer(sim.config, "rgb_array")
    with_text = renderer.render(sim)
    renderer._font = None                                  # as if pygame.font were missing
    without_text = renderer.render(sim)
    assert without_text.shape == with_text.shape
    assert not np.array_equal(with_text, without_text)


def test_bad_arguments_and_render_before_reset():
    cfg = WorldConfig.from_kwargs(environment=1)
    with pytest.raises(ValueError, match="render_mode='png'"):
        Renderer(cfg, "png")
    with pytest.raises(ValueError, match="size_px"):
        Renderer(cfg, "rgb_array", size_px=10)
    with pytest.raises(ValueError, match="fps"):
        Renderer(cfg, "rgb_array", fps=0)
    with pytest.raises(RuntimeError, match="reset"):
        Renderer(cfg, "rgb_array").render(GatheringSimulation(cfg))


def test_human_mode_draws_into_a_window():
    import pygame

    sim = make_sim(environment=1)
    renderer = Renderer(sim.config, "human", size_px=200, fps=1000)
    assert renderer.render(sim) is None
    window = pygame.display.get_surface()
    assert window is not None and window.get_size() == (200, 200)
    assert len(np.unique(pygame.surfarray.array3d(window).reshape(-1, 3), axis=0)) > 5
    renderer.close()
    assert pygame.display.get_surface() is None
    renderer.close()                                        # idempotent


def test_env_render_rgb_array():
    from gathering_env import parallel_env

    env = parallel_env(environment=1, max_cycles=5, render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (640, 640, 3) and frame.dtype == np.uint8
    env.close()


# ---------------------------------------------------------------------- video files
def _frames(n: int = 5, size_px: int = 160) -> list[np.ndarray]:
    sim = make_sim(environment=1)
    renderer = Renderer(sim.config, "rgb_array", size_px=size_px)
    frames = [renderer.render(sim)]
    for _ in range(n - 1):
        for _ in range(5):
            sim.step(np.ones((sim.config.num_robots, 2)))
        frames.append(renderer.render(sim))
    return frames


def test_save_video_gif_round_trip(tmp_path):
    frames = _frames(5)
    path = save_video(frames, tmp_path / "sub" / "ep.gif", fps=10)
    assert path == tmp_path / "sub" / "ep.gif" and path.stat().st_size > 0
    back = imageio.mimread(path)
    assert len(back) == 5
    assert back[0].shape[:2] == (160, 160)


def test_save_video_rejects_bad_input(tmp_path):
    frames = _frames(2)
    with pytest.raises(ValueError, match="suffix '.avi'"):
        save_video(frames, tmp_path / "ep.avi")
    with pytest.raises(ValueError, match="suffix ''"):
        save_video(frames, tmp_path / "ep")
    with pytest.raises(ValueError, match="no frames"):
        save_video([], tmp_path / "ep.gif")
    with pytest.raises(ValueError, match="frame 1 has shape"):
        save_video([frames[0], frames[1][:-1]], tmp_path / "ep.gif")
    with pytest.raises(ValueError, match="fps"):
        save_video(frames, tmp_path / "ep.gif", fps=0)
    assert not (tmp_path / "ep.avi").exists() and not (tmp_path / "ep.gif").exists()


def test_save_video_mp4_without_ffmpeg_names_the_package(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)       # import now fails
    with pytest.raises(ValueError, match="pip install imageio-ffmpeg"):
        save_video(_frames(2), tmp_path / "ep.mp4")


def test_save_video_mp4(tmp_path):
    pytest.importorskip("imageio_ffmpeg")
    frames = _frames(4, size_px=161)                                # odd size: padded to even
    path = save_video(frames, tmp_path / "ep.mp4", fps=5)
    assert path.stat().st_size > 0
    back = imageio.mimread(path)
    assert len(back) == 4 and back[0].shape[:2] == (162, 162)
