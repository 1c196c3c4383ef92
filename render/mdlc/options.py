"""The ``--mdl-path DIR`` option of the commands that read scenes or modules."""

from __future__ import annotations

import argparse

from mdl.loader import MDL_PATH_ENV

__all__ = ["add_mdl_path_option"]


def add_mdl_path_option(parser: argparse.ArgumentParser) -> None:
    """Add ``--mdl-path DIR`` (repeatable) to ``parser`` (``args.mdl_path``, a list)."""
    parser.add_argument(
        "--mdl-path", action="append", default=[], metavar="DIR",
        help="also look for MDL modules in DIR, after the scene's (or module's) own folder "
             f"and before ${MDL_PATH_ENV} and the workbench's library; repeatable")
