"""``python -m pwc``: the ``pwc`` command."""

import sys

from pwc.cli import main

sys.exit(main())
