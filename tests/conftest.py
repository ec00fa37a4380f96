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
