"""A fresh machine: the test run needs nothing outside the repository, and tests that need
an optional system library skip with the reason instead of failing or crashing."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys

import pytest
from optional_libs import ENV, llvm_major, mitsuba_llvm
from repo import ROOT, checkout_env


def test_mitsuba_llvm_is_chosen_or_refused_with_a_reason(tmp_path):
    for name, major in (("libLLVM-19.so", 19), ("libLLVM-15.so", 15), ("libLLVM.so.14", 14)):
        (tmp_path / name).write_bytes(b"")
        assert llvm_major(tmp_path / name) == major
    ok = str(tmp_path / "libLLVM-19.so")
    assert mitsuba_llvm({ENV: ok}) == (ok, None)
    assert mitsuba_llvm({}, default=tmp_path / "libLLVM-19.so") == (ok, None)
    lib, why = mitsuba_llvm({ENV: str(tmp_path / "libLLVM-15.so")})
    assert lib is None and "LLVM 15, which crashes Mitsuba's JIT" in why
    lib, why = mitsuba_llvm({}, default=tmp_path / "absent" / "libLLVM-19.so")
    assert lib is None and "is absent" in why and "apt-get install libllvm19" in why
    lib, why = mitsuba_llvm({ENV: "/nonexistent/libLLVM.so"})
    assert lib is None and "does not exist" in why


def _pytest(*args, env_extra=None, cwd=ROOT, timeout=600):
    env = checkout_env()
    env.pop(ENV, None)
    env.update(env_extra or {})
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider",
                           *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout)


@pytest.mark.parametrize("llvm", ["/nonexistent/libLLVM-19.so",
                                  "/usr/lib/x86_64-linux-gnu/libLLVM-15.so"])
def test_without_a_usable_llvm_mitsuba_tests_skip_and_pytest_survives(llvm):
    """The issue's machine: no libllvm19 (or DRJIT_LIBLLVM_PATH at the system's LLVM 15,
    which kills the process if loaded): every Mitsuba test skips, with the reason."""
    r = _pytest("tests/render/test_mitsuba.py", "tests/test_benchmarks.py",
                "-k", "mitsuba", env_extra={ENV: llvm})
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    skipped = re.search(r"(\d+) skipped", r.stdout)
    assert skipped and int(skipped.group(1)) >= 9 and " passed" not in r.stdout
    assert "Mitsuba" in r.stdout and ("does not exist" in r.stdout or "crashes" in r.stdout)


def test_no_test_reads_outside_the_repository(tmp_path):
    """A copy of the repository with no ../shared beside it: the tests that quote the
    Handbook skip with the reason; nothing fails."""
    copy = tmp_path / "alone" / "repo"
    for part in ("pwc", "mdl", "tests", "profiles", "pyproject.toml"):
        src = ROOT / part
        (shutil.copytree if src.is_dir() else shutil.copy)(src, copy / part)
    assert not (copy.parent / "shared").exists()
    r = _pytest("tests/pwc/test_profiles.py", "tests/mdl/test_pwc_listings.py", "-k",
                "handbook or book or listing", cwd=copy)
    assert r.returncode == 0, r.stdout[-3000:]
    assert "skipped" in r.stdout and "shared/seeds" in r.stdout and "failed" not in r.stdout
    for path in (ROOT / "tests").rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert not re.search(r"""["']/work/""", text), f"{path}: an absolute path"
