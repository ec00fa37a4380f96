"""From run directories to the paper's comparison: fronts, selection points, tests, table.

Runs are grouped by (kind, environment): *SO* runs optimise the task alone, *MO* runs
also the morphology (or more objectives). For every group:

* SO: each run contributes its champion (best task performance) as a point
  (ft, C = morphological simplicity); "AVG SO" is their mean.
* MO: each run contributes its final first front (``front/*.json``); the fronts of all
  repetitions are merged by non-dominated sorting on (ft, C) (Figure 4).
* Selection points, per MO run front (paper section 5.1): **max** (best ft), **mean** (the
  front's mean on both objectives), **knee** (smallest Euclidean distance to the utopia
  point (1, 1) after normalising each objective to [0, 1] over the front) and **epsilon**
  (the simplest point whose ft is within 10 % of the front's max ft).
* Statistics: Shapiro-Wilk on every sample, then Student's two-sample t-test (scipy)
  comparing the SO champions with each selection point, for ft and for C (Table 4).

Which ft: with ``reevaluate = K`` > 0 every champion and front genome is re-run K times on
held-out seeds (``evolution.analysis.reevaluate``) and those scores replace the training scores
(then each run's front is re-filtered to its non-dominated points); with 0 the training
scores are used, which are biased upward (best-of-many noisy evaluations). C does not
depend on the seeds. ``Analysis.scores`` says which were used.
"""

from __future__ import annotations

import math
import warnings
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats as sps

from evolution.reproduction.pareto import non_dominated_fronts
from evolution.run.champion import ChampionError, champion_objectives, read_json
from evolution.run.stats import check_generations, read_stats

SELECTION_POINTS = ("max", "mean", "knee", "epsilon")
EPSILON = 0.10


@dataclass
class Run:
    """What the analysis needs from one run directory."""

    path: Path
    name: str
    environment: int
    multi_objective: bool
    records: list[dict[str, Any]]
    champion: tuple[float, float] | None        # (ft, C) of the best-ft genome
    front: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # (F, 2) rows (ft, C)
    champion_training: tuple[float, float] | None = None  # training (ft, C) when re-evaluated
    front_files: list[str] = field(default_factory=list)   # front/*.json behind each raw front row


def load_run(path: Path) -> Run:
    """Read ``experiment.json``, ``stats.jsonl``, ``champion.json`` and ``front/*.json``.

    Raises ``ValueError`` naming the file for anything the analysis cannot use: a missing or
    broken file, a record without the needed numbers, a champion (SO) or front (MO) that is
    missing or has a non-finite objective.
    """
    path = Path(path)
    if not path.is_dir():
        what = "is a file" if path.exists() else "does not exist"
        raise ValueError(f"{path}: {what}; allowed: a run directory written by gathering-evolve")
    if not (path / "experiment.json").exists():
        raise ValueError(f"{path}: not a run directory (experiment.json missing); allowed: a run directory "
                         "written by gathering-evolve (gathering-evolve --resume RUN_DIR rebuilds a deleted file)")
    experiment = read_json(path / "experiment.json", "experiment file")
    objectives = experiment.get("objectives", ["task"]) if isinstance(experiment, dict) else None
    environment = experiment.get("environment", {}) if isinstance(experiment, dict) else None
    if not isinstance(objectives, list) or not isinstance(environment, dict):
        raise ValueError(f"{path / 'experiment.json'}: needs 'objectives' (a list) and 'environment' (an object)")
    env = environment.get("environment") or 0
    if isinstance(env, bool) or not isinstance(env, int):
        raise ValueError(f"{path / 'experiment.json'}: environment.environment = {env!r}; allowed: 1, 2 or 3")
    multi = len(objectives) > 1
    records = read_stats(path / "stats.jsonl")
    if not records:
        raise ValueError(f"{path / 'stats.jsonl'}: no statistics (empty or missing)")
    for i, record in enumerate(records, 1):
        for key in ("generation", "task_best", "morphology_mean"):
            value = record.get(key)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{path / 'stats.jsonl'}: record {i} has {key} = {value!r}; allowed: a finite number")
    check_generations(path / "stats.jsonl", records)
    champion = None
    champ_file = path / "champion.json"
    if champ_file.exists():
        champion = _point(champ_file)
    elif not multi:
        raise ValueError(f"{champ_file}: missing; a single-objective run enters the analysis through its champion "
                         "(gathering-evolve --resume RUN_DIR rebuilds it, or leave the run out)")
    points, files = [], []
    for f in sorted((path / "front").glob("*.json")):
        points.append(_point(f))
        files.append(f.relative_to(path).as_posix())
    if multi and not points:
        raise ValueError(f"{path / 'front'}: no front genomes; a multi-objective run enters the analysis through its "
                         "final front (gathering-evolve --resume RUN_DIR rebuilds it, or leave the run out)")
    name = experiment.get("name", path.name)
    return Run(path, str(name), env, multi, records, champion,
               _non_dominated(np.array(points, dtype=float).reshape(-1, 2)), front_files=files)


