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
    env = dict(os.environ if env is None else env)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [env.get("PYTHONPATH")])])
    return env


def run_pwc(*args, cwd=None, env=None, timeout=600) -> subprocess.CompletedProcess:
    """``python -m pwc ARGS`` of this checkout, text output captured."""
    return subprocess.run([sys.executable, "-m", "pwc", *map(str, args)], cwd=cwd,
                          env=checkout_env(env), capture_output=True, text=True,
                          timeout=timeout)
