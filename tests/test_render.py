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
    FOLLOW_SPAN,
    GATHERED_SHADE,
    HEADING,
    PAGE,
    ROBOT,
    ROBOT_ATTACHED,
    WALL,
    ZONE,
    ZONE_EDGE,
    ZONE_MARGIN,
    Renderer,
    cone_colour_on,
    film_strip,
    morphology_rows,
    save_video,
    sensor_layout,
    team_cone_cover,
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
    assert renderer.panel_px > 0                                # the information panel, on the right
    assert frame.shape == (size_px, size_px + renderer.panel_px, 3) and frame.dtype == np.uint8
    assert renderer.render(sim, panel=False).shape == (size_px, size_px, 3)
    assert pygame.display.get_surface() is window_before       # rgb_array opened no window
    frame[:] = 0                                                # the caller owns the array
    assert renderer.render(sim).any()
    renderer.close()


def test_non_square_arena_gives_square_frame():
    sim = make_sim(Morphology([SensorSpec("bottom")]), arena_width=60.0, arena_height=30.0)
    renderer = Renderer(sim.config, "rgb_array", size_px=300, panel=False)
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
    renderer._text.font = renderer._small.font = None     # as if pygame.font were missing
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
    assert window is not None and window.get_size() == (200 + renderer.panel_px, 200)
    assert len(np.unique(pygame.surfarray.array3d(window).reshape(-1, 3), axis=0)) > 5
    renderer.close()
    assert pygame.display.get_surface() is None
    renderer.close()                                        # idempotent


