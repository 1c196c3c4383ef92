"""Subcommands the render package adds to ``pwc`` (through the ``pwc.commands`` entry points)."""
