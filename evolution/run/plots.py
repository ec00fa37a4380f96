"""Figures of one run: task performance and morphological simplicity over generations."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

from evolution.guard import writing

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# Axis limits with a margin, so a curve at a bound (ten sensors, C = 100, ft = 0) stays visible
# instead of hiding on the frame; C and the sensor count share the right panel's grid lines.
C_LIMITS = (-3.0, 103.0)
SENSOR_LIMITS = (-0.3, 10.3)


def plot_run(records: Sequence[dict[str, Any]], path: Path, title: str = "") -> Path:
    """Write ``run_figure`` to ``path`` (PNG) and return the path."""
    fig = run_figure(records, title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with writing(path):
        fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def run_figure(records: Sequence[dict[str, Any]], title: str = "") -> plt.Figure:
    """Three panels: best/mean ft with a +- std band (cut at 0: ft is never negative); mean
    morphological simplicity and mean sensor count; species and the compatibility threshold
    that formed them."""
    gen = np.array([r["generation"] for r in records])
    fig, (ax1, ax2, ax3) = plt.subplots(1, 3, figsize=(14, 3.8), constrained_layout=True)
    mean = np.array([r["task_mean"] for r in records])
    std = np.array([r["task_std"] for r in records])
    ax1.plot(gen, [r["task_best"] for r in records], label="best ft", color="tab:red")
    ax1.plot(gen, mean, label="mean ft", color="tab:blue")
    ax1.fill_between(gen, np.maximum(mean - std, 0.0), mean + std, color="tab:blue", alpha=0.2,
                     label="mean ± std (cut at 0)")
    top = max(ax1.get_ylim()[1], 1.0)
    ax1.set_ylim(-0.03 * top, top)  # the band stops at 0; a curve at 0 stays off the frame
    ax1.set_xlabel("generation")
    ax1.set_ylabel("task performance ft (eq. 1)")
    ax1.legend(loc="upper left", fontsize=8)
    ax2.plot(gen, [r["morphology_mean"] for r in records], color="tab:green", label="mean simplicity C")
    ax2.set_xlabel("generation")
    ax2.set_ylabel("morphological simplicity C (eq. 2)")
    ax2.set_ylim(*C_LIMITS)
    twin = ax2.twinx()
    twin.plot(gen, [r["num_sensors_mean"] for r in records], color="tab:gray", ls="--", label="mean sensors")
    twin.set_ylabel("sensors per robot")
    twin.set_ylim(*SENSOR_LIMITS)
    lines = ax2.get_lines() + twin.get_lines()
    ax2.legend(lines, [ln.get_label() for ln in lines], loc="lower right", fontsize=8)
    ax3.plot(gen, [r.get("species", np.nan) for r in records], color="tab:purple", label="species")
    ax3.set_xlabel("generation")
    ax3.set_ylabel("species")
    ax3.set_ylim(0, None)
    thresholds = [r.get("threshold") for r in records]
    lines3 = ax3.get_lines()
    if any(t is not None for t in thresholds):
        twin3 = ax3.twinx()
        twin3.plot(gen, [np.nan if t is None else t for t in thresholds], color="tab:olive", ls="--",
                   label="compatibility threshold")
        twin3.set_ylabel("compatibility threshold")
        lines3 = lines3 + twin3.get_lines()
    ax3.legend(lines3, [ln.get_label() for ln in lines3], loc="upper right", fontsize=8)
    if title:
        fig.suptitle(title)
    return fig
