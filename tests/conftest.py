"""Shared fixtures: small seeded synthetic stereo pairs (no external data in tests)."""

import pytest

from npstereo.golden.synthetic import synthetic_pair


@pytest.fixture(scope="session")
def small_pair():
    """A 64 x 40 RGB pair made for D = 16, seed 1, with exact integer ground truth."""
    return synthetic_pair(width=64, height=40, disparities=16, seed=1)


@pytest.fixture(scope="session")
def default_pair():
    """The embedded default scene of ``make demo`` (160 x 120, D = 32, seed 0)."""
    return synthetic_pair()