def _non_dominated(points: np.ndarray) -> np.ndarray:
    return points[non_dominated_fronts(points)[0]] if len(points) else points


def apply_reevaluation(run: Run, scores: dict[str, dict[str, Any]]) -> Run:
    """Replace the training ft of the run's champion and front by held-out ``scores``."""
    if run.champion is not None and "champion.json" in scores:
        run.champion_training = run.champion
        run.champion = (float(scores["champion.json"]["task"]), run.champion[1])
    if run.front_files:
        points = [(float(scores[f]["task"]), float(scores[f]["morphology"])) for f in run.front_files]
        run.front = _non_dominated(np.array(points, dtype=float).reshape(-1, 2))
    return run


def _point(path: Path) -> tuple[float, float]:
    """(ft, C) of a champion or front file; needs finite 'task' and 'morphology' objectives."""
    objectives = champion_objectives(path, read_json(path, "champion file", ChampionError))
    if "morphology" not in objectives:
        raise ChampionError(f"{path}: objectives.morphology is missing; allowed: an object with 'task' and "
                            "'morphology'")
    return objectives["task"], objectives["morphology"]


def merge_fronts(fronts: list[np.ndarray]) -> np.ndarray:
    """Non-dominated union of several (F, 2) fronts, sorted by ft descending."""
    stacked = np.concatenate([f for f in fronts if len(f)] or [np.zeros((0, 2))])
    if not len(stacked):
        return stacked
    merged = np.unique(stacked[non_dominated_fronts(stacked)[0]], axis=0)
    return merged[np.argsort(-merged[:, 0], kind="stable")]


def selection_points(front: np.ndarray, epsilon: float = EPSILON) -> dict[str, tuple[float, float]]:
    """The four selection points (ft, C) of one front (rows (ft, C), both maximised)."""
    if not len(front):
        raise ValueError("empty front")
    ft, c = front[:, 0], front[:, 1]
    best = int(np.lexsort((-c, -ft))[0])  # max ft, ties -> simpler
    span = np.ptp(front, axis=0)
    norm = (front - front.min(axis=0)) / np.where(span > 0, span, 1.0)
    norm[:, span == 0] = 1.0  # a flat objective is at its best everywhere
    knee = int(np.lexsort((-ft, np.hypot(1.0 - norm[:, 0], 1.0 - norm[:, 1])))[0])
    ok = ft >= ft[best] - epsilon * abs(ft[best])
    candidates = np.flatnonzero(ok)
    eps = int(candidates[np.lexsort((-ft[candidates], -c[candidates]))[0]])
    return {
        "max": (float(ft[best]), float(c[best])),
        "mean": (float(ft.mean()), float(c.mean())),
        "knee": (float(ft[knee]), float(c[knee])),
        "epsilon": (float(ft[eps]), float(c[eps])),
    }


@dataclass
class Comparison:
    """SO champions vs one selection point of the MO fronts, for one objective."""

    environment: int
    point: str
    objective: str               # "task" or "morphology"
    so_mean: float
    mo_mean: float
    difference_percent: float    # (MO - SO) / |SO| * 100
    superior: str                # "SO", "MO" or "=" (no significant difference)
    t_statistic: float
    p_value: float
    shapiro_so_p: float
    shapiro_mo_p: float
    n_so: int
    n_mo: int


    @property
    def untested(self) -> str | None:
        """Why there is no t-test (None when there is one): too few runs, or no variation."""
        if self.n_so < 2 or self.n_mo < 2:
            return f"too few runs for a test (SO {self.n_so}, MO {self.n_mo}; a t-test needs 2 of each)"
        if math.isnan(self.p_value):
            return (f"no variation (every SO run {self.so_mean:.2f}, every MO run {self.mo_mean:.2f}): "
                    "no test")
        return None


def nothing_to_compare(analysis: Analysis) -> str | None:
    """One line when Table 4 has no cell (no environment with both SO and MO runs), else None."""
    if analysis.comparisons:
        return None

    def envs(multi: bool) -> str:
        found = sorted({r.environment for r in analysis.runs if r.multi_objective == multi})
        return "environment " + ", ".join(map(str, found)) if found else "none"

    return (f"nothing to compare: Table 4 needs SO and MO runs of the same environment "
            f"(SO runs: {envs(False)}; MO runs: {envs(True)})")


