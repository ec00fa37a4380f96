"""Hand-placed sensor scenes: readings computed by hand from docs/model.md §3."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gathering_env.config import WorldConfig
from gathering_env.reference.sensing import sensor_bank
from gathering_env.sensors import Morphology, SensorSpec

pytestmark = pytest.mark.usefixtures("both_kernels")  # every test here runs on both kernels

R = 0.15  # robot radius


def bank(sensors, blocks=((0.2, 1),), **cfg):
    """A bank over a 40 x 40 arena with the given blocks ((half side, need), ...)."""
    config = WorldConfig.from_kwargs(environment=None, block_counts=(max(len(blocks), 1), 0, 0),
                                     num_robots=3, **cfg)
    half = np.array([b[0] for b in blocks], dtype=float)
    need = np.array([b[1] for b in blocks], dtype=float)
    return sensor_bank(Morphology(sensors), config, half, need)


def read(b, robots, blocks=()):
    """robots: [(x, y, angle)], blocks: [(x, y, angle)] -> (N, S) readings (float64)."""
    rp = np.array([r[:2] for r in robots], dtype=float)
    ra = np.array([r[2] for r in robots], dtype=float)
    bp = np.array([q[:2] for q in blocks], dtype=float).reshape(-1, 2)
    ba = np.array([q[2] for q in blocks], dtype=float)
    return b.read(rp, ra, bp, ba).astype(float)


FAR = (35.0, 35.0, 0.0)  # a robot far from everything
IR = SensorSpec("infrared", 0.0, 0.0, 2.0, math.pi / 3)


def test_infrared_block_straight_ahead():
    # Robot at (20, 20) facing +x: mount at (20.15, 20). Block (half 0.2) centred at (21.35, 20):
    # its near face is at x = 21.15 -> d = 1.0 -> reading 1 - 1/2 = 0.5.
    b = bank([IR])
    got = read(b, [(20, 20, 0.0), FAR, FAR[:2] + (1.0,)], [(21.35, 20, 0.0)])
    assert got[0, 0] == pytest.approx(0.5)


def test_infrared_robot_ahead_and_wall():
    # Another robot centred 1.15 + 0.15 ahead of the mount: surface at d = 1.0 -> 0.5.
    b = bank([IR])
    got = read(b, [(20, 20, 0.0), (20.15 + 1.0 + R, 20, 2.0), FAR], [(5, 5, 0)])
    assert got[0, 0] == pytest.approx(0.5)
    # Facing the east wall (x = 40) from x = 38.85: mount at 39.0, d = 1 -> 0.5.
    got = read(b, [(38.85, 20, 0.0), FAR, (30, 30, 0)], [(5, 5, 0)])
    assert got[0, 0] == pytest.approx(0.5)


def test_outside_range_fov_and_behind_read_zero():
    b = bank([IR])
    # Block face at d = 2.05 > range 2.
    assert read(b, [(20, 20, 0.0), FAR, FAR], [(22.4, 20, 0.0)])[0, 0] == 0.0
    # Block at 45 deg off-axis (fov/2 = 30 deg): nearest point outside the cone.
    off = (20.15 + 1.0 * math.cos(math.pi / 4), 20 + 1.0 * math.sin(math.pi / 4))
    assert read(b, [(20, 20, 0.0), FAR, FAR], [(off[0], off[1], 0.0)])[0, 0] == 0.0
    # Just inside the cone (25 deg) it is seen.
    inside = (20.15 + 1.3 * math.cos(math.radians(25)), 20 + 1.3 * math.sin(math.radians(25)))
    assert read(b, [(20, 20, 0.0), FAR, FAR], [(inside[0], inside[1], 0.0)])[0, 0] > 0.0
    # Behind the robot: nothing.
    assert read(b, [(20, 20, 0.0), FAR, FAR], [(18.5, 20, 0.0)])[0, 0] == 0.0


def test_bearing_and_orientation_rotate_the_cone():
    block = [(20, 21.35, 0.0)]  # 1.35 north of the robot centre
    left = SensorSpec("infrared", math.pi / 2, 0.0, 2.0, math.pi / 3)
    b = bank([IR, left])
    got = read(b, [(20, 20, 0.0), FAR, FAR], block)
    assert got[0, 0] == 0.0                       # front sensor looks east
    assert got[0, 1] == pytest.approx(0.5)        # bearing +90 deg: mount (20, 20.15), d = 1.0
    # Turning the robot by +90 deg brings the block in front of the front sensor.
    got = read(b, [(20, 20, math.pi / 2), FAR, FAR], block)
    assert got[0, 0] == pytest.approx(0.5) and got[0, 1] == 0.0
    # Orientation: a front-mounted sensor turned +90 deg looks north from its mount (20.15, 20);
    # a block centred at (20.15, 21.2) has its south face at y = 21.0 -> d = 1.0.
    turned = SensorSpec("infrared", 0.0, math.pi / 2, 2.0, math.pi / 3)
    got = read(bank([turned]), [(20, 20, 0.0), FAR, FAR], [(20.15, 21.2, 0.0)])
    assert got[0, 0] == pytest.approx(0.5)


def test_rotated_block_nearest_point():
    # A block rotated 45 deg presents a corner: centre at (21.15 + 0.2*sqrt2, 20) -> the corner
    # is at x = 21.15, straight ahead of the mount at d = 1.0.
    b = bank([IR])
    got = read(b, [(20, 20, 0.0), FAR, FAR], [(21.15 + 0.2 * math.sqrt(2), 20, math.pi / 4)])
    assert got[0, 0] == pytest.approx(0.5)


def test_a_robot_never_sees_itself():
    # Facing -x, mounted at the front (19.85, 20), turned +90 deg to look south with a 180 deg cone:
    # the robot's own disc touches the mount (surface 0) and its centre lies on the cone's edge,
    # inside it in floating point at this heading, so only the self-exclusion keeps the reading 0.
    wide = SensorSpec("ultrasonic", 0.0, math.pi / 2, 0.5, math.pi)
    robots = [(20, 20, -math.pi), FAR, (35, 5, 0.0)]
    unguarded = bank([wide], kernel="numpy")
    unguarded._reach_sq[np.arange(3), np.arange(3)] = unguarded._reach_sq[0, 1]   # self not excluded
    assert read(unguarded, robots, [(5, 35, 0.0)])[0, 0] == 1.0                     # it would see itself
    assert read(bank([wide]), robots, [(5, 35, 0.0)])[0, 0] == 0.0
    # Another robot centred 0.2 south of the mount is seen: surface at d = 0.05 -> (1 - 0.1) / 0.95.
    got = read(bank([wide]), [(20, 20, -math.pi), (19.85, 19.8, 0.0), (35, 5, 0.0)], [(5, 35, 0.0)])
    assert got[0, 0] == pytest.approx(0.9 / 0.95)


def test_ultrasonic_profile():
    us = SensorSpec("ultrasonic", 0.0, 0.0, 10.0, 0.5)
    b = bank([us])
    # d = 0.4 (within the first 5 % = 0.5) -> 1
    assert read(b, [(20, 20, 0.0), FAR, FAR], [(20.15 + 0.4 + 0.2, 20, 0.0)])[0, 0] == pytest.approx(1.0)
    # d = 5 -> (1 - 0.5) / 0.95
    assert read(b, [(20, 20, 0.0), FAR, FAR], [(20.15 + 5 + 0.2, 20, 0.0)])[0, 0] == pytest.approx(0.5 / 0.95)


def test_colour_sensor_bands():
    col = SensorSpec("colour", 0.0, 0.0, 2.0, math.pi / 3)
    b = bank([col])
    block = read(b, [(20, 20, 0.0), FAR, FAR], [(21.35, 20, 0.0)])[0, 0]
    assert block == pytest.approx(0.5 + 0.5 * 0.5)                 # block at d = 1
    wall = read(b, [(38.85, 20, 0.0), FAR, FAR], [(5, 5, 0.0)])[0, 0]
    assert wall == pytest.approx(0.5 * 0.5)                         # wall at d = 1
    robot = read(b, [(20, 20, 0.0), (21.3, 20, 0.0), FAR], [(5, 5, 0.0)])[0, 0]
    assert robot == 0.0                                             # robot -> 0
    # the closest object decides: a robot in front of a block hides the block's colour
    both = read(b, [(20, 20, 0.0), (20.7, 20, 0.0), FAR], [(21.8, 20, 0.0)])[0, 0]
    assert both == 0.0


def test_block_sighting_by_the_originals_three_rays():
    """``block_sighting = "rays"``: a block is seen where the axis or a cone edge enters it, at
    the entry's projection on the axis; between the rays it is unseen; a mount inside it sees it
    at 0. Mount at (20.15, 20) facing +x, cone of 90 degrees, range 4; blocks of half side 0.2."""
    col = SensorSpec("colour", 0.0, 0.0, 4.0, math.pi / 2)
    cone, rays = bank([col]), bank([col], block_sighting="rays")
    me = [(20, 20, 0.0), FAR, FAR]
    # on the axis: entry at x = 21.15, d = 1 either way
    assert read(rays, me, [(21.35, 20, 0.0)])[0, 0] == read(cone, me, [(21.35, 20, 0.0)])[0, 0] \
        == pytest.approx(0.5 + 0.5 * 0.75)
    # 22.5 degrees off the axis at 2 units: inside the cone, between the rays
    between = [(20.15 + 2 * math.cos(math.pi / 8), 20 + 2 * math.sin(math.pi / 8), 0.0)]
    assert read(rays, me, between)[0, 0] == 0.0
    assert read(cone, me, between)[0, 0] == pytest.approx(0.5 + 0.5 * (1 - (2 - 0.2 / math.cos(math.pi / 8)) / 4),
                                                           abs=0.02)
    # across the left edge (45 degrees): it enters the side x = 21.05 at (21.05, 20.9), 0.9 along
    # the axis; the cone sees its nearest point (21.05, 20.8) at hypot(0.9, 0.8)
    edge = [(21.25, 21.0, 0.0)]
    assert read(rays, me, edge)[0, 0] == pytest.approx(0.5 + 0.5 * (1 - 0.9 / 4))
    assert read(cone, me, edge)[0, 0] == pytest.approx(0.5 + 0.5 * (1 - math.hypot(0.9, 0.8) / 4))
    # the right edge likewise (mirror image)
    assert read(rays, me, [(21.25, 19.0, 0.0)])[0, 0] == pytest.approx(0.5 + 0.5 * (1 - 0.9 / 4))
    # the mount inside the block: no ray enters it, the point test sees it at 0
    assert read(rays, me, [(20.3, 20, 0.0)])[0, 0] == pytest.approx(1.0)
    # out of range: the axis ray (length 4) stops short of a block whose side is at 4.2
    assert read(rays, me, [(20.15 + 4.4, 20, 0.0)])[0, 0] == 0.0
    # an edge ray runs to x = range, beyond the arc: a wide cone (150 degrees, range 2) sees a
    # large block (half side 0.4) through its left edge 2.32 along the ray, where it enters the
    # side x = 20.75 at y = 20 + 0.6 tan(75 deg), 0.6 along the axis; the axis misses it
    wide = bank([SensorSpec("colour", 0.0, 0.0, 2.0, 5 * math.pi / 6)], blocks=((0.4, 3),), block_sighting="rays")
    assert read(wide, me, [(21.15, 21.85, 0.0)])[0, 0] == pytest.approx(0.5 + 0.5 * (1 - 0.6 / 2))


def test_wall_distance_original_by_hand():
    """``wall_distance = "original"``: the 2018 formulas, worked by hand for a mount at (2, 20)
    facing west and 0.3 rad south of it (h = (-0.95534, -0.29552)), FOV 90 degrees (g = 1),
    range 6. The west wall's ends in the sensor's frame: (0, 40) -> v1 = (-3.99973, -19.69774),
    (0, 0) -> v2 = (7.82107, 18.51566); m = 3.23273, c = -6.76769; y = -1 at x1 = 1.78415,
    y = +1 at x2 = 2.40282; foot (m + 1/m) / (20 + 2/m - c) = 0.12934 < x1, so d = |(x1, -1)| =
    2.04530, where the wall is 2 away. No other wall is in range."""
    a = math.pi + 0.3
    me = [(2 - 0.15 * math.cos(a), 20 - 0.15 * math.sin(a), a), FAR, FAR]
    col = SensorSpec("colour", 0.0, 0.0, 6.0, math.pi / 2)
    original = bank([col], wall_distance="original", colour_response="farther")
    nearest = bank([col], colour_response="farther")
    assert read(original, me, [(35, 5, 0.0)])[0, 0] == pytest.approx(0.5 * 2.04530 / 6, abs=2e-6)
    assert read(nearest, me, [(35, 5, 0.0)])[0, 0] == pytest.approx(0.5 * 2.0 / 6, abs=2e-6)
    # facing 1.2 rad north of west from (3, 20): the west wall's nearest point in the cone is
    # 3.28 away, within range, but the formulas put it 10.90 away, beyond the range: read as a
    # wall at full distance (0.5), where the nearest point reads 0.27
    a = math.pi - 1.2
    me = [(3 - 0.15 * math.cos(a), 20 - 0.15 * math.sin(a), a), FAR, FAR]
    assert read(original, me, [(35, 5, 0.0)])[0, 0] == pytest.approx(0.5)
    true = 3.0 / (math.cos(math.pi / 2 - 1.2) * math.cos(math.pi / 4) + math.sin(math.pi / 2 - 1.2) * math.sin(math.pi / 4))
    assert read(nearest, me, [(35, 5, 0.0)])[0, 0] == pytest.approx(0.5 * true / 6, abs=2e-6)
    # a block nearer than the formulas' wall is read as the block
    assert read(original, me, [(3 + 1.2 * math.cos(a), 20 + 1.2 * math.sin(a), a)])[0, 0] > 0.5


def test_colour_sensor_farther_rises_with_distance():
    """The original's colour reading (``colour_response = "farther"``): d/R in place of 1 - d/R."""
    col = SensorSpec("colour", 0.0, 0.0, 2.0, math.pi / 3)
    b = bank([col], colour_response="farther")
    near = read(b, [(20, 20, 0.0), FAR, FAR], [(20.85, 20, 0.0)])[0, 0]    # block at d = 0.5
    far = read(b, [(20, 20, 0.0), FAR, FAR], [(21.85, 20, 0.0)])[0, 0]     # block at d = 1.5
    assert (near, far) == (pytest.approx(0.5 + 0.5 * 0.25), pytest.approx(0.5 + 0.5 * 0.75))
    wall = read(b, [(39.35, 20, 0.0), FAR, FAR], [(5, 5, 0.0)])[0, 0]
    assert wall == pytest.approx(0.5 * 0.25)                        # wall at d = 0.5
    touching = read(b, [(39.85, 20, 0.0), FAR, FAR], [(5, 5, 0.0)])[0, 0]
    assert touching == pytest.approx(0.0)                          # wall at contact: as nothing
    nothing = read(b, [(20, 20, 0.0), FAR, FAR], [(5, 5, 0.0)])[0, 0]
    assert nothing == 0.0
    robot = read(b, [(20, 20, 0.0), (21.3, 20, 0.0), FAR], [(5, 5, 0.0)])[0, 0]
    assert robot == 0.0


