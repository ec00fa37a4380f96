"""Non-dominated sorting and crowding distance against brute-force references."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from evolution.reproduction.pareto import crowding_distance, non_dominated_fronts, nsga2_order


def brute_force_fronts(F: np.ndarray) -> list[set[int]]:
    """Peel fronts by checking every pair with plain Python loops."""
    remaining = set(range(len(F)))
    fronts = []
    while remaining:
        front = {i for i in remaining
                 if not any(all(F[j] >= F[i]) and any(F[j] > F[i]) for j in remaining if j != i)}
        fronts.append(front)
        remaining -= front
    return fronts


def brute_force_crowding(F: np.ndarray) -> np.ndarray:
    m, k = F.shape
    d = np.zeros(m)
    if m <= 2:
        return np.full(m, np.inf)
    for j in range(k):
        order = sorted(range(m), key=lambda i: (F[i, j], i))
        lo, hi = F[order[0], j], F[order[-1], j]
        d[order[0]] = d[order[-1]] = np.inf
        for pos in range(1, m - 1):
            if hi > lo:
                d[order[pos]] += (F[order[pos + 1], j] - F[order[pos - 1], j]) / (hi - lo)
    return d


# Few distinct values so that ties and duplicates are common.
objective_sets = st.integers(1, 3).flatmap(
    lambda k: arrays(np.float64, st.tuples(st.integers(0, 40), st.just(k)),
                     elements=st.sampled_from([0.0, 1.0, 2.0, 2.5, 7.0, 10.0]))
)


@settings(max_examples=200, deadline=None)
@given(objective_sets)
def test_fronts_match_brute_force(F):
    got = [set(f.tolist()) for f in non_dominated_fronts(F)]
    assert got == brute_force_fronts(F)


@settings(max_examples=200, deadline=None)
@given(objective_sets)
def test_crowding_matches_brute_force_on_each_front(F):
    for front in non_dominated_fronts(F):
        np.testing.assert_allclose(crowding_distance(F[front]), brute_force_crowding(F[front]))


def test_hand_made_example():
    # (task, simplicity): A dominates C; A, B are incomparable; D duplicates B.
    F = np.array([[90.0, 20.0],   # A
                  [50.0, 60.0],   # B
                  [80.0, 10.0],   # C (dominated by A)
                  [50.0, 60.0],   # D (= B)
                  [10.0, 5.0]])   # E (dominated by everybody)
    fronts = [f.tolist() for f in non_dominated_fronts(F)]
    assert fronts == [[0, 1, 3], [2], [4]]
    order, front_of, crowd = nsga2_order(F)
    assert front_of.tolist() == [0, 0, 1, 0, 2]
    # Front 0 = A, B, D: sorted by task A is the max, B/D at the minimum: boundaries get inf.
    # Ties in the sort keep index order, so B (index 1) is a boundary in task and D (3) in
    # simplicity... every member of a 3-point front with duplicates is a boundary in some axis.
    assert order.tolist()[-2:] == [2, 4]


def test_nan_is_rejected():
    with pytest.raises(ValueError, match="NaN"):
        non_dominated_fronts(np.array([[1.0, np.nan]]))


def test_agrees_with_pymoo_if_installed():
    pymoo_nds = pytest.importorskip("pymoo.util.nds.non_dominated_sorting")
    rng = np.random.default_rng(3)
    for _ in range(20):
        F = rng.integers(0, 6, size=(60, 2)).astype(float)
        ours = [sorted(f.tolist()) for f in non_dominated_fronts(F)]
        # pymoo minimises: negate.
        theirs = [sorted(np.asarray(f).tolist()) for f in pymoo_nds.NonDominatedSorting().do(-F)]
        assert ours == theirs
