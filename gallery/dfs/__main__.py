"""``python -m gallery.dfs``: the distribution-function page's references (slow, explicit)."""

import sys

from gallery.dfs import main

sys.exit(main())