def _shapiro(sample: np.ndarray) -> float:
    if len(sample) < 3 or np.ptp(sample) == 0:
        return float("nan")
    return float(sps.shapiro(sample).pvalue)


def compare(so: np.ndarray, mo: np.ndarray, environment: int, point: str, objective: str,
            alpha: float = 0.05) -> Comparison:
    """Student's t-test (equal variances) of two samples, with Shapiro-Wilk p-values."""
    so, mo = np.asarray(so, float), np.asarray(mo, float)
    if len(so) >= 2 and len(mo) >= 2 and (np.ptp(so) > 0 or np.ptp(mo) > 0):
        result = sps.ttest_ind(mo, so, equal_var=True)
        t, p = float(result.statistic), float(result.pvalue)
    else:
        t, p = float("nan"), float("nan")
    so_mean, mo_mean = float(so.mean()), float(mo.mean())
    diff = (mo_mean - so_mean) / abs(so_mean) * 100.0 if so_mean else float("nan")
    superior = "=" if not (p < alpha) else ("MO" if mo_mean > so_mean else "SO")
    return Comparison(environment, point, objective, so_mean, mo_mean, diff, superior, t, p,
                      _shapiro(so), _shapiro(mo), len(so), len(mo))


@dataclass
class Analysis:
    scores: str                                               # which ft: training or held-out
    runs: list[Run]
    merged_fronts: dict[int, np.ndarray]
    so_points: dict[int, np.ndarray]                         # env -> (R, 2) champions
    run_points: dict[int, dict[str, np.ndarray]]             # env -> point -> (R, 2)
    merged_points: dict[int, dict[str, tuple[float, float]]]  # points of the merged front
    comparisons: list[Comparison]


def analyse(run_dirs: list[Path], reevaluate: int = 0, workers: int | None = None,
            backend: str = "process") -> Analysis:
    """Load and compare all runs (see the module docstring).

    Args:
        run_dirs: run directories (the same directory given twice is counted once, with a
            warning). reevaluate: K held-out trials per champion and front genome (0: use the
            training scores). workers, backend: evaluation backend.
    """
    if reevaluate < 0:
        raise ValueError(f"reevaluate={reevaluate}; allowed: >= 0 (0 = training scores)")
    unique: dict[Path, Path] = {}
    for p in run_dirs:
        key = Path(p).resolve()
        if key in unique:
            warnings.warn(f"{p}: the same run directory as {unique[key]}; counted once", stacklevel=2)
        else:
            unique[key] = Path(p)
    runs = [load_run(p) for p in unique.values()]
    if reevaluate:
        from evolution.analysis.reevaluate import reevaluate_run

        for run in runs:
            apply_reevaluation(run, reevaluate_run(run.path, reevaluate, workers, backend, len(run.records)))
        scores = (f"held-out: every champion and front genome re-evaluated on {reevaluate} trials with seeds "
                  "disjoint from training (evolution.analysis.reevaluate)")
    else:
        scores = "training: the scores recorded during evolution (best-of-many, biased upward)"
    so_by_env: dict[int, list[tuple[float, float]]] = defaultdict(list)
    mo_by_env: dict[int, list[np.ndarray]] = defaultdict(list)
    for run in runs:
        if run.multi_objective:
            if len(run.front):
                mo_by_env[run.environment].append(run.front)
        elif run.champion is not None:
            so_by_env[run.environment].append(run.champion)
    merged = {e: merge_fronts(f) for e, f in mo_by_env.items()}
    run_points = {
        e: {p: np.array([selection_points(f)[p] for f in fronts]) for p in SELECTION_POINTS}
        for e, fronts in mo_by_env.items()
    }
    merged_points = {e: selection_points(f) for e, f in merged.items() if len(f)}
    so_points = {e: np.array(v) for e, v in so_by_env.items()}
    comparisons = []
    for env in sorted(set(so_points) & set(run_points)):
        for point in SELECTION_POINTS:
            for j, objective in enumerate(("task", "morphology")):
                comparisons.append(compare(so_points[env][:, j], run_points[env][point][:, j], env, point, objective))
    return Analysis(scores, runs, merged, so_points, run_points, merged_points, comparisons)


def table4_rows(analysis: Analysis) -> list[dict[str, Any]]:
    """Flat rows of Table 4 (one per environment x point x objective)."""
    return [c.__dict__.copy() for c in analysis.comparisons]