def test_camera_cooperation_ratio():
    cam = SensorSpec("camera", 0.0, 0.0, 10.0, 1.0)
    b = bank([cam], blocks=((0.4, 3), (0.3, 2)))
    # One large block (needs 3) ahead, one other robot in view: R = 1 + 1 = 2, Q = 3 -> 2/3.
    got = read(b, [(20, 20, 0.0), (23, 20.2, 0.0), FAR], [(25, 20, 0.0), (5, 5, 0.0)])
    assert got[0, 0] == pytest.approx(2 / 3)
    # Both blocks in view: Q = 5 -> 2/5.
    got = read(b, [(20, 20, 0.0), (23, 20.2, 0.0), FAR], [(25, 20, 0.0), (27, 19.8, 0.0)])
    assert got[0, 0] == pytest.approx(2 / 5)
    # Enough robots already (R > Q): 0. No blocks in view: 0.
    b1 = bank([cam], blocks=((0.2, 1),))
    assert read(b1, [(20, 20, 0.0), (23, 20.2, 0.0), FAR], [(25, 20, 0.0)])[0, 0] == 0.0
    assert read(b1, [(20, 20, 0.0), (23, 20.2, 0.0), FAR], [(5, 5, 0.0)])[0, 0] == 0.0


def test_bottom_sensor_over_and_near_the_zone():
    b = bank([SensorSpec("bottom")])  # zone x 10..30, y 0..8, falloff 1 unit
    got = read(b, [(20, 4, 0.0), (20, 8.5, 0.0), (20, 9.5, 0.0)], [(35, 35, 0.0)])
    np.testing.assert_allclose(got[:, 0], [1.0, 0.5, 0.0])


