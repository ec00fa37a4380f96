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


# ---------------------------------------------------------------- small inputs, one value per point
def test_one_so_run_says_nothing_to_compare(tmp_path, capsys):
    run = make_run(tmp_path, "S2-0", 2, False, (10.0, 40.0))
    assert analyze_main([str(run), "--out", str(tmp_path / "rep"), "--reevaluate", "0"]) == 0
    printed = capsys.readouterr().out
    line = ("nothing to compare: Table 4 needs SO and MO runs of the same environment "
            "(SO runs: environment 2; MO runs: none)")
    assert line in printed.splitlines()
    assert (tmp_path / "rep" / "table4.md").read_text() == line + "\n"
    header = (tmp_path / "rep" / "table4.csv").read_text().splitlines()
    assert len(header) == 1 and header[0].startswith("environment,point,objective,") and header[0].endswith(",note")


def table_cells(out: Path) -> list[str]:
    rows = (out / "table4.md").read_text().splitlines()[2:]
    return [cell.strip() for row in rows for cell in row.strip("|").split("|")[1:]]


def test_too_few_runs_and_no_variation_say_so_instead_of_nan(tmp_path):
    one = analyse([make_run(tmp_path, "S2-0", 2, False, (10.0, 40.0)),
                   make_run(tmp_path, "M2-0", 2, True, (10.0, 60.0), [(10.0, 60.0)])])
    write_report(one, tmp_path / "one")
    assert set(table_cells(tmp_path / "one")) == {"too few runs for a test (SO 1, MO 1; a t-test needs 2 of each)"}
    # the docs' tiny example: two runs of each, every ft 0 and every C equal
    runs = [make_run(tmp_path, f"S1-{i}", 1, False, (0.0, 50.0)) for i in range(2)]
    runs += [make_run(tmp_path, f"M1-{i}", 1, True, (0.0, 50.0), [(0.0, 50.0)]) for i in range(2)]
    write_report(analyse(runs), tmp_path / "flat")
    cells = table_cells(tmp_path / "flat")
    assert set(cells) == {"no variation (every SO run 0.00, every MO run 0.00): no test",
                          "no variation (every SO run 50.00, every MO run 50.00): no test"}
    assert "nan" not in (tmp_path / "flat" / "report.md").read_text()
    # SO mean ft 0, MO varies: no percentage of 0, the absolute difference instead
    runs = [make_run(tmp_path, f"S3-{i}", 3, False, (0.0, 50.0)) for i in range(2)]
    runs += [make_run(tmp_path, f"M3-{i}", 3, True, (ft, 50.0), [(ft, 50.0)]) for i, ft in enumerate((1.0, 3.0))]
    write_report(analyse(runs), tmp_path / "zero")
    max_ft = table_cells(tmp_path / "zero")[0]
    assert max_ft.startswith("= (MO − SO = +2.00, p=") and "nan" not in max_ft


def test_report_lists_figure6_values_as_the_mean_of_the_runs_points(tmp_path):
    runs = [make_run(tmp_path, f"S2-{i}", 2, False, c) for i, c in enumerate([(70.0, 30.0), (75.0, 35.0)])]
    fronts = [FRONT, FRONT + [[-5.0, 5.0]]]
    runs += [make_run(tmp_path, f"M2-{i}", 2, True, tuple(f[0]), [tuple(r) for r in f]) for i, f in enumerate(fronts)]
    text = write_report(analyse(runs), tmp_path / "rep").read_text()
    # by hand: the max points of the two runs are (90, 20) and (85, 25): mean ft 87.5, C 22.5,
    # standard error of C = std([20, 25], ddof=1) / sqrt(2) = 3.5355 / 1.4142 = 2.5
    assert "max = 87.50 / 22.5 ± 2.5" in text
    # the merged front's max is the best single point, (90, 20): a second value for "max",
    # listed apart (Figure 4)
    assert "max = (90.00, 20.0)" in text


def test_stats_figure_keeps_curves_off_the_frame_and_the_band_above_zero():
    from evolution.run.plots import run_figure

    records = [{"generation": g, "task_best": 5.0 + g, "task_mean": 1.0, "task_std": 4.0,
                "morphology_mean": 100.0, "num_sensors_mean": 10.0} for g in range(4)]
    fig = run_figure(records)
    by_label = {ax.get_ylabel(): ax for ax in fig.axes}
    ax1, ax2 = by_label["task performance ft (eq. 1)"], by_label["morphological simplicity C (eq. 2)"]
    twin = by_label["sensors per robot"]
    assert twin.get_ylim()[1] > 10.0 and twin.get_ylim()[0] < 0.0     # ten sensors: not on the top border
    assert ax2.get_ylim()[1] > 100.0 and ax2.get_ylim()[0] < 0.0       # C = 100 likewise
    (band,) = ax1.collections
    assert band.get_paths()[0].vertices[:, 1].min() == 0.0             # mean 1 - std 4 is cut at 0
    assert ax1.get_ylim()[0] < 0.0                                     # and a curve at 0 stays visible
    # the sensor axis is the C axis scaled by 10, so both share the grid
    assert np.allclose(np.array(twin.get_ylim()) * 10, ax2.get_ylim())
