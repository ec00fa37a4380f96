"""Figures of one run: task performance and morphological simplicity over generations."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def plot_run(records: Sequence[dict[str, Any]], path: Path, title: str = "") -> Path:
    """Three panels: best/mean (+- std) ft; mean morphological simplicity and sensor count;
    species and the compatibility threshold that formed them."""
    gen = np.array([r["generation"] for r in records])
    fig, (ax1, ax2, ax3) = plt.subplots(1, 3, figsize=(14, 3.8), constrained_layout=True)
    mean = np.array([r["task_mean"] for r in records])
    std = np.array([r["task_std"] for r in records])
    ax1.plot(gen, [r["task_best"] for r in records], label="best ft", color="tab:red")
    ax1.plot(gen, mean, label="mean ft", color="tab:blue")
    ax1.fill_between(gen, mean - std, mean + std, color="tab:blue", alpha=0.2, label="mean +- std")
    ax1.set_xlabel("generation")
    ax1.set_ylabel("task performance ft (eq. 1)")
    ax1.legend(loc="upper left", fontsize=8)
    ax2.plot(gen, [r["morphology_mean"] for r in records], color="tab:green", label="mean simplicity C")
    ax2.set_xlabel("generation")
    ax2.set_ylabel("morphological simplicity C (eq. 2)")
    ax2.set_ylim(0, 100)
    twin = ax2.twinx()
    twin.plot(gen, [r["num_sensors_mean"] for r in records], color="tab:gray", ls="--", label="mean sensors")
    twin.set_ylabel("sensors per robot")
    twin.set_ylim(0, 10)
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
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