def test_env_render_rgb_array():
    from gathering_env import parallel_env

    env = parallel_env(environment=1, max_cycles=5, render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape[0] == 640 and frame.shape[1] > 640 and frame.dtype == np.uint8
    assert env.render(panel=False, size_px=320).shape == (320, 320, 3)     # this frame only
    assert env.render().shape == frame.shape
    env.close()
    env = parallel_env(environment=1, max_cycles=5, render_mode="rgb_array",
                       render_options={"panel": False, "size_px": 300})
    env.reset(seed=0)
    assert env.render().shape == (300, 300, 3)
    env.close()


# ---------------------------------------------------------------------- video files
def _frames(n: int = 5, size_px: int = 160) -> list[np.ndarray]:
    sim = make_sim(environment=1)
    renderer = Renderer(sim.config, "rgb_array", size_px=size_px, panel=False)
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


# ---------------------------------------------------------------------- legible replays
def empty_arena_colour(renderer: Renderer, sim: GatheringSimulation, frame: np.ndarray) -> np.ndarray:
    """(H, W, 3) colour every arena pixel would have with nothing on it (FLOOR or ZONE), by hand."""
    h, w = frame.shape[:2]
    cols, rows = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    x = (cols - renderer._ox) / renderer.scale
    y = (renderer._oy - rows) / renderer.scale
    x0, y0, x1, y1 = sim.config.zone_rect
    in_zone = (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)
    return np.where(in_zone[..., None], np.array(ZONE), np.array(FLOOR))


def arena_pixels(renderer: Renderer) -> tuple[slice, slice]:
    left, top, width, height = renderer.arena_rect
    return slice(top + 2, top + height - 2), slice(left + 2, left + width - 2)


def ten_cameras() -> Morphology:
    return Morphology([SensorSpec("camera", bearing=b, orientation=0.0, range=20.0, fov=8 * math.pi / 9)
                       for b in np.linspace(-math.pi, math.pi, 10, endpoint=False)])


@pytest.mark.parametrize("cones", ["auto", "all"])
def test_many_long_cameras_leave_the_arena_readable(cones):
    # 20 robots, ten maximum-range cameras each: the cones' summed area is ~30 arenas.
    sim = make_sim(ten_cameras(), seed=1)
    assert team_cone_cover(sim.morphology, sim.config) > 20
    renderer = Renderer(sim.config, "rgb_array", cones=cones)
    frame = renderer.render(sim)
    rows, cols = arena_pixels(renderer)
    diff = np.abs(frame[rows, cols].astype(int) - empty_arena_colour(renderer, sim, frame)[rows, cols]).max(axis=2)
    close = np.mean(diff <= 30)
    assert close >= 0.5, f"only {close:.0%} of the arena keeps its colour with cones={cones!r}"
    if cones == "auto":                   # too many cones for everyone: one robot's are shown
        assert renderer.cone_robots(sim).tolist() == [0]
    # the fill is light and does not add up: no arena pixel is darker than one fill on the floor
    # (outlines aside), however many cones overlap there
    one_fill = np.array(cone_colour_on(FLOOR, "camera"))
    floor = (empty_arena_colour(renderer, sim, frame) == np.array(FLOOR)).all(axis=2)
    tinted = floor[rows, cols] & (diff > 0) & (diff <= np.abs(one_fill - FLOOR).max() + 1)
    assert tinted.mean() > 0.1                                      # cones are there


def test_cones_are_drawn_once_not_accumulated():
    # One robot, many overlapping cones of one type: the overlap has exactly one fill's colour.
    morph = Morphology([SensorSpec("ultrasonic", bearing=0.0, orientation=0.0, range=5.0, fov=1.0)] * 5)
    sim = make_sim(morph, num_robots=1)
    park_blocks(sim)
    sim.world.place_robot(0, 20.0, 20.0, 0.0)
    renderer = Renderer(sim.config, "rgb_array")
    frame = renderer.render(sim)
    one_fill = np.array(cone_colour_on(FLOOR, "ultrasonic"))
    assert np.abs(np.array(pixel(frame, renderer, 22.5, 20.3)) - one_fill).max() <= 1   # pygame rounds
    assert np.abs(one_fill - FLOOR).max() > 10                                          # a visible tint


def test_every_robot_is_at_least_the_minimum_size():
    sim = make_sim(Morphology([SensorSpec("bottom")]))
    park_blocks(sim)
    for i in range(20):                                           # a 5 x 4 grid, 6 units apart
        sim.world.place_robot(i, 6.0 + 6.0 * (i % 5), 10.0 + 6.0 * (i // 5), 0.3 * i)
    for min_px in (4, 7):
        renderer = Renderer(sim.config, "rgb_array", min_robot_px=min_px)
        assert round(sim.config.robot_radius * renderer.scale) < min_px    # true size is smaller
        frame = renderer.render(sim)
        is_body = (frame == np.array(ROBOT)).all(axis=2)
        for col, row in renderer.to_screen(sim.world.robot_pos).astype(int):
            box = is_body[row - min_px - 1: row + min_px + 2, col - min_px - 1: col + min_px + 2]
            assert box.sum() >= 0.75 * math.pi * min_px ** 2
            assert is_body[row, col]


def test_heading_mark_points_where_the_robot_faces():
    sim = make_sim(Morphology([SensorSpec("bottom")]), num_robots=1)
    park_blocks(sim)
    renderer = Renderer(sim.config, "rgb_array", min_robot_px=8)
    for angle, (dx, dy) in ((0.0, (1, 0)), (math.pi / 2, (0, -1)), (math.pi, (-1, 0))):
        sim.world.place_robot(0, 20.0, 20.0, angle)
        frame = renderer.render(sim)
        col, row = renderer.to_screen(sim.world.robot_pos[0]).astype(int)
        assert tuple(frame[row + 5 * dy, col + 5 * dx]) == HEADING          # inside, in front
        assert tuple(frame[row - 5 * dy, col - 5 * dx]) == ROBOT            # inside, behind
        assert tuple(frame[row + 10 * dy, col + 10 * dx]) == ROBOT          # the stub outside


def test_cones_of_one_robot_change_pixels_only_near_it():
    morph = Morphology([SensorSpec("ultrasonic", bearing=0.0, orientation=0.0, range=4.0, fov=1.2),
                        SensorSpec("infrared", bearing=math.pi, orientation=0.0, range=2.0, fov=1.0)])
    sim = make_sim(morph, seed=2)
    renderer = Renderer(sim.config, "rgb_array", panel=False)
    without = renderer.render(sim, cones="none")
    with_3 = renderer.render(sim, cones=[3])
    changed = np.argwhere((without != with_3).any(axis=2))                  # (row, col)
    assert len(changed) > 100
    col, row = renderer.to_screen(sim.world.robot_pos[3])
    reach = (4.0 + sim.config.robot_radius) * renderer.scale + 2
    ring = renderer.robot_px + max(2, renderer.robot_px // 2) + 2             # the focus ring
    dist = np.hypot(changed[:, 1] + 0.5 - col, changed[:, 0] + 0.5 - row)
    assert dist.max() <= max(reach, ring)
    assert renderer.render(sim, cones="3").tobytes() == with_3.tobytes()    # "3" == [3]
    all_cones = renderer.render(sim, cones="all")
    assert (all_cones != with_3).any(axis=2).sum() > len(changed)            # more robots, more pixels


def test_carried_and_gathered_blocks_are_marked(sim):
    w = sim.world
    park_blocks(sim)
    block = 5                                                   # medium, half side 0.3
    w.place_block(block, 20.0, 20.0, 0.0)
    w.place_robot(0, 20.0 - 0.3 - sim.config.robot_radius - 0.01, 20.0, 0.0)
    assert w.try_attach(0, block)
    renderer = Renderer(sim.config, "rgb_array", min_robot_px=2, size_px=800)
    frame = renderer.render(sim)
    assert pixel(frame, renderer, 20.0, 20.3 - 0.5 / renderer.scale) == ROBOT_ATTACHED   # north edge
    assert pixel(frame, renderer, 20.0, 20.0) == BLOCK_COLOURS[1]
    other = 6
    x, y = w.block_pos[other]
    assert pixel(frame, renderer, x, y + 0.3 - 0.5 / renderer.scale) == BLOCK_COLOURS[1]  # not carried


def test_trails_follow_the_last_k_steps():
    sim = make_sim(Morphology([SensorSpec("bottom")]), num_robots=1)
    park_blocks(sim)
    renderer = Renderer(sim.config, "rgb_array", trail=3)
    for k, x in enumerate((10.0, 12.0, 14.0, 16.0, 18.0)):        # teleport 2 units per step
        sim.world.place_robot(0, x, 20.0, 0.0)
        if k:
            sim.step(np.zeros((1, 2)))
        renderer.record(sim)
    frame = renderer.render(sim)
    # the last 3 steps: segments 12 -> 14 -> 16 -> 18 are drawn, 10 -> 12 has aged out
    for x in (13.0, 15.0, 17.0 - 0.5):
        assert pixel(frame, renderer, x, sim.world.robot_pos[0, 1]) != FLOOR
    assert pixel(frame, renderer, 11.0, sim.world.robot_pos[0, 1]) == FLOOR
    assert pixel(renderer.render(sim, trail=0), renderer, 15.0, sim.world.robot_pos[0, 1]) == FLOOR


def test_follow_view_keeps_the_followed_robot_centred():
    sim = make_sim(seed=4)
    renderer = Renderer(sim.config, "rgb_array", view="follow:3", size_px=400)
    rng = np.random.default_rng(0)
    for where in [None, (0.5, 0.5), (39.5, 20.0), (20.0, 39.5)]:            # also against walls
        if where is not None:
            sim.world.place_robot(3, *where, 1.0)
        else:
            for _ in range(30):
                sim.step(rng.uniform(-1, 1, (20, 2)))
        frame = renderer.render(sim)
        centre = renderer.to_screen(sim.world.robot_pos[3])
        assert np.allclose(centre, [200.0, 200.0])
        assert tuple(frame[200, 200]) in (ROBOT, ROBOT_ATTACHED)
        assert renderer.scale == pytest.approx(400 / FOLLOW_SPAN)


def test_zone_view_crops_around_the_zone():
    sim = make_sim(Morphology([SensorSpec("bottom")]))
    full = Renderer(sim.config, "rgb_array", panel=False)
    zone = Renderer(sim.config, "rgb_array", panel=False, view="zone")
    zone_px = [(f == np.array(ZONE)).all(axis=2).sum() for f in (full.render(sim), zone.render(sim))]
    x0, y0, x1, y1 = sim.config.zone_rect
    assert zone_px[1] > 2 * zone_px[0]
    frame = zone.render(sim)
    assert pixel(frame, zone, 0.5 * (x0 + x1), 0.5 * (y0 + y1)) == ZONE
    assert zone.scale == pytest.approx(640 / (x1 - x0 + 2 * ZONE_MARGIN))    # zone + margins fill the view


def test_panel_sparkline_rises_with_the_gathered_value():
    sim = make_sim(max_cycles=20)
    park_blocks(sim)
    renderer = Renderer(sim.config, "rgb_array")
    renderer.render(sim)
    box = renderer.sparkline_rect
    x0, y0, x1, y1 = sim.config.zone_rect
    large = int(np.flatnonzero(sim.world.block_type == 2)[0])
    sim.world.place_block(large, 0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.0)
    for _ in range(10):
        sim.step(np.zeros((20, 2)))
        renderer.record(sim)
    assert sim.gathered_value == 3.0 and sim.total_value == 30.0
    frame = renderer.render(sim)
    line = (frame[box.top:box.bottom, box.left:box.right] == np.array(ZONE_EDGE)).all(axis=2)
    rows, cols = np.flatnonzero(line.any(axis=1)), np.flatnonzero(line.any(axis=0))
    # 3 of 30 value: the line's top is a tenth of the plot height above the bottom ...
    expected_row = box.height - 2 - 0.1 * (box.height - 4)
    assert abs(rows.min() - expected_row) <= 2.0
    # ... and it runs over the first half of the box (step 10 of 20)
    assert abs(cols.max() - 0.5 * box.width) <= 3.0


def test_morphology_table_rows():
    rows = morphology_rows(Morphology.khepera_iii())
    assert rows[0] == ("0", "bottom", "+0\u00b0", "\u2013", "\u2013", "\u2013")
    assert rows[1] == ("1", "infrared", "+40\u00b0", "+0\u00b0", "0.2", "30\u00b0")
    assert rows[5] == ("5", "ultrasonic", "-90\u00b0", "+0\u00b0", "4.0", "70\u00b0")


def test_film_strip_has_the_requested_panels():
    frames = _frames(5, size_px=160)
    for n in (1, 3, 5):
        strip = film_strip(frames[:n], [f"step {i}" for i in range(n)])
        assert strip.shape[1] == n * 160 + (n - 1) * 8
        middle = strip[80]                                        # a row through the arenas
        is_wall = (middle == np.array(WALL)).all(axis=1).astype(int)
        wall_runs = int(np.sum(np.diff(np.concatenate([[0], is_wall])) == 1))
        assert wall_runs == 2 * n                                 # a west and an east wall per panel
    with pytest.raises(ValueError, match="frame 1 has shape"):
        film_strip([frames[0], frames[1][:, :-1]])
    with pytest.raises(ValueError, match="one per frame"):
        film_strip(frames[:2], ["a"])
    with pytest.raises(ValueError, match="no frames"):
        film_strip([])


def test_sensor_layout_points_cones_by_bearing():
    def layout(bearing: float) -> np.ndarray:
        sensors = [SensorSpec("ultrasonic", bearing=bearing, orientation=0.0, range=4.0, fov=0.6)]
        return sensor_layout(Morphology(sensors), size_px=400)

    tint = np.array(cone_colour_on(PAGE, "ultrasonic"))

    def tinted(image: np.ndarray, dx: int, dy: int) -> bool:
        """Pixels 50..90 px from the robot's centre (200, 205) in direction (dx, dy) are cone fill."""
        return all(np.abs(image[205 + d * dy, 200 + d * dx].astype(int) - tint).max() <= 1 for d in range(50, 91, 10))

    ahead = layout(0.0)                              # heading is up: the cone is above the body
    assert ahead.shape[0] == 400 and ahead.shape[1] > 400
    assert tinted(ahead, 0, -1) and not tinted(ahead, 0, 1) and not tinted(ahead, -1, 0)
    left = layout(math.pi / 2)                       # bearing +90 deg (counter-clockwise) = left
    assert tinted(left, -1, 0) and not tinted(left, 1, 0) and not tinted(left, 0, -1)


def test_human_window_keys():
    import pygame

    sim = make_sim(environment=1)
    renderer = Renderer(sim.config, "human", size_px=200, fps=40)
    renderer.render(sim)
    assert "pause" in pygame.display.get_caption()[0]
    assert renderer.cone_robots(sim).size == 20

    def press(*keys):
        for key in keys:
            pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=key, mod=0, unicode="", scancode=0))

    press(pygame.K_PLUS)
    renderer.render(sim)
    assert renderer.fps == 80
    press(pygame.K_MINUS, pygame.K_MINUS)
    renderer.render(sim)
    assert renderer.fps == 20
    press(pygame.K_c)                                   # auto -> all -> none
    renderer.render(sim)
    press(pygame.K_c)
    renderer.render(sim)
    assert renderer.cone_robots(sim).size == 0
    press(pygame.K_SPACE, pygame.K_RIGHT)               # pause, then one step: render returns
    renderer.render(sim)
    assert renderer.paused
    press(pygame.K_RIGHT)                               # paused: each render waits for a step key
    renderer.render(sim)
    press(pygame.K_SPACE)                               # resume
    renderer.render(sim)
    assert not renderer.paused
    press(pygame.K_ESCAPE)
    renderer.render(sim)
    assert pygame.display.get_surface() is None


BAD_OPTIONS = [
    (dict(cones="some"), r"cones: 'some'.*allowed: 'auto', 'all', 'none' or robot indices in 0\.\.19"),
    (dict(cones=[3, 25]), r"cones: robot index 25 does not exist.*allowed:"),
    (dict(cones=[1.5]), r"cones: .*allowed: 'auto', 'all', 'none'"),
    (dict(view="side"), r"view: 'side' is not a view; allowed: 'full', 'zone' or 'follow:K' with K in 0\.\.19"),
    (dict(view="follow:x"), r"view: .*allowed: 'full', 'zone' or 'follow:K'"),
    (dict(view="follow:20"), r"view: robot 20 does not exist.*allowed:"),
    (dict(size_px=10), r"size_px: 10 .*allowed: an integer in 64..4096"),
    (dict(size_px=100_000), r"size_px: 100000 .*allowed: an integer in 64..4096"),
    (dict(trail=-1), r"trail: -1 .*allowed: an integer >= 0"),
    (dict(panel="yes"), r"panel: 'yes' .*allowed: True or False"),
    (dict(min_robot_px=0), r"min_robot_px: 0 .*allowed: an integer >= 1"),
    (dict(colour="red"), r"colour: unknown render option; allowed: size_px, cones, view, trail, panel, min_robot_px"),
]


@pytest.mark.parametrize("options,message", BAD_OPTIONS)
def test_bad_render_options_name_the_allowed_values(options, message):
    cfg = WorldConfig.from_kwargs(environment=1)
    with pytest.raises(ValueError, match=message):
        Renderer(cfg, "rgb_array", **options)
    from gathering_env import parallel_env

    with pytest.raises(ValueError, match=message):
        parallel_env(render_mode="rgb_array", render_options=options)
    env = parallel_env(render_mode="rgb_array")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.render(**options)
    assert env.render().shape[0] == 640                 # a failed override leaves the options alone
    env.close()
