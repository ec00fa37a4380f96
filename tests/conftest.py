"""Shared test setup: pygame renders offscreen (SDL's dummy drivers)."""

import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import pytest  # noqa: E402

from gathering_env.config import KERNELS, WorldConfig  # noqa: E402


@pytest.fixture(params=KERNELS)
def both_kernels(request, monkeypatch):
    """Run a test once per kernel: ``WorldConfig.from_kwargs`` (and so ``parallel_env`` and
    every helper built on it) defaults to ``kernel=<param>`` for the test's duration."""
    original = WorldConfig.from_kwargs.__func__

    def from_kwargs(cls, environment=2, **overrides):
        overrides.setdefault("kernel", request.param)
        return original(cls, environment, **overrides)

    monkeypatch.setattr(WorldConfig, "from_kwargs", classmethod(from_kwargs))
    return request.param


# Every hypothesis test is reproducible: its examples derive from the test's own source
# (derandomize), or from a fixed ``@seed`` (the slow fuzz runs, which want other examples
# than the fast ones); no example database carries failures from one run into the next.
from hypothesis import settings  # noqa: E402

settings.register_profile("reproducible", derandomize=True, database=None, print_blob=True)
settings.load_profile("reproducible")


def pytest_collection_modifyitems(config, items):
    """Refuse a hypothesis test that would draw fresh random examples on each run."""
    for item in items:
        test = getattr(item, "obj", None)
        if not getattr(test, "is_hypothesis_test", False):
            continue
        chosen = getattr(test, "_hypothesis_internal_use_settings", settings.default)
        if not chosen.derandomize and getattr(test, "_hypothesis_internal_use_seed", None) is None:
            raise pytest.UsageError(f"{item.nodeid}: a hypothesis test must be derandomized or have a fixed @seed")
