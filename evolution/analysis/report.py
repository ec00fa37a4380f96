"""Write the analysis as files: Table 4 (markdown + CSV), Figures 4-6 (PNG), report.md."""

from __future__ import annotations

import csv
import dataclasses
import math
from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from evolution.analysis.fronts import SELECTION_POINTS, Analysis, Comparison, nothing_to_compare  # noqa: E402
from evolution.guard import check_output_dir, writing  # noqa: E402

ENV_COLOURS = {1: "tab:blue", 2: "tab:orange", 3: "tab:red"}
POINT_MARKERS = {"max": "^", "mean": "s", "knee": "D", "epsilon": "P"}


def table4_cell(c: Comparison) -> str:
    """One cell of Table 4: the superior arm and the mean difference in % of SO with p, '=' and
    the same when not significant, or why there is no test."""
    if c.untested:
        return c.untested
    if math.isnan(c.difference_percent):  # SO mean 0: no percentage; the absolute difference
        change = f"MO − SO = {c.mo_mean - c.so_mean:+.2f}"
    else:
        change = f"{c.difference_percent:+.1f} %" if c.superior == "=" else f"{abs(c.difference_percent):.1f} %"
    if c.superior == "=":
        return f"= ({change}, p={c.p_value:.2g})"
    return f"{c.superior} {change} (p={c.p_value:.2g})"


def write_table4(analysis: Analysis, out: Path) -> tuple[Path, Path]:
    """table4.csv (one row per environment x point x objective, with the reason for a missing
    test in ``note``) and table4.md; with nothing to compare, the markdown is that one line."""
    fields = [f.name for f in dataclasses.fields(Comparison)] + ["note"]
    csv_path = out / "table4.csv"
    with writing(csv_path), open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        writer.writerows({**c.__dict__, "note": c.untested or ""} for c in analysis.comparisons)
    md_path = out / "table4.md"
    empty = nothing_to_compare(analysis)
    if empty:
        with writing(md_path):
            md_path.write_text(empty + "\n")
        return md_path, csv_path
    envs = sorted({c.environment for c in analysis.comparisons})
    lines = ["| SO vs | " + " | ".join(f"env {e} ft | env {e} C" for e in envs) + " |",
             "|---|" + "---|---|" * len(envs)]
    cell = {(c.environment, c.point, c.objective): c for c in analysis.comparisons}
    for point in SELECTION_POINTS:
        parts = [table4_cell(cell[(e, point, obj)]) if (e, point, obj) in cell else ""
                 for e in envs for obj in ("task", "morphology")]
        lines.append(f"| {point} | " + " | ".join(parts) + " |")
    with writing(md_path):
        md_path.write_text("\n".join(lines) + "\n")
    return md_path, csv_path


def point_means(analysis: Analysis) -> dict[int, dict[str, tuple[float, float, float, int]]]:
    """env -> point -> (mean ft, mean C, standard error of C, runs) over the MO runs' own
    selection points: the values of Figure 6 and the MO samples of Table 4."""
    table = {}
    for env, points in sorted(analysis.run_points.items()):
        table[env] = {}
        for point in SELECTION_POINTS:
            ft, c = points[point][:, 0], points[point][:, 1]
            se = float(c.std(ddof=1) / np.sqrt(len(c))) if len(c) > 1 else 0.0
            table[env][point] = (float(ft.mean()), float(c.mean()), se, len(c))
    return table


def figure4(analysis: Analysis, out: Path) -> Path:
    """Merged MO fronts (ft vs C) per environment with the AVG SO point and selection points."""
    fig, ax = plt.subplots(figsize=(6.5, 4.8), constrained_layout=True)
    for env, front in sorted(analysis.merged_fronts.items()):
        colour = ENV_COLOURS.get(env, "k")
        if len(front):
            order = np.argsort(front[:, 1])
            ax.plot(front[order, 1], front[order, 0], "o-", color=colour, ms=4, label=f"MO front, env {env}")
        for point, (ft, c) in analysis.merged_points.get(env, {}).items():
            ax.scatter([c], [ft], marker=POINT_MARKERS[point], s=60, facecolors="none", edgecolors=colour)
    for env, pts in sorted(analysis.so_points.items()):
        colour = ENV_COLOURS.get(env, "k")
        ax.scatter(pts[:, 1], pts[:, 0], marker="x", color=colour, alpha=0.5)
        ax.scatter([pts[:, 1].mean()], [pts[:, 0].mean()], marker="*", s=160, color=colour,
                   edgecolors="k", label=f"AVG SO, env {env}")
    for point, marker in POINT_MARKERS.items():
        ax.scatter([], [], marker=marker, facecolors="none", edgecolors="k", label=point)
    ax.set_xlabel("morphological simplicity C (eq. 2)")
    ax.set_ylabel("task performance ft (eq. 1)")
    ax.set_title(f"Figure 4: MO fronts vs SO champions ({analysis.scores.split(':')[0]} ft)")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="best")
    path = out / "figure4_fronts.png"
    return _save(fig, path)


