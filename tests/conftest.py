"""Shared pytest fixtures for swarmdeck's suites."""
from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator so that every random scene is reproducible."""
    return np.random.default_rng(12345)
