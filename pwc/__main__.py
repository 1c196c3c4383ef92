"""``python -m pwc``: the ``pwc`` command of the tree on ``sys.path``."""

import sys

from pwc.cli import entry

sys.exit(entry())
