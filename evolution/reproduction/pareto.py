"""NSGA-II building blocks on objective matrices (all objectives maximised).

``non_dominated_fronts(F)`` splits the rows of an (M, k) objective matrix into Pareto
fronts (Deb et al.'s fast non-dominated sort, with the domination relation computed as one
(M, M) boolean matrix); ``crowding_distance(F)`` is NSGA-II's density estimate within one
front; ``nsga2_order(F)`` is the total order NSGA-II sorts by: front, then crowding
distance descending, then index (a deterministic tie-break).
"""

from __future__ import annotations

import numpy as np


def dominates_matrix(objectives: np.ndarray) -> np.ndarray:
    """(M, M) bool: ``D[i, j]`` is True when row i Pareto-dominates row j (maximisation)."""
    F = np.asarray(objectives, dtype=float)
    ge = (F[:, None, :] >= F[None, :, :]).all(axis=2)
    gt = (F[:, None, :] > F[None, :, :]).any(axis=2)
    return ge & gt


def non_dominated_fronts(objectives: np.ndarray) -> list[np.ndarray]:
    """Indices of the rows in each front, best front first (each sorted ascending).

    Rows with identical objective vectors share a front. Raises ``ValueError`` on NaN.
    """
    F = np.asarray(objectives, dtype=float)
    if F.ndim != 2:
        raise ValueError(f"objectives must be an (M, k) matrix; got shape {F.shape}")
    if np.isnan(F).any():
        raise ValueError("objectives contain NaN")
    if F.shape[0] == 0:
        return []
    dom = dominates_matrix(F)
    dominated_by = dom.sum(axis=0)  # how many rows dominate each row
    fronts = []
    current = np.flatnonzero(dominated_by == 0)
    while current.size:
        fronts.append(current)
        dominated_by = dominated_by - dom[current].sum(axis=0)
        dominated_by[current] = -1  # done
        current = np.flatnonzero(dominated_by == 0)
    return fronts


def crowding_distance(objectives: np.ndarray) -> np.ndarray:
    """NSGA-II crowding distance of each row of one front (boundary rows get inf).

    For each objective the rows are sorted; interior rows add the normalised gap between
    their neighbours. Objectives with zero spread contribute nothing.
    """
    F = np.asarray(objectives, dtype=float)
    m, k = F.shape
    distance = np.zeros(m)
    if m <= 2:
        distance[:] = np.inf
        return distance
    for j in range(k):
        order = np.argsort(F[:, j], kind="stable")
        values = F[order, j]
        spread = values[-1] - values[0]
        distance[order[0]] = distance[order[-1]] = np.inf
        if spread > 0:
            distance[order[1:-1]] += (values[2:] - values[:-2]) / spread
    return distance


def nsga2_order(objectives: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """NSGA-II's total order of the rows.

    Returns:
        (order, front_of_row, crowding_of_row): ``order`` lists row indices best first
        (lower front, then larger crowding distance, then lower index).
    """
    F = np.asarray(objectives, dtype=float)
    front_of = np.zeros(F.shape[0], dtype=np.int64)
    crowd = np.zeros(F.shape[0])
    for rank, idx in enumerate(non_dominated_fronts(F)):
        front_of[idx] = rank
        crowd[idx] = crowding_distance(F[idx])
    order = np.lexsort((np.arange(F.shape[0]), -crowd, front_of))
    return order, front_of, crowd
