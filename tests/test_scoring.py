"""Gathered blocks, rewards and the task performance of paper eq. 1."""

from __future__ import annotations

import numpy as np
import pytest

from gathering_env import parallel_env
from gathering_env.scoring import gathered_mask, task_performance

pytestmark = pytest.mark.usefixtures("both_kernels")  # every test here runs on both kernels

ZONE = (10.0, 0.0, 30.0, 8.0)


def test_gathered_mask_needs_the_whole_bounding_box():
    pos = np.array([[20.0, 4.0], [20.0, 7.75], [20.0, 7.85], [10.25, 4.0], [20.0, 7.6]])
    angle = np.array([0.0, 0.0, 0.0, 0.0, np.pi / 4])
    half = np.array([0.2, 0.2, 0.2, 0.2, 0.2])
    # inside; touching the top edge from inside (7.95 <= 8); top edge at 8.05; inside by x;
    # rotated 45 deg: half extent 0.2 * sqrt(2) = 0.283 -> top at 7.883 (inside)
    assert gathered_mask(pos, angle, half, ZONE).tolist() == [True, True, False, True, True]


def test_task_performance_by_hand():
    assert task_performance(10, 20, 5000, 10_000) == pytest.approx(50.0)         # no bonus
    assert task_performance(20, 20, 2500, 10_000) == pytest.approx(100 + 20 * 0.75)
    assert task_performance(20, 20, 10_000, 10_000) == pytest.approx(100.0)
    assert task_performance(20, 20, 5000, 10_000, time_bonus=10) == pytest.approx(105.0)
    assert task_performance(1, 1, 50, 100) == pytest.approx(110.0)                # one small block, in half the steps
    assert task_performance(0.25, 0.5, 100, 100) == pytest.approx(50.0)           # any positive total value
    with pytest.raises(ValueError):
        task_performance(1, 0, 1, 1)
    with pytest.raises(ValueError):
        task_performance(0, -1, 1, 1)


def make_env(**kw):
    e = parallel_env(environment=None, block_counts=(1, 1, 0), num_robots=2, max_cycles=100, **kw)
    e.reset(seed=0)
    w = e.sim.world
    w.place_robot(0, 35, 35, 0.0)
    w.place_robot(1, 35, 30, 0.0)
    w.place_block(0, 5.0, 30.0, 0.0)   # small (value 1)
    w.place_block(1, 5.0, 20.0, 0.0)   # medium (value 2)
    return e, w


def still(e):
    return e.step_batch(np.zeros((2, 2)))


def test_block_in_counts_partly_in_does_not_and_out_again_stops_counting():
    e, w = make_env()
    total = 3.0
    w.place_block(1, 29.75, 4.0, 0.0)            # medium block half 0.3: x up to 30.05 -> partly in
    _, reward, *_ = still(e)
    assert reward == 0.0 and e.team_info()["gathered_value"] == 0.0
    w.place_block(1, 20.0, 4.0, 0.0)             # wholly in
    _, reward, *_ = still(e)
    assert reward == pytest.approx(100 * 2 / total)
    assert e.team_info()["blocks_gathered_by_type"] == (0, 1, 0)
    w.place_block(1, 20.0, 12.0, 0.0)            # pushed out again
    _, reward, *_ = still(e)
    assert reward == pytest.approx(-100 * 2 / total)
    assert e.team_info()["gathered_value"] == 0.0


def test_all_blocks_gathered_terminates_with_the_time_bonus():
    e, w = make_env()
    for _ in range(9):
        still(e)
    w.place_block(0, 15.0, 4.0, 0.0)
    w.place_block(1, 25.0, 4.0, 0.0)
    obs, reward, terminated, truncated = still(e)                 # step 10
    assert terminated and not truncated
    info = e.team_info()
    assert info["task_performance"] == pytest.approx(100 + 20 * (1 - 10 / 100))
    assert e.agents == []


def test_rewards_sum_to_the_value_part_of_ft():
    e = parallel_env(environment=1, max_cycles=400)
    e.reset(seed=2)
    rng = np.random.default_rng(0)
    total = 0.0
    while e.agents:
        _, r, *_ = e.step_batch(rng.uniform(-1, 1, (20, 2)))
        total += r
    info = e.team_info()
    assert total == pytest.approx(100 * info["gathered_value"] / info["total_value"])


def test_gathered_mask_against_the_rotated_corners():
    """Brute force: a block is gathered when all four corners of the rotated square lie in the
    zone (edges included); plus blocks touching each edge exactly, straight and turned 90 deg."""
    rng = np.random.default_rng(5)
    m = 4000
    half = rng.choice([0.2, 0.3, 0.4], m)
    angle = rng.uniform(-np.pi, np.pi, m)
    pos = np.stack([rng.uniform(9.0, 31.0, m), rng.uniform(-1.0, 9.0, m)], axis=1)
    corners = np.array([[1, 1], [1, -1], [-1, 1], [-1, -1]], dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    cx = pos[:, None, 0] + half[:, None] * (corners[None, :, 0] * c[:, None] - corners[None, :, 1] * s[:, None])
    cy = pos[:, None, 1] + half[:, None] * (corners[None, :, 0] * s[:, None] + corners[None, :, 1] * c[:, None])
    x0, y0, x1, y1 = ZONE
    want = ((cx >= x0) & (cx <= x1) & (cy >= y0) & (cy <= y1)).all(axis=1)
    got = gathered_mask(pos, angle, half, ZONE)
    assert 500 < want.sum() < m - 500                  # both outcomes well represented
    np.testing.assert_array_equal(got, want)
    # exactly touching each edge from inside counts; a hair outside does not
    h = 0.25
    touching = np.array([[x0 + h, 4.0], [x1 - h, 4.0], [20.0, y0 + h], [20.0, y1 - h]])
    for turn in (0.0, np.pi / 2):
        assert gathered_mask(touching, np.full(4, turn), np.full(4, h), ZONE).all(), turn
        out = touching + np.array([[-1e-9, 0], [1e-9, 0], [0, -1e-9], [0, 1e-9]])
        assert not gathered_mask(out, np.full(4, turn), np.full(4, h), ZONE).any(), turn