def _khepera(x):
    """The original's curve from scipy's Gamma(2.5, scale 2) density (independent of gathering_env)."""
    from scipy.stats import gamma

    return min(6.64 * gamma.pdf(x, 2.5, scale=2.0), 1.0)


def test_ir_khepera_response_is_the_originals_gamma_density():
    """``ir_response = "khepera"``: the density at 200 d / R; range 2, so x = 100 d."""
    b = bank([SensorSpec("infrared", 0.0, 0.0, 2.0, math.pi / 3)], ir_response="khepera")
    me = [(20, 20, 0.0), FAR, FAR]
    for d in (0.0, 0.01, 0.03, 0.1, 0.2, 1.5):                # block face d ahead of the mount
        got = read(b, me, [(20.15 + d + 0.2, 20, 0.0)])[0, 0]
        assert got == pytest.approx(_khepera(100 * d), abs=1e-6), d
    assert _khepera(3.0) == 1.0 and _khepera(0.0) == 0.0 and _khepera(10.0) == pytest.approx(0.18814, abs=1e-5)
    assert read(b, me, [(5, 35, 0.0)])[0, 0] == 0.0              # nothing in range
    wall = read(b, [(39.75, 20, 0.0), FAR, FAR], [(5, 35, 0.0)])[0, 0]
    assert wall == pytest.approx(_khepera(100 * 0.1), abs=1e-6)  # the east wall 0.1 ahead


