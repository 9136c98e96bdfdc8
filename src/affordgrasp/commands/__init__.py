"""Subcommands of the ``affordgrasp`` CLI, one module each (see ``affordgrasp.cli``)."""

from __future__ import annotations

import argparse


def add_verbose_argument(p: argparse.ArgumentParser) -> None:
    """``-v`` on a subcommand too (``affordgrasp generate ... -v``); the top level sets it.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    p.add_argument(
        "-v", "--verbose", action="store_true", default=argparse.SUPPRESS, help="log details"
    )
