"""Paths of the repository that tests read, and how tests run its ``pwc`` command."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PROFILES = sorted((ROOT / "profiles").glob("*.pwc"))


def checkout_env(env: dict | None = None) -> dict:
    """``env`` (default: this process's) with this checkout first on ``PYTHONPATH``, so a
    subprocess runs this tree's packages from any current folder."""
    from render import checkout_pythonpath

    env = dict(os.environ if env is None else env)
    env["PYTHONPATH"] = checkout_pythonpath(env.get("PYTHONPATH", ""))
    return env


#: the ``pwc`` command of the tree under test (``pwc`` on PATH may be another tree's)
PWC = [sys.executable, "-m", "pwc"]


def run_pwc(*args, cwd=None, env=None, timeout=600) -> subprocess.CompletedProcess:
    """``python -m pwc ARGS`` of this checkout, text output captured."""
    return subprocess.run([sys.executable, "-m", "pwc", *map(str, args)], cwd=cwd,
                          env=checkout_env(env), capture_output=True, text=True,
                          timeout=timeout)


#: the Handbook's text, in the project's shared folder beside the checkout (not part of
#: the repository: tests that quote the book skip, with this reason, where it is absent)
HANDBOOK = ROOT.parent / "shared" / "seeds" / "000_da8979e79ecf3d68.txt"
HANDBOOK_MISSING = (f"the Handbook's text {HANDBOOK.relative_to(ROOT.parent)} is not beside "
                    "this checkout (../shared/seeds); these tests check quotations against it")


def needs_handbook(test):
    """Skip ``test``, with the reason, where the Handbook's text is absent."""
    import pytest

    return pytest.mark.skipif(not HANDBOOK.is_file(), reason=HANDBOOK_MISSING)(test)