def _save(fig: plt.Figure, path: Path) -> Path:
    """Write a figure (the error names the file) and free it."""
    with writing(path):
        fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def figure5(analysis: Analysis, out: Path) -> Path:
    """Mean morphological simplicity over generations, MO vs SO, per environment."""
    curves: dict[tuple[int, bool], list[np.ndarray]] = defaultdict(list)
    for run in analysis.runs:
        curves[(run.environment, run.multi_objective)].append(np.array([r["morphology_mean"] for r in run.records]))
    fig, ax = plt.subplots(figsize=(6.5, 4.2), constrained_layout=True)
    for (env, multi), series in sorted(curves.items()):
        length = min(len(s) for s in series)
        mean = np.mean([s[:length] for s in series], axis=0)
        ax.plot(np.arange(length), mean, color=ENV_COLOURS.get(env, "k"), ls="-" if multi else "--",
                alpha=1.0 if multi else 0.6, label=f"{'MO' if multi else 'SO'} env {env} (n={len(series)})")
    ax.set_xlabel("generation")
    ax.set_ylabel("mean morphological simplicity C")
    ax.set_title("Figure 5: simplicity over generations")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)
    path = out / "figure5_simplicity.png"
    return _save(fig, path)


def figure6(analysis: Analysis, out: Path) -> Path:
    """Mean simplicity (+- standard error over runs) of each selection point per environment."""
    envs = sorted(analysis.run_points)
    fig, ax = plt.subplots(figsize=(6.5, 4.2), constrained_layout=True)
    width = 0.8 / max(len(envs), 1)
    x = np.arange(len(SELECTION_POINTS))
    values = point_means(analysis)
    for i, env in enumerate(envs):
        means = [values[env][p][1] for p in SELECTION_POINTS]
        errs = [values[env][p][2] for p in SELECTION_POINTS]
        ax.bar(x + i * width, means, width, yerr=errs, capsize=3, color=ENV_COLOURS.get(env, "k"), label=f"env {env}")
    ax.set_xticks(x + width * (len(envs) - 1) / 2, SELECTION_POINTS)
    ax.set_ylabel("morphological simplicity C")
    ax.set_title(f"Figure 6: simplicity per selection point ({analysis.scores.split(':')[0]} ft)")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)
    path = out / "figure6_points.png"
    return _save(fig, path)


#: Every file ``write_report`` writes: the output folder may hold these (an earlier report,
#: replaced) and nothing else.
REPORT_FILES = ("table4.csv", "table4.md", "figure4_fronts.png", "figure5_simplicity.png", "figure6_points.png",
                "report.md")


def write_report(analysis: Analysis, out: Path) -> Path:
    """All tables and figures plus ``report.md`` tying them together.

    ``out`` must be missing, empty or an earlier report (``REPORT_FILES`` only): other files
    are never overwritten (``UsageError``).
    """
    out = Path(out)
    check_output_dir(out, REPORT_FILES)
    out.mkdir(parents=True, exist_ok=True)
    table_md, table_csv = write_table4(analysis, out)
    figs = [figure4(analysis, out), figure5(analysis, out), figure6(analysis, out)]
    lines = ["# Cost on morphological complexity: analysis report", "",
             f"Runs analysed: {len(analysis.runs)}", "",
             f"Task performance ft in the table, figures 4 and 6 and the run list: {analysis.scores}. "
             "Figure 5 shows population means recorded during training.", ""]
    lines.append("| run | kind | env | generations | champion ft | champion ft (training) | champion C | front size |")
    lines.append("|---|---|---|---|---|---|---|---|")
    for r in analysis.runs:
        ft, c = r.champion if r.champion else (float("nan"), float("nan"))
        trained = f"{r.champion_training[0]:.2f}" if r.champion_training else ""
        lines.append(f"| {r.path.name} | {'MO' if r.multi_objective else 'SO'} | {r.environment} | "
                     f"{len(r.records)} | {ft:.2f} | {trained} | {c:.1f} | "
                     f"{len(r.front) if r.multi_objective else ''} |")
    lines += ["", "## Selection points", "",
              "Two kinds, so one point has two values. Figure 6 and Table 4 use each MO run's own "
              "selection point, averaged over the runs (the paper's Figure 6: mean and standard error); "
              "Figure 4 marks the selection points of the merged front (the non-dominated points of all "
              "runs together), one front whose points can lie far from the runs' average.", "",
              "Per-run means (Figure 6, Table 4), ft / C ± standard error of C:", ""]
    for env, pts in point_means(analysis).items():
        cells = ", ".join(f"{p} = {ft:.2f} / {c:.1f} ± {se:.1f}" for p, (ft, c, se, _) in pts.items())
        runs = next(iter(pts.values()))[3]
        lines.append(f"* environment {env} ({runs} MO runs): {cells}")
    lines += ["", "Merged front (Figure 4), (ft, C):", ""]
    for env, pts in sorted(analysis.merged_points.items()):
        cells = ", ".join(f"{p} = ({v[0]:.2f}, {v[1]:.1f})" for p, v in pts.items())
        lines.append(f"* environment {env}: {cells}")
    for env, pts in sorted(analysis.so_points.items()):
        lines.append(f"* environment {env}, AVG SO = ({pts[:, 0].mean():.2f}, {pts[:, 1].mean():.1f}) over {len(pts)} runs")
    lines += ["", "## Table 4: SO vs each selection point", "",
              "Cells: the superior experiment and the mean difference in % of SO (Student's t-test, "
              "p < 0.05), or '=' with the difference and p when not significant. Shapiro-Wilk p-values "
              f"are in `{table_csv.name}`.", "", table_md.read_text(), "## Figures", ""]
    lines += [f"![{f.stem}]({f.name})" for f in figs]
    path = out / "report.md"
    with writing(path):
        path.write_text("\n".join(lines) + "\n")
    return path
