"""Shared fixtures (a seeded rng and the repository root), and the skips of tests that
need an optional system library: ``@pytest.mark.mitsuba`` tests run Mitsuba 3's LLVM
back end and skip, with the reason, where no usable LLVM is installed
(:mod:`optional_libs`)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings
from optional_libs import use_mitsuba_llvm
from repo import ROOT

# Property tests: a developer's run draws new examples every time (and keeps a failing
# one in .hypothesis/ to replay); CI (.ci/run sets HYPOTHESIS_PROFILE=ci) draws the same
# examples on every run, so that the gate passes or fails with the change, not the draw.
# Neither times an example: hypothesis' default 200 ms deadline fails a test whose first
# example compiles a kernel or meets a busy machine ("Unreliable test timings"), and speed
# is measured in benchmarks/, never asserted in a test.
settings.register_profile("local", deadline=None)
settings.register_profile("ci", derandomize=True, database=None, print_blob=True,
                          deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "local"))

# Scripts that write expectations run only by hand, never at collection (issue 17).
collect_ignore = ["pwc/golden/regenerate.py"]

#: why Mitsuba's tests cannot run here (None: they can); set before mitsuba is imported
MITSUBA_SKIP = use_mitsuba_llvm()


def pytest_collection_modifyitems(config, items):
    if MITSUBA_SKIP is None:
        return
    skip = pytest.mark.skip(reason=MITSUBA_SKIP)
    for item in items:
        if item.get_closest_marker("mitsuba") is not None:
            item.add_marker(skip)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261121)


@pytest.fixture
def root() -> Path:
    return ROOT
