"""Shared test configuration: one place for seeds and hypothesis settings."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

import modelgen

#: The one seed of every random test input.
SEED = 20090402

settings.register_profile(
    "sflm",
    derandomize=True,
    deadline=None,
    max_examples=40,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "sflm"))


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded NumPy generator."""
    return np.random.default_rng(SEED)


@pytest.fixture(scope="session")
def steel() -> modelgen.Model:
    """The steel strip of one's own (``tests/data/steel-strip.toml``), loaded once for the session."""
    from pathlib import Path

    return modelgen.load(str(Path(__file__).parent / "data" / "steel-strip.toml"))
