
"""The vectorised sensing kernel agrees with a plain per-robot, per-sensor, per-object loop.

The reference below is written independently of ``gathering_env.reference.sensing`` from
docs/model.md §3: nearest points by brute-force sampling-free geometry, cones by angles (atan2),
walls by scanning the cone's edge and normal directions.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gathering_env.config import WorldConfig
from gathering_env.reference.sensing import sensor_bank
from gathering_env.sensors import SENSOR_TYPES, Morphology, SensorSpec

pytestmark = pytest.mark.usefixtures("both_kernels")  # every test here runs on both kernels


def _angle_diff(a: float, b: float) -> float:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


def _nearest_on_square(p, centre, half, angle):
    c, s = math.cos(angle), math.sin(angle)
    rx, ry = p[0] - centre[0], p[1] - centre[1]
    lx, ly = rx * c + ry * s, -rx * s + ry * c
    qx, qy = min(max(lx, -half), half), min(max(ly, -half), half)
    return (centre[0] + qx * c - qy * s, centre[1] + qx * s + qy * c)


def _distance_to_square(p, centre, half, angle):
    """Distance from p to the square, measured in the square's frame (exactly 0 inside; a
    round trip through world coordinates would leave ~1e-16 and lose ties at distance 0)."""
    c, s = math.cos(angle), math.sin(angle)
    rx, ry = p[0] - centre[0], p[1] - centre[1]
    lx, ly = rx * c + ry * s, -rx * s + ry * c
    return math.hypot(min(max(lx, -half), half) - lx, min(max(ly, -half), half) - ly)


def _wall_distance(mount, axis, half_fov, cfg):
    """Nearest wall point inside the cone, by checking the wall normal and both cone edges."""
    best = math.inf
    walls = [(math.pi, mount[0]), (0.0, cfg.arena_width - mount[0]),
             (-math.pi / 2, mount[1]), (math.pi / 2, cfg.arena_height - mount[1])]
    for normal_angle, perp in walls:
        delta = _angle_diff(normal_angle, axis)
        off = max(delta - half_fov, 0.0)
        if off < math.pi / 2 - 1e-9:
            best = min(best, perp / math.cos(off))
    return best


def _square_corners(centre, half, angle):
    c, s = math.cos(angle), math.sin(angle)
    local = [(-half, -half), (half, -half), (half, half), (-half, half)]
    return [(centre[0] + x * c - y * s, centre[1] + x * s + y * c) for x, y in local]


def _ray_hits_square(origin, angle, length, corners):
    """Smallest t in [0, length] where the ray origin + t (cos, sin) crosses one of the square's
    four sides (segment against segment, by Cramer's rule), or None."""
    dx, dy = math.cos(angle), math.sin(angle)
    best = None
    for a, b in zip(corners, corners[1:] + corners[:1]):
        ex, ey = b[0] - a[0], b[1] - a[1]
        det = ex * dy - dx * ey
        if abs(det) < 1e-15:
            continue
        wx, wy = a[0] - origin[0], a[1] - origin[1]
        t = (ex * wy - wx * ey) / det
        u = (dx * wy - wx * dy) / det
        if -1e-12 <= u <= 1 + 1e-12 and 0 <= t <= length and (best is None or t < best):
            best = t
    return best


def _rays_distance(mount, axis, s, centre, half, angle):
    """The original's sighting of a square by three rays (docs/model.md §3), or None."""
    if _distance_to_square(mount, centre, half, angle) == 0.0:
        return 0.0              # the mount inside: no ray enters, the point test sees it
    corners = _square_corners(centre, half, angle)
    cos_half = math.cos(s.fov / 2)
    for offset, length in ((0.0, s.range), (s.fov / 2, s.range / cos_half), (-s.fov / 2, s.range / cos_half)):
        t = _ray_hits_square(mount, axis + offset, length, corners)
        if t is not None:
            return t * math.cos(offset)
    return None


def _khepera(x):
    from scipy.stats import gamma

    return min(6.64 * gamma.pdf(x, 2.5, scale=2.0), 1.0)


def reference_read(morph, cfg, robot_pos, robot_angle, block_pos, block_angle, block_half, block_need):
    n = len(robot_pos)
    out = np.zeros((n, len(morph)))
    zx0, zy0, zx1, zy1 = cfg.zone_rect
    for i in range(n):
        for j, s in enumerate(morph):
            if s.type == "bottom" and cfg.bottom_response == "khepera":
                # the original's disc ahead of the centre, by its own case analysis
                fx = robot_pos[i][0] + 0.95 * cfg.robot_radius * math.cos(robot_angle[i])
                fy = robot_pos[i][1] + 0.95 * cfg.robot_radius * math.sin(robot_angle[i])
                if zx0 <= fx <= zx1 and zy0 <= fy <= zy1:
                    d = 0.0
                elif fx < zx0 or fx > zx1:
                    d = zx0 - fx if fx < zx0 else fx - zx1
                else:
                    d = zy0 - fy if fy < zy0 else fy - zy1
                gap = math.hypot(max(zx0 - fx, 0, fx - zx1), max(zy0 - fy, 0, fy - zy1))
                out[i, j] = _khepera(1000 * (d + 0.0025)) if gap < 0.05 else 0.0
                continue
            if s.type == "bottom":
                dx = max(zx0 - robot_pos[i][0], 0, robot_pos[i][0] - zx1)
                dy = max(zy0 - robot_pos[i][1], 0, robot_pos[i][1] - zy1)
                out[i, j] = min(max(1 - math.hypot(dx, dy) / cfg.bottom_falloff, 0), 1)
                continue
            mount_angle = robot_angle[i] + s.bearing
            mount = (robot_pos[i][0] + cfg.robot_radius * math.cos(mount_angle),
                     robot_pos[i][1] + cfg.robot_radius * math.sin(mount_angle))
            axis = mount_angle + s.orientation
            seen = []  # (distance, kind, need)
            for k in range(n):
                if k == i:
                    continue
                cx, cy = robot_pos[k]
                d_centre = math.hypot(cx - mount[0], cy - mount[1])
                dist = max(d_centre - cfg.robot_radius, 0.0)
                direction = math.atan2(cy - mount[1], cx - mount[0])
                if _angle_diff(direction, axis) <= s.fov / 2 + 1e-12 and dist < s.range:
                    seen.append((dist, "robot", 0))
            for b in range(len(block_pos)):
                q = _nearest_on_square(mount, block_pos[b], block_half[b], block_angle[b])
                dist = _distance_to_square(mount, block_pos[b], block_half[b], block_angle[b])
                inside_cone = dist < 1e-12 or _angle_diff(math.atan2(q[1] - mount[1], q[0] - mount[0]), axis) <= s.fov / 2 + 1e-12
                if cfg.block_sighting == "rays":
                    ray = _rays_distance(mount, axis, s, block_pos[b], block_half[b], block_angle[b])
                    if ray is not None and dist < s.range:
                        seen.append((ray, "block", block_need[b]))
                elif inside_cone and dist < s.range:
                    seen.append((dist, "block", block_need[b]))
            if s.type == "camera":
                robots = sum(1 for d, kind, _ in seen if kind == "robot") + 1
                need = sum(nd for d, kind, nd in seen if kind == "block")
                out[i, j] = robots / need if need > 0 and robots <= need else 0.0
                continue
            d_wall = _wall_distance(mount, axis, s.fov / 2, cfg)
            if d_wall < s.range:
                seen.append((d_wall, "wall", 0))
            if not seen:
                continue
            d, kind, _ = min(seen, key=lambda t: (t[0], {"block": 0, "wall": 1, "robot": 2}[t[1]]))
            close = 1 - d / s.range
            if s.type == "infrared" and cfg.ir_response == "khepera":
                out[i, j] = _khepera(200 * d / s.range)
            elif s.type == "infrared":
                out[i, j] = close
            elif s.type == "ultrasonic":
                out[i, j] = min(close / 0.95, 1.0)
            elif s.type == "colour":
                level = d / s.range if cfg.colour_response == "farther" else close
                out[i, j] = {"block": 0.5 + 0.5 * level, "wall": 0.5 * level, "robot": 0.0}[kind]
    return out


def _sensor(draw, kind):
    spec = SENSOR_TYPES[kind]
    if not spec.configurable:
        return SensorSpec("bottom")
    return SensorSpec(
        kind,
        bearing=draw(st.floats(-math.pi, math.pi)),
        orientation=draw(st.floats(-math.pi / 2, math.pi / 2)),
        range=draw(st.floats(0.05, spec.range_max)),
        fov=draw(st.floats(spec.fov_min, spec.fov_max)),
    )


@st.composite
def scenes(draw):
    kinds = draw(st.lists(st.sampled_from(list(SENSOR_TYPES)), min_size=1, max_size=10))
    morph = Morphology([_sensor(draw, k) for k in kinds])
    n = draw(st.integers(1, 8))
    b = draw(st.integers(0, 6))
    seed = draw(st.integers(0, 2**32 - 1))
    # A small arena so that objects are close together and walls are in range.
    size = draw(st.sampled_from([3.0, 6.0, 40.0]))
    colour = draw(st.sampled_from(["nearer", "farther"]))
    sighting = draw(st.sampled_from(["cone", "rays"]))
    khepera = draw(st.booleans())
    return morph, n, b, seed, size, colour, sighting, khepera


@settings(max_examples=150, deadline=None)
@given(scenes())
def test_kernel_matches_reference(scene):
    morph, n, b, seed, size, colour, sighting, khepera = scene
    rng = np.random.default_rng(seed)
    cfg = WorldConfig.from_kwargs(environment=None, block_counts=(max(b, 1), 0, 0), num_robots=n,
                                  arena_width=size, arena_height=size, zone_width=size / 2,
                                  zone_depth=size / 5, colour_response=colour,
                                  block_sighting=sighting, ir_response="khepera" if khepera else "linear",
                                  bottom_response="khepera" if khepera else "linear")
    robot_pos = rng.uniform(0.2, size - 0.2, (n, 2))
    robot_angle = rng.uniform(-math.pi, math.pi, n)
    block_pos = rng.uniform(0.5, size - 0.5, (b, 2))
    block_angle = rng.uniform(-math.pi, math.pi, b)
    block_half = rng.choice([0.2, 0.3, 0.4], b)
    block_need = rng.choice([1, 2, 3], b)
    bank = sensor_bank(morph, cfg, block_half, block_need)
    got = bank.read(robot_pos, robot_angle, block_pos, block_angle)
    want = reference_read(list(morph), cfg, robot_pos.tolist(), robot_angle.tolist(),
                          block_pos.tolist(), block_angle.tolist(), block_half.tolist(), block_need.tolist())
    np.testing.assert_allclose(got, want, atol=2e-5)
