"""examples/weld_fates.py: a team's welds, from how far off course they start and how they end."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from gathering_env import parallel_env
from gathering_env.config import WorldConfig
from gathering_env.simulation import GatheringSimulation

ROOT = Path(__file__).resolve().parent.parent
CHAMPION = ROOT / "docs" / "evidence" / "original-S1-v10" / "champion-gen140.json"


@pytest.fixture(scope="module")
def fates():
    spec = importlib.util.spec_from_file_location("weld_fates", ROOT / "examples" / "weld_fates.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("error, folded", [(0.0, 0.0), (30.0, 30.0), (-60.0, 60.0), (89.0, 89.0),
                                           (120.0, 60.0), (-150.0, 30.0), (179.0, 1.0)])
def test_steering_error_by_hand(fates, error, folded):
    """Heading error e to the zone centre, folded: |e| up to 90 degrees, 180 - |e| beyond (the
    robot then drives backwards)."""
    cfg = WorldConfig.from_kwargs(environment=None, block_counts=(1, 0, 0), num_robots=1)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=1)
    cx, cy = cfg.zone_centre
    # 10 units north of the zone centre its bearing is -pi/2, so heading -pi/2 - e makes the error e
    sim.world.place_robot(0, cx, cy + 10.0, -math.pi / 2 - math.radians(error))
    assert fates.steering_error(sim.world, np.array([0]))[0] == pytest.approx(folded, abs=1e-9)


def test_tables_bin_count_and_median_by_hand(fates):
    welds = [(5.0, 100, True), (14.9, 300, True), (15.0, 50, False), (44.0, 10, True), (60.0, 7, True),
             (90.0, 9, True), (80.0, 1, True), (70.0, 2, False)]
    text = fates.tables([(3, {"task_performance": 95.0, "steps": 10_000, "welded_share": 0.25})], welds)
    assert "| 3 | 95.00 | 10000 | 25.0% |" in text
    assert "| 0–15° | 2 | 2 | 0 | 200 |" in text          # median of 100 and 300
    assert "| 15–45° | 2 | 1 | 1 | 10 |" in text
    assert "| 45–90° | 4 | 3 | 1 | 7 |" in text            # 90 itself falls in the last bin
    finer = fates.tables([], welds, (0.0, 66.5, 81.0, 90.0))
    assert "| 0–66.5° | 5 | 4 | 1 | 55 |" in finer        # 5, 14.9, 15, 44, 60: median of 100, 300, 10, 7
    assert "| 66.5–81° | 2 | 1 | 1 | 1 |" in finer and "| 81–90° | 1 | 1 | 0 | 9 |" in finer


@pytest.mark.parametrize("text, edges", [("0,15,45,90", (0.0, 15.0, 45.0, 90.0)), ("0,66.5,90", (0.0, 66.5, 90.0)),
                                         ("0,90", (0.0, 90.0))])
def test_bins_are_read_as_rising_degrees(fates, text, edges):
    assert fates.bins_arg(text) == edges


def test_every_welded_robot_step_belongs_to_one_weld(fates):
    """Counted two ways on a champion's own episodes (1 500 steps): the steps of its welds, and
    the welded robots after each step; some welds are delivered, some still held at the end."""
    from evolution.policies import make_policy

    policy = make_policy(f"champion:{CHAMPION}")
    env = parallel_env(**{**policy.environment, "max_cycles": 1500})
    delivered = held = 0
    for seed in (1000, 1001):
        info, welds = fates.follow_welds(env, policy, seed)
        total = info["welded_share"] * info["steps"] * env.sim.config.num_robots
        assert sum(w[1] for w in welds) == pytest.approx(total, abs=1e-6)
        assert all(0.0 <= w[0] <= 90.0 for w in welds)
        delivered += sum(w[2] for w in welds)
        held += sum(not w[2] for w in welds)
    assert delivered > 0 and held > 0


def test_bad_input_is_one_line_exit_2(fates, tmp_path, capsys):
    for args, says in (([str(tmp_path / "none.json")], "champion file not found"),
                       ([str(CHAMPION), "--world", "weld_spin=loose"], "--world weld_spin='loose'"),
                       ([str(CHAMPION), "--world", "max_cycles=-1"], "--world max_cycles=-1"),
                       *(([str(CHAMPION), "--bins", bad], f"--bins: {bad!r}: allowed: comma-separated degrees")
                         for bad in ("0,45", "15,90", "0,45,45,90", "0,nan,90", "0,x,90", "0,60,30,90", "")),
                       ([str(ROOT / "docs" / "evidence" / "original-S1-force" / "champion.json"), "--own-layout"],
                        "has no layout_seed")):
        try:
            status = fates.main(args)
        except SystemExit as stop:  # argparse's own refusals
            status = stop.code
        assert status == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and says in err[0], err
