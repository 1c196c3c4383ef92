"""Every benchmark still runs (tiny sizes): they are the record of measured trade-offs,
so they must not rot.  Figures are not asserted here; they live in README/docs."""

from __future__ import annotations

import subprocess
import sys

import pytest
from repo import ROOT, checkout_env

BENCHMARKS = {
    "pwc_speed.py": ["--points", "500", "--positions", "20000"],
    "bake_roundtrip.py": ["--sizes", "16", "--samples", "2000"],
    "dicing.py": ["--quick", "--size", "64", "--samples", "500", "--n-max", "64"],
    "render_vs_mitsuba.py": ["--quick"],
    "bump_vs_displacement.py": ["--quick"],
    "glossy_kernels.py": ["--quick"],
    "embree_calls.py": ["--quick"],
    "gallery_speed.py": ["--quick"],
    "cluster_speed.py": ["--quick"],
    "invisible_displacement.py": ["--quick"],
    "displaced_vs_mitsuba.py": ["--quick"],
    "light_selection.py": ["--quick"],
    "mdl_speed.py": ["--quick"],
    "hair.py": ["--quick"],
    "start_up.py": ["--quick"],
    "kernel_profile.py": ["--quick"],
    "simd_probe.py": ["--quick"],
}


#: benchmarks that need Mitsuba's LLVM back end (skipped with the reason without it)
NEEDS_MITSUBA = {"render_vs_mitsuba.py", "displaced_vs_mitsuba.py"}


@pytest.mark.slow
@pytest.mark.parametrize("name", [
    pytest.param(n, marks=[pytest.mark.mitsuba] if n in NEEDS_MITSUBA else [])
    for n in sorted(BENCHMARKS)])
def test_benchmark_runs(name):
    r = subprocess.run([sys.executable, str(ROOT / "benchmarks" / name), *BENCHMARKS[name]],
                       capture_output=True, text=True, timeout=600, cwd=ROOT, env=checkout_env())
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() and "Traceback" not in r.stderr


@pytest.mark.slow
@pytest.mark.mitsuba
def test_kernel_profile_of_the_peer_runs():
    """``kernel_profile.py --peer``: Mitsuba's scalar variant profiled (or, without perf,
    the reason why not)."""
    r = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "kernel_profile.py"),
                        "--quick", "--peer"], capture_output=True, text=True, timeout=600,
                       cwd=ROOT, env=checkout_env())
    assert r.returncode == 0, r.stderr
    assert "Mitsuba 3 scalar_rgb" in r.stdout or "nothing measured" in r.stdout, r.stdout


def test_every_benchmark_is_exercised():
    assert {p.name for p in (ROOT / "benchmarks").glob("*.py")} == set(BENCHMARKS)
