"""Shared fixtures: a seeded rng and the repository root."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from repo import ROOT

# Scripts that write expectations run only by hand, never at collection (issue 17).
collect_ignore = ["pwc/golden/regenerate.py"]


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261121)


@pytest.fixture
def root() -> Path:
    return ROOT