def test_bottom_khepera_reads_the_front_on_or_off():
    """``bottom_response = "khepera"``: a disc 0.95 r = 0.1425 ahead of the centre, read at
    1000 (d + 0.0025), d along x first, while it overlaps the zone (x 10..30, y 0..8)."""
    b = bank([SensorSpec("bottom")], bottom_response="khepera")
    robots = [(20, 8.1, -math.pi / 2),      # front at y = 7.9575: over the zone
              (20, 8.1, math.pi / 2),       # front 0.2425 beyond it: off (linear would read 0.9)
              (20, 8.01, 0.0),              # front 0.01 beyond the north edge
              (29.8625, 8.02, 0.0),         # front 0.005 beyond the east edge and 0.02 north
              (20, 7.9175, math.pi / 2)]    # centre over the zone, front 0.06 beyond: the disc is clear
    got = read(b, robots, [(35, 35, 0.0)])[:, 0]
    want = [_khepera(2.5), 0.0, _khepera(12.5), _khepera(7.5), 0.0]
    np.testing.assert_allclose(got, want, atol=1e-6)
    assert got[4] == 0.0 < _khepera(1000 * 0.0625)     # exactly 0 once the disc leaves the zone
    assert _khepera(2.5) == pytest.approx(1.0, abs=1e-5) and _khepera(7.5) > 0.4 > 0.01 > _khepera(22.5)
    linear = read(bank([SensorSpec("bottom")]), robots, [(35, 35, 0.0)])[:, 0]
    np.testing.assert_allclose(linear, [0.9, 0.9, 0.99, 0.98, 1.0], atol=1e-6)   # the centre, either way it faces


def test_ir_gamma_response():
    b = bank([IR], ir_response="gamma", ir_gamma=2.0)
    got = read(b, [(20, 20, 0.0), FAR, FAR], [(21.35, 20, 0.0)])
    assert got[0, 0] == pytest.approx(0.25)      # (1 - 1/2) ** 2
