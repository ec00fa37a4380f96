"""Analysis on synthetic run directories: selection points, tests and files by hand."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from evolution.analysis.fronts import analyse, merge_fronts, selection_points
from evolution.analysis.report import write_report
from evolution.cli import analyze_main


def make_run(root: Path, name: str, env: int, multi: bool, champion: tuple[float, float],
             front: list[tuple[float, float]] = (), generations: int = 3) -> Path:
    run = root / name
    (run / "front").mkdir(parents=True)
    objectives = ["task", "morphology"] if multi else ["task"]
    (run / "experiment.json").write_text(json.dumps(
        {"name": name, "objectives": objectives, "environment": {"environment": env}}))
    with open(run / "stats.jsonl", "w") as f:
        for g in range(generations):
            f.write(json.dumps({"generation": g, "task_best": champion[0], "morphology_mean": 40.0 + g}) + "\n")
    (run / "champion.json").write_text(json.dumps({"objectives": {"task": champion[0], "morphology": champion[1]}}))
    for i, (ft, c) in enumerate(front):
        (run / "front" / f"genome-{i}.json").write_text(json.dumps({"objectives": {"task": ft, "morphology": c}}))
    return run


FRONT = np.array([[90.0, 20.0], [85.0, 50.0], [60.0, 70.0], [30.0, 90.0]])


def test_selection_points_by_hand():
    pts = selection_points(FRONT)
    assert pts["max"] == (90.0, 20.0)
    assert pts["mean"] == pytest.approx((66.25, 57.5))  # (90+85+60+30)/4, (20+50+70+90)/4
    # Normalised: ft (1, 55/60, 0.5, 0), C (0, 30/70, 50/70, 1); squared distances to (1, 1):
    # A 1, B (5/60)^2 + (40/70)^2 = 0.3335, C 0.25 + (20/70)^2 = 0.3316, D 1 -> knee = C.
    assert pts["knee"] == (60.0, 70.0)
    # Within 10 % of max ft: ft >= 81 -> A, B; the simplest of them is B.
    assert pts["epsilon"] == (85.0, 50.0)


def test_merge_fronts_drops_dominated_points():
    a = np.array([[90.0, 20.0], [50.0, 60.0]])
    b = np.array([[88.0, 30.0], [40.0, 55.0]])  # (40, 55) is dominated by (50, 60)
    merged = merge_fronts([a, b])
    assert merged.tolist() == [[90.0, 20.0], [88.0, 30.0], [50.0, 60.0]]


def test_t_test_and_files(tmp_path):
    so = [(70.0, 30.0), (75.0, 35.0), (80.0, 25.0)]
    runs = [make_run(tmp_path, f"S2-{i}", 2, False, c) for i, c in enumerate(so)]
    fronts = [FRONT, FRONT + [[-5.0, 5.0]], FRONT + [[5.0, -5.0]]]
    runs += [make_run(tmp_path, f"M2-{i}", 2, True, tuple(f[0]), [tuple(r) for r in f]) for i, f in enumerate(fronts)]
    analysis = analyse(runs)
    cmp = {(c.point, c.objective): c for c in analysis.comparisons}
    # Max point ft per MO run: 90, 85, 95 vs SO 70, 75, 80. Pooled-variance t by hand:
    mo, s = np.array([90.0, 85.0, 95.0]), np.array([70.0, 75.0, 80.0])
    sp2 = (((mo - mo.mean()) ** 2).sum() + ((s - s.mean()) ** 2).sum()) / 4
    t = (mo.mean() - s.mean()) / math.sqrt(sp2 * (1 / 3 + 1 / 3))
    assert cmp[("max", "task")].t_statistic == pytest.approx(t)   # = 15 / sqrt(25 * 2/3) = 3.674
    assert cmp[("max", "task")].difference_percent == pytest.approx((90 - 75) / 75 * 100)
    assert cmp[("max", "task")].superior == "MO"                  # p = 0.021 < 0.05
    # Epsilon simplicity per run: 50, 55, 45 vs SO 30, 35, 25 -> MO simpler by (50-30)/30.
    assert cmp[("epsilon", "morphology")].mo_mean == pytest.approx(50.0)
    assert cmp[("epsilon", "morphology")].difference_percent == pytest.approx(200.0 / 3.0)
    out = tmp_path / "report"
    report = write_report(analysis, out)
    assert report.exists() and "Table 4" in report.read_text()
    for name in ("figure4_fronts.png", "figure5_simplicity.png", "figure6_points.png", "table4.md", "table4.csv"):
        assert (out / name).stat().st_size > 0, name
    assert (out / "figure4_fronts.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_reports_broken_run_directory(tmp_path, capsys):
    (tmp_path / "broken").mkdir()
    assert analyze_main([str(tmp_path / "broken"), "--out", str(tmp_path / "r")]) == 2
    assert "experiment.json missing" in capsys.readouterr().err
