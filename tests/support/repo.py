"""Paths of the repository that tests read, and how tests run its commands."""

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PROFILES = sorted((ROOT / "profiles").glob("*.pwc"))


def tree_env(env: dict | None = None) -> dict:
    """Environment for a subprocess that must import this tree's packages (not whichever
    tree the editable install points to): ``ROOT`` first on ``PYTHONPATH``."""
    env = dict(os.environ if env is None else env)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [env.get("PYTHONPATH")])])
    return env


#: the ``pwc`` command of the tree under test (``pwc`` on PATH may be another tree's)
PWC = [sys.executable, "-m", "pwc"]
